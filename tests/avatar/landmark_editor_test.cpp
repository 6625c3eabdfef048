// The landmark editor (`retarget avatar landmarks`): a click picks the vertex the user sees under
// it, Save rewrites rig.yaml's landmarks and nothing else (atomically), and the HTTP API refuses
// bad requests with clear JSON errors.
#include "avatar/landmark_editor.h"

// clang-format off
#include <httplib.h>
// clang-format on
#include <fmt/format.h>
#include <sys/stat.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "avatar/avatar_init.h"
#include "geometry/face_model.h"
#include "raw_connection.h"
#include "scratch.h"
#include "synthetic/synthetic_faces.h"

namespace retarget {
namespace landmark_editor_test {

using nlohmann::json;
namespace fs = std::filesystem;

Rig synthetic_avatar(const std::string& name) {
  for (const SyntheticAvatar& a : synthetic_avatars())
    if (a.rig.name == name) return a.rig;
  FAIL("no synthetic avatar " << name);
  return {};
}

std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  return lines;
}

// The lines of a rig.yaml outside its top-level landmarks: section.
std::vector<std::string> outside_landmarks(const std::string& text) {
  std::vector<std::string> out;
  bool inside = false;
  for (const std::string& l : lines_of(text)) {
    if (!l.empty() && l[0] != ' ' && l[0] != '#') inside = l.rfind("landmarks:", 0) == 0;
    if (!inside) out.push_back(l);
  }
  return out;
}

TEST_CASE("a click picks the visible vertex under it; the background picks nothing", "[avatar][editor]") {
  const Rig fox = synthetic_avatar("fox");
  for (const RenderOptions::View view : {RenderOptions::View::front, RenderOptions::View::side}) {
    RenderOptions o;
    o.width = o.height = 400;
    o.view = view;
    o.margin = 0.08;
    const VertexPicker picker(fox.neutral, fox.neutral.vertices, o);
    const Image picture = render(fox.neutral, fox.neutral.vertices, picker.options());
    const uint8_t* corner = picture.pixel(0, 0);  // the background's colour

    int visible = 0, checked = 0;
    for (int v = 0; v < fox.neutral.vertex_count(); v += 7) {
      if (!picker.visible(v)) continue;
      ++visible;
      const Eigen::Vector2d at = picker.pixel(v);
      const int picked = picker.pick(at, 6);
      INFO("view " << view_name(view) << ", vertex " << v << " at " << at.transpose() << " picked " << picked);
      REQUIRE(picked >= 0);
      CHECK(picker.visible(picked));
      CHECK((picker.pixel(picked) - at).norm() <= 1.0);
      checked += picked == v ? 1 : 0;
    }
    // Most clicks return the very vertex (the others share its pixel).
    CHECK(visible > 100);
    CHECK(checked > 0.9 * visible);

    // The picture agrees: under the frontmost vertex there is the avatar, in the corner nothing.
    int front = 0;
    for (int v = 1; v < fox.neutral.vertex_count(); ++v)
      if (picker.pixel(v).x() > 0 && (picker.options().view == RenderOptions::View::front
                                          ? fox.neutral.vertices(v, 2) > fox.neutral.vertices(front, 2)
                                          : fox.neutral.vertices(v, 0) > fox.neutral.vertices(front, 0)))
        front = v;
    CHECK(picker.visible(front));
    const Eigen::Vector2d p = picker.pixel(front);
    const uint8_t* under = picture.pixel(static_cast<int>(p.x()), static_cast<int>(p.y()));
    CHECK(!(under[0] == corner[0] && under[1] == corner[1] && under[2] == corner[2]));
    CHECK(picker.pick({2.5, 2.5}, 8) == -1);
    CHECK(picker.pick({o.width - 2.5, o.height / 2.0}, 8) == -1);
    CHECK(picker.pick({-10, -10}, 8) == -1);
  }

  // Front view of a closed head (moppet): the back of the head is hidden behind the face, and a
  // click on its pixel finds the face.
  const Rig moppet = synthetic_avatar("moppet");
  RenderOptions o;
  o.width = o.height = 400;
  const VertexPicker picker(moppet.neutral, moppet.neutral.vertices, o);
  int back = 0;
  for (int v = 1; v < moppet.neutral.vertex_count(); ++v)
    if (moppet.neutral.vertices(v, 2) < moppet.neutral.vertices(back, 2)) back = v;
  CHECK_FALSE(picker.visible(back));
  const int picked = picker.pick(picker.pixel(back), 6);
  REQUIRE(picked >= 0);
  CHECK(picked != back);
  CHECK(picker.visible(picked));
  CHECK(moppet.neutral.vertices(picked, 2) > moppet.neutral.vertices(back, 2));
}

TEST_CASE("saving rewrites rig.yaml's landmarks only, atomically, and the rig still loads", "[avatar][editor]") {
  const Rig fox = synthetic_avatar("fox");
  const fs::path folder = test::process_scratch_dir("landmark_editor_save");
  write_avatar_folder(folder.string(), fox, propose_landmarks(fox));
  const fs::path yaml = folder / "rig.yaml";
  const std::string before = read_text(yaml);
  const Rig loaded = load_rig_folder(yaml.string());

  std::map<std::string, int> landmarks = loaded.landmarks;
  REQUIRE(landmarks.count("mouth_left"));
  REQUIRE(landmarks.count("nose_tip"));
  landmarks["mouth_left"] = landmarks["mouth_left"] + 1;
  landmarks.erase("nose_tip");
  landmarks["forehead"] = 17;

  // A second name for the old file: an atomic replace leaves it with the old text.
  const fs::path old_link = folder / "rig.yaml.before";
  fs::create_hard_link(yaml, old_link);
  write_rig_landmarks(yaml.string(), landmarks, {{"mouth_left", "hand-set"}});
  CHECK(read_text(old_link) == before);
  fs::remove(old_link);
  for (const auto& entry : fs::directory_iterator(folder))
    CHECK(entry.path().filename().string().find(".tmp") == std::string::npos);

  const std::string after = read_text(yaml);
  const Rig reloaded = load_rig_folder(yaml.string());
  CHECK(reloaded.landmarks == landmarks);
  CHECK(reloaded.eyes.left == loaded.eyes.left);
  CHECK(reloaded.eyes.right == loaded.eyes.right);
  CHECK(reloaded.controller_count() == loaded.controller_count());
  // Every other line as it was, comments included; unchanged landmarks keep avatar init's
  // comment, the moved one gets the one given.
  CHECK(outside_landmarks(after) == outside_landmarks(before));
  CHECK(after.find("# Written by `retarget avatar init`") != std::string::npos);
  CHECK(after.find(fmt::format("  mouth_left: {}  # hand-set\n", landmarks["mouth_left"])) != std::string::npos);
  CHECK(after.find(fmt::format("  mouth_right: {}  # confidence", landmarks["mouth_right"])) != std::string::npos);
  CHECK(after.find("  forehead: 17\n") != std::string::npos);
  CHECK(after.find("nose_tip") == std::string::npos);

  SECTION("a rig.yaml without landmarks gets the section before eyes:") {
    std::string without;
    bool inside = false;
    for (const std::string& l : lines_of(before)) {
      if (!l.empty() && l[0] != ' ' && l[0] != '#') inside = l.rfind("landmarks:", 0) == 0;
      if (!inside) without += l + "\n";
    }
    test::write_file(yaml, without);
    write_rig_landmarks(yaml.string(), {{"chin", 5}});
    const std::string added = read_text(yaml);
    CHECK(added.find("landmarks:\n  chin: 5\neyes:") != std::string::npos);
    CHECK(load_rig_folder(yaml.string()).landmarks == std::map<std::string, int>{{"chin", 5}});
  }

  SECTION("a hand-written rig.yaml keeps its comments and blank lines; a one-line section is replaced") {
    const std::string hand =
        "# my rig, by hand\n"
        "neutral: neutral.obj   # the rest pose\n"
        "targets: absolute\n"
        "controllers:\n"
        "  - {name: jawOpen, file: jawOpen.obj}\n"
        "landmarks: {chin: 1, nose_tip: 2}   # picked by hand\n"
        "\n"
        "# the eyes, from the eyeballs\n"
        "eyes: {left: [0, 1], right: [2, 3]}\n";
    test::write_file(yaml, hand);
    write_rig_landmarks(yaml.string(), {{"chin", 5}, {"mouth_left", 6}});
    CHECK(read_text(yaml) ==
          "# my rig, by hand\n"
          "neutral: neutral.obj   # the rest pose\n"
          "targets: absolute\n"
          "controllers:\n"
          "  - {name: jawOpen, file: jawOpen.obj}\n"
          "landmarks:\n"
          "  chin: 5\n"
          "  mouth_left: 6\n"
          "\n"
          "# the eyes, from the eyeballs\n"
          "eyes: {left: [0, 1], right: [2, 3]}\n");
    const Rig hand_rig = load_rig_folder(yaml.string());
    CHECK(hand_rig.landmarks == std::map<std::string, int>{{"chin", 5}, {"mouth_left", 6}});
    CHECK(hand_rig.eyes.right == std::vector<int>{2, 3});
  }

  SECTION("a rig.yaml written as one flow map is written anew and still loads") {
    test::write_file(yaml,
                     "{neutral: neutral.obj, targets: absolute, controllers: [{name: jawOpen, file: jawOpen.obj}], "
                     "landmarks: {chin: 1}}\n");
    write_rig_landmarks(yaml.string(), {{"chin", 2}, {"nose_tip", 3}});
    const Rig flow = load_rig_folder(yaml.string());
    CHECK(flow.landmarks == std::map<std::string, int>{{"chin", 2}, {"nose_tip", 3}});
    CHECK(flow.controller_count() == 1);
  }

  SECTION("a file that is not a YAML map is refused, naming it") {
    test::write_file(yaml, "- just\n- a list\n");
    const std::string message = test::error_of([&] { write_rig_landmarks(yaml.string(), {{"chin", 1}}); });
    CHECK(message.find("rig.yaml") != std::string::npos);
    CHECK(message.find("not a YAML map") != std::string::npos);
    CHECK(read_text(yaml) == "- just\n- a list\n");
  }
}

// The editor on the fox's `avatar init` folder beside the synthetic human, served from a thread.
struct RunningEditor {
  LandmarkEditorServer server;
  std::thread thread;
  RunningEditor(const std::string& rig, const std::string& human, LandmarkEditorOptions options)
      : server(rig, human, options) {
    server.bind();
    thread = std::thread([this] { server.run(); });
  }
  ~RunningEditor() {
    server.stop();
    thread.join();
  }
  httplib::Client client() const {
    httplib::Client c("127.0.0.1", server.port());
    c.set_read_timeout(60, 0);
    return c;
  }
  httplib::Headers auth() const { return {{"Authorization", "Bearer " + server.token()}}; }
};

TEST_CASE("the editor's API: places by click, undoes, saves, and refuses bad requests", "[avatar][editor]") {
  const fs::path root = test::process_scratch_dir("landmark_editor_api");
  const Rig fox = synthetic_avatar("fox");
  write_avatar_folder((root / "fox").string(), fox, propose_landmarks(fox));
  write_face_model((root / "human").string(), synthetic_human());
  LandmarkEditorOptions options;
  options.view_size = 400;
  RunningEditor editor((root / "fox").string(), (root / "human" / "face_model.yaml").string(), options);
  httplib::Client c = editor.client();

  const auto post = [&](const std::string& path, const json& body, int expected) {
    auto r = c.Post(path.c_str(), editor.auth(), body.dump(), "application/json");
    REQUIRE(r);
    INFO(path << " " << body.dump() << " -> " << r->status << " " << r->body);
    CHECK(r->status == expected);
    return json::parse(r->body);
  };

  // The page is open to anyone on this machine; the API needs the token.
  auto page = c.Get("/");
  REQUIRE(page);
  CHECK(page->status == 200);
  CHECK(page->body.find("<html") != std::string::npos);
  auto r = c.Get("/api/state");
  REQUIRE(r);
  CHECK(r->status == 401);
  CHECK(json::parse(r->body).at("error").get<std::string>().find("token") != std::string::npos);
  r = c.Get("/api/state", {{"Authorization", "Bearer not-the-token"}});
  REQUIRE(r);
  CHECK(r->status == 403);
  r = c.Get("/img/avatar/front.png", editor.auth());
  REQUIRE(r);
  CHECK(r->status == 200);
  CHECK(r->body.substr(1, 3) == "PNG");

  r = c.Get("/api/state", editor.auth());
  REQUIRE(r);
  REQUIRE(r->status == 200);
  const json state = json::parse(r->body);
  std::map<std::string, json> by_name;
  for (const json& l : state.at("landmarks")) by_name[l.at("name").get<std::string>()] = l;
  REQUIRE(by_name.at("mouth_left").at("avatar").at("origin") == "proposed");
  CHECK(by_name.at("mouth_left").at("avatar").at("confidence").get<double>() > 0.5);
  CHECK(by_name.at("forehead").at("avatar").is_null());  // the human has it, the fox not yet
  CHECK(!by_name.at("forehead").at("human").is_null());
  CHECK(state.at("unsaved") == false);

  // Bad requests.
  r = c.Post("/api/place", editor.auth(), R"({"name": "mouth_left"})", "text/plain");
  REQUIRE(r);
  CHECK(r->status == 415);
  r = c.Post("/api/place", editor.auth(), "{not json", "application/json");
  REQUIRE(r);
  CHECK(r->status == 400);
  CHECK(json::parse(r->body).at("error").get<std::string>().find("not valid JSON") != std::string::npos);
  CHECK(post("/api/place", {{"name", "mouth_left"}, {"view", "front"}, {"x", 100}}, 400)
            .at("error")
            .get<std::string>()
            .find("'y'") != std::string::npos);
  CHECK(post("/api/place", {{"name", "mouth_left"}, {"view", "top"}, {"x", 1}, {"y", 1}}, 400)
            .at("error")
            .get<std::string>()
            .find("view") != std::string::npos);
  CHECK(post("/api/place", {{"name", "tail_tip"}, {"view", "front"}, {"x", 200}, {"y", 200}}, 404)
            .at("error")
            .get<std::string>()
            .find("tail_tip") != std::string::npos);
  CHECK(post("/api/place", {{"name", "mouth_left"}, {"view", "front"}, {"x", 2}, {"y", 2}}, 422)
            .at("error")
            .get<std::string>()
            .find("beside the avatar's head") != std::string::npos);
  CHECK(post("/api/remove", {{"name", "forehead"}}, 404).at("error").get<std::string>().find("forehead") !=
        std::string::npos);
  CHECK(post("/api/undo", json::object(), 409).at("error") == "nothing to undo");

  // mouth_left clicked onto the nose tip's pixel takes the nose tip's vertex (or one within a
  // pixel of it).
  const json nose = by_name.at("nose_tip").at("avatar");
  const int old_mouth = by_name.at("mouth_left").at("avatar").at("vertex");
  json placed = post("/api/place",
                     {{"name", "mouth_left"},
                      {"view", "front"},
                      {"x", nose.at("pixels").at("front")[0]},
                      {"y", nose.at("pixels").at("front")[1]}},
                     200);
  const int picked = placed.at("picked");
  CHECK(picked != old_mouth);
  json moved;
  for (const json& l : placed.at("landmarks"))
    if (l.at("name") == "mouth_left") moved = l.at("avatar");
  CHECK(moved.at("vertex") == picked);
  CHECK(moved.at("origin") == "hand-set");
  CHECK(std::hypot(moved.at("pixels").at("front")[0].get<double>() - nose.at("pixels").at("front")[0].get<double>(),
                   moved.at("pixels").at("front")[1].get<double>() - nose.at("pixels").at("front")[1].get<double>()) <=
        1.0);
  CHECK(placed.at("unsaved") == true);

  // Undo brings it back; placing again and adding the forehead, then saving, writes rig.yaml.
  json undone = post("/api/undo", json::object(), 200);
  CHECK(undone.at("unsaved") == false);
  post("/api/place",
       {{"name", "mouth_left"},
        {"view", "front"},
        {"x", nose.at("pixels").at("front")[0]},
        {"y", nose.at("pixels").at("front")[1]}},
       200);
  post("/api/place", {{"name", "forehead"}, {"view", "side"}, {"x", 200}, {"y", 200}}, 200);
  post("/api/remove", {{"name", "chin"}}, 200);
  const json saved = post("/api/save", json::object(), 200);
  CHECK(saved.at("unsaved") == false);
  const Rig reloaded = load_rig_folder((root / "fox").string());
  CHECK(reloaded.landmarks.at("mouth_left") == picked);
  CHECK(reloaded.landmarks.count("forehead") == 1);
  CHECK(reloaded.landmarks.count("chin") == 0);
  CHECK(reloaded.landmarks.at("mouth_right") == by_name.at("mouth_right").at("avatar").at("vertex").get<int>());
  CHECK(reloaded.controller_count() == fox.controller_count());

  // A later session on the saved folder: what was set by hand still says so, the rest is proposed.
  RunningEditor again((root / "fox").string(), (root / "human" / "face_model.yaml").string(), options);
  httplib::Client c2 = again.client();
  auto r2 = c2.Get("/api/state", again.auth());
  REQUIRE(r2);
  REQUIRE(r2->status == 200);
  const json later = json::parse(r2->body);
  std::map<std::string, std::string> origins;
  for (const json& l : later.at("landmarks"))
    if (!l.at("avatar").is_null()) origins[l.at("name")] = l.at("avatar").at("origin");
  CHECK(origins.at("mouth_left") == "hand-set");
  CHECK(origins.at("forehead") == "hand-set");
  CHECK(origins.at("mouth_right") == "proposed");
  CHECK(origins.count("chin") == 0);
}

TEST_CASE("the editor's page: 40 never-finished requests from one client leave it to the others",
          "[avatar][editor][limits]") {
  const fs::path root = test::process_scratch_dir("landmark_editor_slow");
  const Rig fox = synthetic_avatar("fox");
  write_avatar_folder((root / "fox").string(), fox, propose_landmarks(fox));
  write_face_model((root / "human").string(), synthetic_human());
  LandmarkEditorOptions options;  // 16 threads: one client is served on 8 at most
  options.view_size = 128;
  options.connections.request_seconds = 120;
  RunningEditor editor((root / "fox").string(), (root / "human" / "face_model.yaml").string(), options);
  test::check_slow_clients_are_contained(editor.server.port(), 40, 8);
}

TEST_CASE("the editor refuses what is not a rig folder, saying what to give", "[avatar][editor]") {
  const fs::path root = test::process_scratch_dir("landmark_editor_refusals");
  test::write_file(root, "avatar.glb", "glTF");
  const std::string human = (root / "human" / "face_model.yaml").string();
  std::string message =
      test::error_of([&] { LandmarkEditorServer((root / "avatar.glb").string(), human, LandmarkEditorOptions{}); });
  CHECK(message.find("avatar.glb") != std::string::npos);
  CHECK(message.find("cannot hold landmarks") != std::string::npos);
  message = test::error_of([&] { LandmarkEditorServer(root.string(), human, LandmarkEditorOptions{}); });
  CHECK(message.find("rig.yaml") != std::string::npos);
  CHECK(message.find("does not exist") != std::string::npos);
}

TEST_CASE("the editor's options are checked, naming the field", "[avatar][editor]") {
  LandmarkEditorOptions o;
  o.view_size = 50;
  CHECK(test::error_of([&] { o.validate(); }).find("landmarks.view_size") != std::string::npos);
  o = {};
  o.token = "short";
  CHECK(test::error_of([&] { o.validate(); }).find("landmarks.token") != std::string::npos);
  o = {};
  o.pick_radius_px = 0;
  CHECK(test::error_of([&] { o.validate(); }).find("landmarks.pick_radius_px") != std::string::npos);
}

}  // namespace landmark_editor_test
}  // namespace retarget
