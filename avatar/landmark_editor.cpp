#include "avatar/landmark_editor.h"

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <regex>
#include <set>
#include <sstream>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/log.h"
#include "geometry/face_model.h"
#include "geometry/rig.h"
#include "web/asset_serving.h"
#include "web/guarded_http_server.h"
#include "web/http_json.h"
#include "web/token.h"
#include "web/web_assets.h"

namespace retarget {

// The editor's pages (avatar/web/), embedded by cmake/embed_web_assets.cmake under these names
// (avatar/CMakeLists.txt renames the annotation tool's two functions for this copy).
const std::vector<WebAsset>& landmark_editor_web_assets();
const WebAsset* find_landmark_editor_web_asset(std::string_view name);

namespace landmark_editor_detail {

constexpr double kInf = std::numeric_limits<double>::infinity();
// The comment a saved landmark set by hand gets in rig.yaml (and is known by when loaded again).
constexpr const char* kHandSet = "hand-set in retarget avatar landmarks";

// Twice the signed area of (a, b, p): > 0 when p lies to the left of a -> b.
double edge(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& p) {
  return (b.x() - a.x()) * (p.y() - a.y()) - (b.y() - a.y()) * (p.x() - a.x());
}

}  // namespace landmark_editor_detail

// --- VertexPicker ------------------------------------------------------------------------------

VertexPicker::VertexPicker(const Mesh& topology, const Positions& vertices, RenderOptions options)
    : triangles_(topology.triangles), options_(std::move(options)) {
  if (vertices.rows() != topology.vertex_count() || vertices.rows() == 0)
    throw Error(topology.source.empty() ? "picker" : topology.source,
                fmt::format("{} positions given for a mesh of {} vertices", vertices.rows(), topology.vertex_count()));
  if (!options_.frame) options_.frame = frame_box(vertices);
  options_.validate();
  const Eigen::Index n = vertices.rows();
  projected_.resize(n, 3);
  for (Eigen::Index i = 0; i < n; ++i)
    projected_.row(i) = project_to_image(vertices, options_, vertices.row(i).transpose()).transpose();

  tiles_x_ = (options_.width + kTile - 1) / kTile;
  tiles_y_ = (options_.height + kTile - 1) / kTile;
  tiles_.assign(static_cast<size_t>(tiles_x_) * tiles_y_, {});
  for (Eigen::Index t = 0; t < triangles_.rows(); ++t) {
    Eigen::Vector2d low = Eigen::Vector2d::Constant(landmark_editor_detail::kInf), high = -low;
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector2d p = projected_.row(triangles_(t, k)).head<2>().transpose();
      low = low.cwiseMin(p), high = high.cwiseMax(p);
    }
    const int tx0 = std::max(0, static_cast<int>(std::floor(low.x() / kTile)));
    const int ty0 = std::max(0, static_cast<int>(std::floor(low.y() / kTile)));
    const int tx1 = std::min(tiles_x_ - 1, static_cast<int>(std::floor(high.x() / kTile)));
    const int ty1 = std::min(tiles_y_ - 1, static_cast<int>(std::floor(high.y() / kTile)));
    for (int ty = ty0; ty <= ty1; ++ty)
      for (int tx = tx0; tx <= tx1; ++tx)
        tiles_[static_cast<size_t>(ty) * tiles_x_ + tx].push_back(static_cast<int>(t));
  }

  // A vertex is seen when no surface lies in front of it: its depth is the frontmost at its own
  // pixel, up to a thousandth of the head's size (rounding, and its own triangles meeting there).
  const double tolerance = 1e-3 * options_.frame->diagonal().norm();
  visible_.assign(static_cast<size_t>(n), false);
  for (Eigen::Index i = 0; i < n; ++i) {
    const double front = surface_depth(pixel(static_cast<int>(i)), nullptr);
    visible_[static_cast<size_t>(i)] = projected_(i, 2) >= front - tolerance;
  }
}

double VertexPicker::surface_depth(const Eigen::Vector2d& p, int* triangle) const {
  using landmark_editor_detail::edge;
  if (triangle) *triangle = -1;
  if (!(p.x() >= 0 && p.y() >= 0 && p.x() <= options_.width && p.y() <= options_.height))
    return -landmark_editor_detail::kInf;
  const int tx = std::min(tiles_x_ - 1, static_cast<int>(p.x() / kTile));
  const int ty = std::min(tiles_y_ - 1, static_cast<int>(p.y() / kTile));
  double best = -landmark_editor_detail::kInf;
  for (int t : tiles_[static_cast<size_t>(ty) * tiles_x_ + tx]) {
    const int a = triangles_(t, 0), b = triangles_(t, 1), c = triangles_(t, 2);
    const Eigen::Vector2d A = projected_.row(a).head<2>().transpose(), B = projected_.row(b).head<2>().transpose(),
                          C = projected_.row(c).head<2>().transpose();
    const double area = edge(A, B, C);
    if (std::abs(area) < 1e-12) continue;  // seen edge-on: covers nothing
    // Barycentric weights; a point on an edge or corner counts as inside (a vertex's own pixel).
    const double wa = edge(B, C, p) / area, wb = edge(C, A, p) / area, wc = edge(A, B, p) / area;
    const double eps = -1e-9;
    if (wa < eps || wb < eps || wc < eps) continue;
    const double depth = wa * projected_(a, 2) + wb * projected_(b, 2) + wc * projected_(c, 2);
    if (depth > best) {
      best = depth;
      if (triangle) *triangle = t;
    }
  }
  return best;
}

int VertexPicker::pick(const Eigen::Vector2d& click, double radius_px) const {
  int front = -1;
  surface_depth(click, &front);
  if (front < 0) return -1;
  int best = -1;
  double best_distance = radius_px;
  for (Eigen::Index i = 0; i < projected_.rows(); ++i) {
    if (!visible_[static_cast<size_t>(i)]) continue;
    const double d = (projected_.row(i).head<2>().transpose() - click).norm();
    if (d <= best_distance) best = static_cast<int>(i), best_distance = d;
  }
  if (best >= 0) return best;
  // A large triangle: the nearest of its corners.
  best_distance = landmark_editor_detail::kInf;
  for (int k = 0; k < 3; ++k) {
    const int v = triangles_(front, k);
    const double d = (projected_.row(v).head<2>().transpose() - click).norm();
    if (d < best_distance) best = v, best_distance = d;
  }
  return best;
}

// --- write_rig_landmarks -----------------------------------------------------------------------

namespace landmark_editor_detail {

// A YAML key: plain when it can be, else double-quoted with JSON's escapes (valid YAML).
std::string yaml_key(const std::string& name) {
  static const std::regex plain("^[A-Za-z_][A-Za-z0-9_.-]*$");
  return std::regex_match(name, plain) ? name : nlohmann::json(name).dump();
}

std::string one_line(std::string text) {
  std::replace(text.begin(), text.end(), '\n', ' ');
  std::replace(text.begin(), text.end(), '\r', ' ');
  return text;
}

std::string landmarks_block(const std::map<std::string, int>& landmarks,
                            const std::map<std::string, std::string>& comments) {
  if (landmarks.empty()) return "landmarks: {}\n";
  std::string out = "landmarks:\n";
  for (const auto& [name, vertex] : landmarks) {
    out += fmt::format("  {}: {}", yaml_key(name), vertex);
    const auto c = comments.find(name);
    if (c != comments.end() && !c->second.empty()) out += "  # " + one_line(c->second);
    out += "\n";
  }
  return out;
}

std::vector<std::string> split_lines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

// Every top-level key but `landmarks`, each as YAML text, to compare two versions of a file.
std::map<std::string, std::string> other_keys(const YAML::Node& root) {
  std::map<std::string, std::string> out;
  for (const auto& entry : root) {
    const std::string key = entry.first.as<std::string>();
    if (key != "landmarks") out[key] = YAML::Dump(entry.second);
  }
  return out;
}

bool has_landmarks(const YAML::Node& root, const std::map<std::string, int>& landmarks) {
  const YAML::Node node = root["landmarks"];
  if (!node || !node.IsMap() || node.size() != landmarks.size()) return false;
  for (const auto& [name, vertex] : landmarks)
    if (!node[name] || node[name].as<int>() != vertex) return false;
  return true;
}

// The new text with only the landmarks section replaced, or nullopt when the file's layout does
// not allow that (a flow map at the top).
std::optional<std::string> replace_landmarks_section(const std::string& text, const YAML::Node& root,
                                                     const std::map<std::string, int>& landmarks,
                                                     std::map<std::string, std::string> comments) {
  std::vector<int> key_lines;  // the line of every top-level key, in file order
  int start = -1, eyes = -1;
  for (const auto& entry : root) {
    const YAML::Mark mark = entry.first.Mark();
    if (mark.column != 0 || mark.line < 0) return std::nullopt;
    key_lines.push_back(mark.line);
    const std::string key = entry.first.as<std::string>();
    if (key == "landmarks") start = mark.line;
    if (key == "eyes") eyes = mark.line;
  }
  std::sort(key_lines.begin(), key_lines.end());
  std::vector<std::string> lines = split_lines(text);
  std::vector<std::string> out;
  if (start < 0) {
    const int at = eyes >= 0 ? eyes : static_cast<int>(lines.size());
    out.assign(lines.begin(), lines.begin() + at);
    for (const std::string& l : split_lines(landmarks_block(landmarks, comments))) out.push_back(l);
    out.insert(out.end(), lines.begin() + at, lines.end());
  } else {
    int end = static_cast<int>(lines.size());
    for (int line : key_lines)
      if (line > start) {
        end = line;
        break;
      }
    // Blank lines and comments at the start of a line just before the next key belong to it.
    while (end - 1 > start) {
      const std::string& l = lines[static_cast<size_t>(end - 1)];
      const bool blank = l.find_first_not_of(" \t\r") == std::string::npos;
      if (!blank && l[0] != '#') break;
      --end;
    }
    // Keep the comment of each landmark whose vertex did not change (avatar init's confidence).
    static const std::regex entry(R"(^\s+([A-Za-z0-9_.-]+)\s*:\s*(-?\d+)\s*(#\s?(.*))?\r?$)");
    for (int i = start + 1; i < end; ++i) {
      std::smatch m;
      const std::string& l = lines[static_cast<size_t>(i)];
      if (!std::regex_match(l, m, entry) || !m[4].matched) continue;
      const auto now = landmarks.find(m[1].str());
      if (now != landmarks.end() && std::to_string(now->second) == m[2].str() && !comments.count(m[1].str()))
        comments[m[1].str()] = m[4].str();
    }
    out.assign(lines.begin(), lines.begin() + start);
    for (const std::string& l : split_lines(landmarks_block(landmarks, comments))) out.push_back(l);
    out.insert(out.end(), lines.begin() + end, lines.end());
  }
  std::string result;
  for (const std::string& l : out) result += l + "\n";
  return result;
}

// The comment on each line of a block `landmarks:` section ("name: vertex  # comment"), by name.
std::map<std::string, std::string> landmark_line_comments(const std::string& text) {
  static const std::regex entry(R"(^\s+([A-Za-z0-9_.-]+)\s*:\s*(-?\d+)\s*#\s?(.*?)\r?$)");
  std::map<std::string, std::string> out;
  bool inside = false;
  for (const std::string& l : split_lines(text)) {
    if (!l.empty() && l[0] != ' ' && l[0] != '#' && l[0] != '\r') inside = l.rfind("landmarks:", 0) == 0;
    std::smatch m;
    if (inside && std::regex_match(l, m, entry)) out[m[1].str()] = m[3].str();
  }
  return out;
}

}  // namespace landmark_editor_detail

void write_rig_landmarks(const std::string& rig_yaml, const std::map<std::string, int>& landmarks,
                         const std::map<std::string, std::string>& comments) {
  namespace detail = landmark_editor_detail;
  std::ifstream in(rig_yaml, std::ios::binary);
  if (!in) throw Error(rig_yaml, "cannot be read");
  std::stringstream buffer;
  buffer << in.rdbuf();
  const std::string text = buffer.str();
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw Error(fmt::format("{}:{}", rig_yaml, e.mark.line + 1), "is not valid YAML: " + e.msg);
  }
  if (!root.IsMap()) throw Error(rig_yaml, "is not a YAML map (a rig.yaml starts with keys such as neutral:)");
  const std::map<std::string, std::string> before = detail::other_keys(root);

  std::optional<std::string> updated = detail::replace_landmarks_section(text, root, landmarks, comments);
  if (updated) {
    // The new text must read back as the old one with the new landmarks, else write it anew.
    try {
      const YAML::Node check = YAML::Load(*updated);
      if (!check.IsMap() || detail::other_keys(check) != before || !detail::has_landmarks(check, landmarks))
        updated.reset();
    } catch (const YAML::Exception&) {
      updated.reset();
    }
  }
  if (!updated) {
    log::warn("{}: its layout is not one block map; written anew from its content, without its comments", rig_yaml);
    YAML::Node fresh = YAML::Clone(root);
    YAML::Node section(YAML::NodeType::Map);
    for (const auto& [name, vertex] : landmarks) section[name] = vertex;
    fresh["landmarks"] = section;
    YAML::Emitter e;
    e << fresh;
    updated = std::string(e.c_str()) + "\n";
  }
  write_file_atomically(rig_yaml, [&](std::ostream& out) { out << *updated; });
}

// --- options -----------------------------------------------------------------------------------

void LandmarkEditorOptions::validate(const std::string& key_path) const {
  if (host.empty()) throw Error(key_path + ".host", "must not be empty");
  if (port < 0 || port > 65535) throw Error(key_path + ".port", fmt::format("must be in 0..65535, got {}", port));
  if (!token.empty() && token.size() < 8)
    throw Error(key_path + ".token", "must have at least 8 characters (or be empty for a random one)");
  if (view_size < 128 || view_size > 2048)
    throw Error(key_path + ".view_size", fmt::format("must be in 128..2048 pixels, got {}", view_size));
  if (!(pick_radius_px >= 1 && pick_radius_px <= 64))
    throw Error(key_path + ".pick_radius_px", fmt::format("must be in 1..64 pixels, got {}", pick_radius_px));
  if (max_body_bytes < 64 || max_body_bytes > (1u << 20))
    throw Error(key_path + ".max_body_bytes", fmt::format("must be in 64..1048576, got {}", max_body_bytes));
  if (threads < 1 || threads > 64) throw Error(key_path + ".threads", fmt::format("must be in 1..64, got {}", threads));
  connections.validate(key_path + ".connections");
}

// --- the server --------------------------------------------------------------------------------

namespace landmark_editor_detail {

using nlohmann::json;

struct Proposed {
  int vertex = -1;
  double confidence = 0;
  std::string how;
};

// One drawing of one face: its render options and picker, and the PNG once rendered.
struct Picture {
  std::unique_ptr<VertexPicker> picker;
  std::string png;
};

const char* kViews[] = {"front", "side"};

int view_index(const json& value) {
  const std::string name = value.is_string() ? value.get<std::string>() : std::string();
  if (name == "front") return 0;
  if (name == "side") return 1;
  http_json::reject(400, "'view' must be \"front\" or \"side\"");
}

double number_field(const json& body, const std::string& key) {
  const json& value = http_json::field(body, key);
  if (!value.is_number() || !std::isfinite(value.get<double>()))
    http_json::reject(400, fmt::format("'{}' must be a number (pixels of the picture)", key));
  return value.get<double>();
}

std::string name_field(const json& body) {
  const json& value = http_json::field(body, "name");
  if (!value.is_string() || value.get<std::string>().empty() || value.get<std::string>().size() > 100)
    http_json::reject(400, "'name' must be a landmark's name (a non-empty string)");
  return value.get<std::string>();
}

}  // namespace landmark_editor_detail

struct LandmarkEditorServer::Impl {
  using json = nlohmann::json;
  using Picture = landmark_editor_detail::Picture;

  LandmarkEditorOptions options;
  std::string token;
  std::string rig_yaml;
  Rig rig;
  FaceModel human;
  Positions avatar_drawn;  // the avatar in its face frame (upright), as drawn
  std::map<std::string, landmark_editor_detail::Proposed> proposals;
  Picture pictures[2][2];  // [avatar, human][front, side]
  GuardedHttpServer http;
  int port = 0;

  // The session: the landmarks as edited, which ones a person set, the undo stack, and what
  // rig.yaml holds (to tell unsaved changes).
  struct Snapshot {
    std::map<std::string, int> landmarks;
    std::set<std::string> hand_set;
    std::string change;
  };
  std::mutex mutex;  // everything below, and the pictures' PNGs
  std::map<std::string, int> landmarks;
  std::set<std::string> hand_set;
  std::vector<Snapshot> undo_stack;
  std::map<std::string, int> saved;
  std::string last_change;

  Impl(const std::string& rig_folder, const std::string& face_model_yaml, const LandmarkEditorOptions& o)
      : options(o), http(o.connections, o.max_body_bytes, o.threads) {
    namespace fs = std::filesystem;
    std::error_code ec;
    rig_yaml = fs::is_directory(rig_folder, ec) ? (fs::path(rig_folder) / "rig.yaml").string() : rig_folder;
    const std::string extension = fs::path(rig_yaml).extension().string();
    if (extension == ".glb" || extension == ".gltf")
      throw Error(rig_folder,
                  "a glTF file cannot hold landmarks: give a rig folder whose rig.yaml points at it (`retarget "
                  "avatar init` writes one)");
    if (!fs::exists(rig_yaml, ec))
      throw Error(rig_yaml, "does not exist: give a rig folder with a rig.yaml (`retarget avatar init` writes one)");
    rig = load_rig_folder(rig_yaml);
    human = load_face_model(face_model_yaml);
    token = options.token.empty() ? random_token() : options.token;
    landmarks = saved = rig.landmarks;
    // Landmarks an earlier session set by hand say so in their comment: they stay "hand-set".
    {
      std::ifstream in(rig_yaml, std::ios::binary);
      std::stringstream text;
      text << in.rdbuf();
      for (const auto& [name, comment] : landmark_editor_detail::landmark_line_comments(text.str()))
        if (landmarks.count(name) && comment.rfind(landmark_editor_detail::kHandSet, 0) == 0) hand_set.insert(name);
    }
    avatar_drawn = rig.neutral.vertices;
    read_proposals((fs::path(rig_yaml).parent_path() / "proposals.yaml").string());
    for (int v = 0; v < 2; ++v) {
      RenderOptions r;
      r.width = r.height = options.view_size;
      r.view = v == 0 ? RenderOptions::View::front : RenderOptions::View::side;
      r.margin = 0.08;
      pictures[0][v].picker = std::make_unique<VertexPicker>(rig.neutral, avatar_drawn, r);
      r.frame = face_box(human);
      pictures[1][v].picker = std::make_unique<VertexPicker>(human.neutral, human.neutral.vertices, r);
    }
    routes();
  }

  // proposals.yaml (avatar init): each proposal's vertex, confidence and origin, and the face's
  // frame, in which the avatar is drawn upright. Optional; a broken one is reported and ignored.
  void read_proposals(const std::string& path) {
    if (!std::filesystem::exists(path)) return;
    try {
      const YAML::Node root = YAML::LoadFile(path);
      for (const auto& entry : root["landmarks"]) {
        landmark_editor_detail::Proposed p;
        p.vertex = entry.second["vertex"].as<int>();
        p.confidence = entry.second["confidence"].as<double>(0.0);
        p.how = entry.second["how"].as<std::string>("");
        proposals[entry.first.as<std::string>()] = p;
      }
      if (const YAML::Node frame = root["frame"]) {
        Eigen::Matrix3d axes;  // rows: left, up, forward
        int row = 0;
        for (const char* key : {"left", "up", "forward"}) {
          const auto v = frame[key].as<std::vector<double>>();
          if (v.size() != 3) throw Error(path, fmt::format("frame.{} must have 3 numbers", key));
          axes.row(row++) << v[0], v[1], v[2];
        }
        if (!((axes * axes.transpose() - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() < 1e-3))
          throw Error(path, "frame: left, up and forward must be orthonormal");
        avatar_drawn = (rig.neutral.vertices * axes.transpose()).eval();
      }
    } catch (const YAML::Exception& e) {
      log::warn("{}:{}: ignored ({}); confidences are not shown", path, e.mark.line + 1, e.msg);
      proposals.clear();
    } catch (const Error& e) {
      log::warn("{}; drawn in the rig's own axes", e.what());
    }
  }

  // What the human's pictures frame: the face, not the whole head and shoulders (a scanned bust's
  // face fills a third of it): the box of its landmarks, widened by a third of its largest side
  // each way, within the mesh's own box. The whole mesh without three landmarks.
  static Eigen::AlignedBox3d face_box(const FaceModel& face) {
    const Eigen::AlignedBox3d whole = frame_box(face.neutral.vertices);
    if (face.landmarks.size() < 3) return whole;
    Eigen::AlignedBox3d box;
    for (const auto& [name, v] : face.landmarks) box.extend(face.neutral.vertices.row(v).transpose());
    const double pad = box.sizes().maxCoeff() / 3;
    box.min().array() -= pad;
    box.max().array() += pad;
    return box.intersection(whole);
  }

  // --- state ----------------------------------------------------------------------------------

  json pixels_of(int face, int vertex) const {
    json out = json::object();
    for (int v = 0; v < 2; ++v) {
      const VertexPicker& p = *pictures[face][v].picker;
      const Eigen::Vector2d px = p.pixel(vertex);
      out[landmark_editor_detail::kViews[v]] = {px.x(), px.y(), p.visible(vertex)};
    }
    return out;
  }

  json state() const {
    std::set<std::string> names;
    for (const auto& [name, v] : landmarks) names.insert(name);
    for (const auto& [name, v] : human.landmarks) names.insert(name);
    json list = json::array();
    for (const std::string& name : names) {
      json item = {{"name", name}, {"avatar", nullptr}, {"human", nullptr}};
      const auto a = landmarks.find(name);
      if (a != landmarks.end()) {
        const auto p = proposals.find(name);
        const bool proposed = !hand_set.count(name) && p != proposals.end() && p->second.vertex == a->second;
        item["avatar"] = {{"vertex", a->second},
                          {"origin", hand_set.count(name) ? "hand-set"
                                     : proposed           ? "proposed"
                                                          : "rig.yaml"},
                          {"confidence", proposed ? json(p->second.confidence) : json(nullptr)},
                          {"how", proposed ? p->second.how : std::string()},
                          {"pixels", pixels_of(0, a->second)}};
      }
      const auto h = human.landmarks.find(name);
      if (h != human.landmarks.end()) item["human"] = {{"pixels", pixels_of(1, h->second)}};
      list.push_back(std::move(item));
    }
    return {{"rig", rig.name},
            {"human", human.name},
            {"rig_yaml", rig_yaml},
            {"size", {options.view_size, options.view_size}},
            {"views", {"front", "side"}},
            {"landmarks", list},
            {"can_undo", !undo_stack.empty()},
            {"last_change", last_change},
            {"unsaved", landmarks != saved}};
  }

  void remember(std::string change) {
    undo_stack.push_back({landmarks, hand_set, change});
    if (undo_stack.size() > 200) undo_stack.erase(undo_stack.begin());
    last_change = std::move(change);
  }

  // --- routes ---------------------------------------------------------------------------------

  using Endpoint = void (Impl::*)(const httplib::Request&, httplib::Response&);

  // Runs `endpoint` with the token checked (pages excepted) and JSON bodies required on POSTs,
  // turning HttpError and retarget::Error into JSON errors.
  httplib::Server::Handler wrap(Endpoint endpoint, bool needs_token = true) {
    return [this, endpoint, needs_token](const httplib::Request& req, httplib::Response& res) {
      try {
        if (req.body.size() > options.max_body_bytes) http_json::reject(413, "the request body is too large");
        if (needs_token) {
          const std::string given = http_json::bearer_token(req);
          if (given.empty())
            http_json::reject(401,
                              "the page's token is required: open the address `retarget avatar landmarks` printed");
          if (!http_json::same_token(given, token)) http_json::reject(403, "this is not the page's token");
        }
        if (req.method == "POST" && req.get_header_value("Content-Type").rfind("application/json", 0) != 0)
          http_json::reject(415, "send the request body as JSON (Content-Type: application/json)");
        (this->*endpoint)(req, res);
      } catch (const http_json::HttpError& e) {
        http_json::send_json(res, {{"error", e.message}}, e.status);
      } catch (const Error& e) {
        http_json::send_json(res, {{"error", e.what()}}, 500);
      }
    };
  }

  void routes() {
    http.set_default_headers(
        {{"X-Content-Type-Options", "nosniff"}, {"X-Frame-Options", "DENY"}, {"Referrer-Policy", "no-referrer"}});
    http.Get("/", wrap(&Impl::on_page, false));
    http.Get(R"(/static/([A-Za-z0-9_-]+\.(js|css)))", wrap(&Impl::on_asset, false));
    http.Get("/api/state", wrap(&Impl::on_state));
    http.Get(R"(/img/(avatar|human)/(front|side)\.png)", wrap(&Impl::on_picture));
    http.Post("/api/place", wrap(&Impl::on_place));
    http.Post("/api/remove", wrap(&Impl::on_remove));
    http.Post("/api/undo", wrap(&Impl::on_undo));
    http.Post("/api/save", wrap(&Impl::on_save));
    http.set_error_responder(http_json::respond_to_error);
    http.set_exception_handler(http_json::respond_to_exception);
  }

  void serve_asset(httplib::Response& res, std::string_view name) {
    serve_web_asset(res, find_landmark_editor_web_asset, name);
  }

  void on_page(const httplib::Request&, httplib::Response& res) { serve_asset(res, "index.html"); }
  void on_asset(const httplib::Request& req, httplib::Response& res) { serve_asset(res, req.matches[1].str()); }

  void on_state(const httplib::Request&, httplib::Response& res) {
    std::lock_guard<std::mutex> lock(mutex);
    http_json::send_json(res, state());
  }

  void on_picture(const httplib::Request& req, httplib::Response& res) {
    const int face = req.matches[1].str() == "avatar" ? 0 : 1;
    const int view = req.matches[2].str() == "front" ? 0 : 1;
    std::string png;
    {
      std::lock_guard<std::mutex> lock(mutex);
      Picture& p = pictures[face][view];
      if (p.png.empty()) {
        const Mesh& mesh = face == 0 ? rig.neutral : human.neutral;
        const Positions& drawn = face == 0 ? avatar_drawn : human.neutral.vertices;
        p.png = encode_png(render(mesh, drawn, p.picker->options()), "picture");
      }
      png = p.png;
    }
    res.set_header("Cache-Control", "private, max-age=86400");
    res.set_content(png, "image/png");
  }

  // The name must be one the human or the avatar has; 404 otherwise.
  void check_known(const std::string& name) const {
    if (landmarks.count(name) || human.landmarks.count(name)) return;
    http_json::reject(404, fmt::format("no landmark '{}': neither the avatar nor the human face ({}) has one of "
                                       "that name",
                                       name, human.name));
  }

  void on_place(const httplib::Request& req, httplib::Response& res) {
    const json body = http_json::body_object(req);
    const std::string name = landmark_editor_detail::name_field(body);
    const int view = landmark_editor_detail::view_index(http_json::field(body, "view"));
    const Eigen::Vector2d click(landmark_editor_detail::number_field(body, "x"),
                                landmark_editor_detail::number_field(body, "y"));
    std::lock_guard<std::mutex> lock(mutex);
    check_known(name);
    const int vertex = pictures[0][view].picker->pick(click, options.pick_radius_px);
    if (vertex < 0)
      http_json::reject(422, fmt::format("the click at ({:.0f}, {:.0f}) is beside the avatar's head: click on its "
                                         "surface",
                                         click.x(), click.y()));
    const auto old = landmarks.find(name);
    remember(old == landmarks.end() ? fmt::format("added {}", name) : fmt::format("moved {}", name));
    landmarks[name] = vertex;
    hand_set.insert(name);
    json out = state();
    out["picked"] = vertex;
    http_json::send_json(res, out);
  }

  void on_remove(const httplib::Request& req, httplib::Response& res) {
    const std::string name = landmark_editor_detail::name_field(http_json::body_object(req));
    std::lock_guard<std::mutex> lock(mutex);
    check_known(name);
    if (!landmarks.count(name)) http_json::reject(404, fmt::format("the avatar has no landmark '{}' to remove", name));
    remember(fmt::format("removed {}", name));
    landmarks.erase(name);
    hand_set.erase(name);
    http_json::send_json(res, state());
  }

  void on_undo(const httplib::Request& req, httplib::Response& res) {
    http_json::body_object(req);
    std::lock_guard<std::mutex> lock(mutex);
    if (undo_stack.empty()) http_json::reject(409, "nothing to undo");
    Snapshot s = std::move(undo_stack.back());
    undo_stack.pop_back();
    landmarks = std::move(s.landmarks);
    hand_set = std::move(s.hand_set);
    last_change = "undid: " + s.change;
    http_json::send_json(res, state());
  }

  void on_save(const httplib::Request& req, httplib::Response& res) {
    http_json::body_object(req);
    std::lock_guard<std::mutex> lock(mutex);
    std::map<std::string, std::string> comments;
    for (const std::string& name : hand_set)
      if (landmarks.count(name)) comments[name] = landmark_editor_detail::kHandSet;
    write_rig_landmarks(rig_yaml, landmarks, comments);
    // What the pipeline will read: the file must load, with exactly these landmarks.
    const Rig reloaded = load_rig_folder(rig_yaml);
    if (reloaded.landmarks != landmarks)
      throw Error(rig_yaml, "was written but does not read back with the landmarks saved");
    saved = landmarks;
    last_change = fmt::format("saved {} landmarks to {}", landmarks.size(), rig_yaml);
    json out = state();
    out["saved"] = rig_yaml;
    http_json::send_json(res, out);
  }
};

LandmarkEditorServer::LandmarkEditorServer(const std::string& rig_folder, const std::string& face_model_yaml,
                                           const LandmarkEditorOptions& options) {
  options.validate();
  impl_ = std::make_unique<Impl>(rig_folder, face_model_yaml, options);
}

LandmarkEditorServer::~LandmarkEditorServer() { stop(); }

int LandmarkEditorServer::bind() {
  Impl& s = *impl_;
  s.port = s.http.listen_on(s.options.host, s.options.port);
  return s.port;
}

void LandmarkEditorServer::run() { impl_->http.listen_after_bind(); }

void LandmarkEditorServer::stop() {
  if (impl_) impl_->http.stop();
}

int LandmarkEditorServer::port() const { return impl_->port; }
const std::string& LandmarkEditorServer::token() const { return impl_->token; }
std::string LandmarkEditorServer::base_url() const {
  return fmt::format("http://{}:{}", impl_->options.host, impl_->port);
}
std::string LandmarkEditorServer::page_url() const { return base_url() + "/#token=" + impl_->token; }

}  // namespace retarget
