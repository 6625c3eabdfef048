// retarget-infer --stream: ARKit rows in, weights lines out, against --arkit --weights on the same take.
#include <sys/wait.h>
#include <unistd.h>

// LibTorch before Catch: glog (through c10) defines CHECK, and the last definition wins.
#include <torch/torch.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <future>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "bundle/bundle_format.h"
#include "geometry/controller_map.h"
#include "geometry/face_model.h"
#include "geometry/mesh_io.h"
#include "infer/infer_run.h"
#include "infer/rig_head_run.h"
#include "infer/stream_run.h"
#include "infer/stream_socket.h"
#include "tests/infer/arkit_test_support.h"

namespace retarget {

// The helpers and the test cases in a namespace of their own: unity builds put several test files together.
namespace stream_run_test {

namespace fs = std::filesystem;
using Json = nlohmann::json;

// A tiny bundle with a rig on the human patch, the patch face model on disk and a Live Link take of 11 frames.
struct StreamScene {
  fs::path dir;
  std::string bundle, face_model, take_text, take;
  explicit StreamScene(const std::string& name)
      : dir(test::scratch_dir(name)), bundle(test::tiny_rig_bundle(dir / "bundle")) {
    write_face_model((dir / "model").string(), test::arkit_test_model());
    face_model = (dir / "model" / "face_model.yaml").string();
    take_text = test::live_link_csv(test::arkit_test_frames(11));
    take = test::write_file(dir / "take.csv", take_text);
  }

  StreamOptions options() const {
    StreamOptions o;
    o.bundle = bundle;
    o.face_model = face_model;
    o.weights_smoothness = 0.1;  // the previous frame's weights matter: the order must be the take's
    return o;
  }
};

struct QuietLog {
  log::Level previous = log::level();
  QuietLog() { log::set_level(log::Level::off); }
  ~QuietLog() { log::set_level(previous); }
};

std::vector<Json> json_lines(const std::string& text) {
  std::vector<Json> lines;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) lines.push_back(Json::parse(line));
  return lines;
}

// weights.csv of retarget-infer --arkit --weights: frame name -> the controllers' weights.
std::vector<std::vector<double>> arkit_weights(const StreamScene& scene, const std::string& out, int batch) {
  InferOptions o;
  o.bundle = scene.bundle;
  o.arkit = scene.take;
  o.face_model = scene.face_model;
  o.out = (scene.dir / out).string();
  o.batch = batch;
  o.progress = nullptr;
  o.weights = true;
  o.weights_smoothness = 0.1;
  o.weights_format = "csv";
  const InferSummary summary = run_inference(o);
  REQUIRE(summary.failed() == 0);
  std::vector<std::vector<double>> rows;
  const std::vector<std::string> lines = test::lines_of(fs::path(o.out) / "weights.csv");
  for (size_t l = 1; l < lines.size(); ++l) {
    std::vector<double> row;
    std::istringstream fields(lines[l]);
    std::string field;
    std::getline(fields, field, ',');  // the frame name
    while (std::getline(fields, field, ',')) row.push_back(std::stod(field));
    row.pop_back();  // residual_mm
    rows.push_back(row);
  }
  return rows;
}

void check_weights(const std::vector<Json>& lines, const std::vector<std::vector<double>>& expected,
                   const std::vector<std::string>& controllers) {
  REQUIRE(lines.size() == expected.size());
  for (size_t f = 0; f < lines.size(); ++f) {
    INFO("frame " << f);
    CHECK(lines[f]["frame"] == static_cast<int>(f));
    REQUIRE(lines[f]["weights"].size() == controllers.size());
    for (size_t k = 0; k < controllers.size(); ++k)
      CHECK(std::abs(lines[f]["weights"][controllers[k]].get<double>() - expected[f][k]) <= 1e-9);
  }
}

int run_stream_cli(const std::string& arguments, const fs::path& in, const fs::path& out, const fs::path& err) {
  const std::string command = std::string("'") + RETARGET_INFER_EXE + "' " + arguments + " <'" + in.string() + "' >'" +
                              out.string() + "' 2>'" + err.string() + "'";
  const int status = std::system(command.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

TEST_CASE("a take through the stream gives --arkit --weights' weights, one line per frame in order", "[stream]") {
  const QuietLog quiet;
  const StreamScene scene("stream_equal");
  // Batch 1, as the stream runs; batch 4 within float rounding of the network's batched forward.
  const std::vector<std::vector<double>> expected = arkit_weights(scene, "arkit_out", 1);
  StreamRun stream(scene.options());
  for (const bool jsonl : {false, true}) {
    INFO((jsonl ? "JSON lines" : "CSV"));
    std::istringstream in(jsonl ? test::ict_jsonl(test::arkit_test_frames(11)) : scene.take_text);
    std::ostringstream out;
    const StreamSummary summary = stream.run(in, out);
    CHECK(summary.frames == 11);
    CHECK(summary.dropped == 0);
    CHECK(summary.malformed == 0);
    CHECK(summary.latency_ms.size() == 11);
    const std::vector<Json> lines = json_lines(out.str());
    check_weights(lines, expected, stream.controllers());
    for (int f = 0; f < 11; ++f) {
      CHECK(lines[f]["timecode"] == test::live_link_timecode(f));
      CHECK(lines[f]["residual_mm"].get<double>() >= 0);
      CHECK(lines[f]["latency_ms"].get<double>() >= 0);
    }
  }
  const std::vector<std::vector<double>> batched = arkit_weights(scene, "arkit_out_batch4", 4);
  for (size_t f = 0; f < batched.size(); ++f)
    for (size_t k = 0; k < batched[f].size(); ++k) CHECK(std::abs(batched[f][k] - expected[f][k]) <= 1e-5);
}

TEST_CASE("the stream with --arkit-columns reads every line as a frame", "[stream]") {
  const QuietLog quiet;
  const StreamScene scene("stream_columns");
  const std::string header = scene.take_text.substr(0, scene.take_text.find('\n'));
  StreamOptions options = scene.options();
  options.arkit_columns = header;
  StreamRun stream(options);
  std::istringstream in(scene.take_text.substr(header.size() + 1));
  std::ostringstream out;
  const StreamSummary summary = stream.run(in, out);
  check_weights(json_lines(out.str()), arkit_weights(scene, "arkit_out", 1), stream.controllers());
  CHECK(summary.frames == 11);

  options.arkit_columns = "Timecode,,JawOpen";
  StreamRun bad(options);
  std::istringstream none("");
  CHECK_THROWS_WITH(bad.run(none, out), Catch::Matchers::Contains("--arkit-columns") &&
                                            Catch::Matchers::Contains("column 2: an empty column name"));
}

TEST_CASE("malformed rows are reported with their line and column and skipped; the stream goes on", "[stream]") {
  const StreamScene scene("stream_malformed");
  std::vector<std::string> lines;
  std::istringstream take(scene.take_text);
  for (std::string line; std::getline(take, line);) lines.push_back(line);
  lines[4] = "12:00:00:00.000,12,abc" + lines[4].substr(lines[4].find(',', lines[4].find(',') + 1) + 1 +
                                                        lines[4]
                                                            .substr(lines[4].find(',', lines[4].find(',') + 1) + 1)
                                                            .find(','));  // frame 3, line 5: column 3 not a number
  lines[7] = "12:00:00:00.000,12,0.5";                                    // frame 6, line 8: too few fields
  std::string text;
  for (const std::string& line : lines) text += line + "\n";
  text += "12:34:59:59.999,12,0.1";  // the input ends mid-line

  test::LogCapture log;
  StreamRun stream(scene.options());
  std::istringstream in(text);
  std::ostringstream out;
  const StreamSummary summary = stream.run(in, out);
  CHECK(summary.malformed == 2);
  CHECK(summary.frames == 9);
  CHECK(summary.incomplete_line);
  CHECK(log.count(log::Level::error, "stdin:5: column 3 (BrowInnerUpLeft): expected a number") == 1);
  CHECK(log.count(log::Level::error, "stdin:8: 3 fields but the header (line 1) has") == 1);
  CHECK(log.count(log::Level::error, "stdin:13: the input ended in the middle of the line") == 1);
  // The header's reports once, as --arkit gives them: the head rotation columns are not used.
  CHECK(log.count(log::Level::info, "stdin: not used (head and eye rotations") == 1);
  const std::vector<Json> written = json_lines(out.str());
  REQUIRE(written.size() == 9);
  const std::vector<int> timecode_frames{0, 1, 2, 4, 5, 7, 8, 9, 10};  // the take's frames that were read
  for (int f = 0; f < 9; ++f) {
    CHECK(written[f]["frame"] == f);
    CHECK(written[f]["timecode"] == test::live_link_timecode(timecode_frames[f]));
  }
  CHECK_THAT(format_stream_summary(summary),
             Catch::Matchers::StartsWith("stream: 9 frames, 0 dropped, 2 malformed; latency p50 "));

  // A header that is not one ends the stream: nothing can be read without it.
  std::istringstream numbers("0.1,0.2\n0.3,0.4\n");
  CHECK_THROWS_WITH(stream.run(numbers, out), Catch::Matchers::Contains("stdin:1: column 1: expected a header"));
}

TEST_CASE("what leaves no line readable ends the stream: junk headers, bytes that are not text, endless lines",
          "[stream]") {
  const StreamScene scene("stream_unreadable");
  StreamRun stream(scene.options());
  const std::string rows = scene.take_text.substr(scene.take_text.find('\n') + 1);  // the frames, no header
  struct Case {
    std::string text;
    std::string message;
  };
  const std::vector<Case> cases = {
      {"foo;bar\n" + rows,
       "stdin:1: no column of the header names an expression of the face model (1 column: foo;bar)"},
      {"\x89PNG\r\n\x1a\n" + rows, "stdin:1: column 1: byte 0x89 is not text"},
      {scene.take_text + "\xff\xfe\x00\x01\n" + rows, "stdin:13: column 1: byte 0xFF is not text"},
      {"{\"foo\": 0.5}\n", "stdin:1: no name on this line (nor on a line before it) names an expression"},
      // 3 MiB without a line break: the reader holds 1 MiB of it at most, then stops.
      {scene.take_text + std::string(3 << 20, '1') + "\n" + rows,
       "stdin:13: a line longer than a take's lines may be (1048576 bytes)"},
  };
  for (const Case& c : cases) {
    INFO(c.message);
    std::istringstream in(c.text);
    std::ostringstream out;
    CHECK_THROWS_AS(stream.run(in, out), UnreadableTake);
    std::istringstream again(c.text);
    CHECK_THAT(test::error_of([&] { stream.run(again, out); }),
               Catch::Matchers::Contains(c.message) && Catch::Matchers::Contains("the stream ends here"));
  }
  // From the command line: status 2 with the message, as for a bad header.
  const fs::path junk = scene.dir / "junk.csv", out = scene.dir / "out.jsonl", err = scene.dir / "err.txt";
  test::write_text(junk, "foo;bar\n" + rows);
  CHECK(run_stream_cli("--stream --bundle '" + scene.bundle + "' --face-model '" + scene.face_model + "'", junk, out,
                       err) == 2);
  CHECK_THAT(test::read_text(err),
             Catch::Matchers::Contains("retarget-infer: stdin:1: no column of the header names an expression"));
}

// A std::ostream's buffer whose flushes fail after `allowed` of them: a reader that went away.
struct ClosingBuffer : std::stringbuf {
  int allowed;
  explicit ClosingBuffer(int n) : allowed(n) {}
  int sync() override { return --allowed >= 0 ? 0 : -1; }
};

TEST_CASE("stream meshes: each frame's avatar mesh written; a mesh or the output that fails is handled", "[stream]") {
  const StreamScene scene("stream_meshes");
  test::LogCapture log;
  StreamOptions options = scene.options();
  options.meshes = (scene.dir / "meshes").string();
  StreamRun stream(options);
  fs::create_directories(scene.dir / "meshes" / "frame_000001.obj");  // a folder where frame 1's mesh goes
  std::istringstream in(scene.take_text);
  std::ostringstream out;
  const StreamSummary summary = stream.run(in, out);
  CHECK(summary.frames == 11);
  CHECK(summary.meshes_failed == 1);
  CHECK(log.count(log::Level::error, "frame 1: ") == 1);
  CHECK(json_lines(out.str()).size() == 11);
  for (const int f : {0, 2, 10}) {
    INFO("frame " << f);
    const Mesh mesh = read_mesh((scene.dir / "meshes" / fmt::format("frame_{:06d}.obj", f)).string());
    CHECK(mesh.vertex_count() == test::fine_ball().vertex_count());
  }
  CHECK_THAT(format_stream_summary(summary), Catch::Matchers::Contains("1 mesh not written"));

  // The reader goes away after two lines: the stream stops there, with its summary.
  ClosingBuffer closing(2);
  std::ostream gone(&closing);
  std::istringstream again(scene.take_text);
  const StreamSummary stopped = stream.run(again, gone);
  CHECK(stopped.frames == 2);
  CHECK(stopped.output_closed);
  CHECK_THAT(format_stream_summary(stopped), Catch::Matchers::Contains("the output closed"));
}

TEST_CASE(
    "with drop or max-latency-ms, a slow worker takes the newest waiting row and writes the older ones as dropped",
    "[stream]") {
  const QuietLog quiet;
  const StreamScene scene("stream_drop");
  const bool drop = GENERATE(true, false);
  INFO((drop ? "--drop" : "--max-latency-ms 50"));
  std::vector<std::string> lines;
  std::istringstream take(scene.take_text);
  for (std::string line; std::getline(take, line);) lines.push_back(line + "\n");

  int fds[2];
  REQUIRE(::pipe(fds) == 0);
  std::promise<void> started, written;
  std::shared_future<void> rows_written = written.get_future().share();
  StreamOptions options = scene.options();
  options.drop = drop;
  if (!drop) options.max_latency_ms = 50;  // rows 1 to 5 wait 300 ms: all but the newest are too old
  options.before_frame = [&, rows_written](int frame) {
    if (frame != 0) return;
    started.set_value();
    rows_written.wait();
    std::this_thread::sleep_for(std::chrono::milliseconds(300));  // the reader queues rows 1 to 5
  };
  StreamRun stream(options);
  FdStream in(fds[0]);
  std::ostringstream out;
  StreamSummary summary;
  std::thread worker([&] { summary = stream.run(in, out); });
  auto send = [&](const std::string& text) {
    REQUIRE(::write(fds[1], text.data(), text.size()) == ssize_t(text.size()));
  };
  send(lines[0] + lines[1]);  // header, frame 0
  started.get_future().wait();
  for (int f = 1; f <= 5; ++f) send(lines[f + 1]);
  written.set_value();
  ::close(fds[1]);
  worker.join();

  const std::vector<Json> written_lines = json_lines(out.str());
  REQUIRE(written_lines.size() == 6);
  CHECK(written_lines[0]["frame"] == 0);
  CHECK(written_lines[0].contains("weights"));
  for (int f = 1; f <= 4; ++f) {
    CHECK(written_lines[f] == Json{{"frame", f}, {"dropped", true}});
  }
  CHECK(written_lines[5]["frame"] == 5);
  CHECK(written_lines[5]["timecode"] == test::live_link_timecode(5));
  CHECK(written_lines[5].contains("weights"));
  CHECK(summary.frames == 2);
  CHECK(summary.dropped == 4);
}

TEST_CASE("the stream over a loopback TCP client: rows in, lines back, half-close mid-line ends it", "[stream]") {
  const QuietLog quiet;
  const StreamScene scene("stream_tcp");
  std::vector<std::string> lines;
  std::istringstream take(scene.take_text);
  for (std::string line; std::getline(take, line);) lines.push_back(line + "\n");

  std::promise<int> port;
  StreamOptions options = scene.options();
  options.listen = 0;
  options.on_listening = [&](int p) { port.set_value(p); };
  StreamRun stream(options);
  StreamSummary summary;
  std::thread server([&] { summary = stream.serve(); });
  std::unique_ptr<FdStream> client = connect_loopback(port.get_future().get());
  std::string text;
  for (const std::string& line : lines) text += line;
  *client << text << "12:34:59:59.999,12,0.1";  // closes mid-line
  client->shutdown_write();
  std::string received;
  for (std::string line; std::getline(*client, line);) received += line + "\n";
  server.join();

  check_weights(json_lines(received), arkit_weights(scene, "arkit_out", 1), stream.controllers());
  CHECK(summary.frames == 11);
  CHECK(summary.incomplete_line);
}

TEST_CASE("a --listen client that sends an endless line ends the stream at 1 MiB", "[stream]") {
  const QuietLog quiet;
  const StreamScene scene("stream_tcp_long_line");
  std::promise<int> port;
  StreamOptions options = scene.options();
  options.listen = 0;
  options.on_listening = [&](int p) { port.set_value(p); };
  StreamRun stream(options);
  std::string failure;
  std::thread server([&] {
    try {
      stream.serve();
    } catch (const UnreadableTake& e) {
      failure = e.what();
    }
  });
  std::unique_ptr<FdStream> client = connect_loopback(port.get_future().get());
  // The take, then 8 MiB without a line break: the server stops reading at 1 MiB and closes.
  *client << scene.take_text << std::flush;
  const std::string chunk(1 << 20, '7');
  for (int i = 0; i < 8 && *client; ++i) *client << chunk << std::flush;
  server.join();  // the server stopped on its own: it did not wait for the 8 MiB
  CHECK_THAT(failure, Catch::Matchers::Contains("127.0.0.1:") &&
                          Catch::Matchers::Contains(":13: a line longer than a take's lines may be (1048576 bytes)"));
}

TEST_CASE("retarget-infer --stream reads rows on stdin and writes lines on stdout, the summary on stderr",
          "[stream][cli]") {
  const StreamScene scene("stream_cli");
  const fs::path out = scene.dir / "out.jsonl", err = scene.dir / "err.txt";
  const std::string common = "--stream --bundle '" + scene.bundle + "' --face-model '" + scene.face_model + "'";
  REQUIRE(run_stream_cli(common + " --weights-smoothness 0.1", scene.take, out, err) == 0);
  const StreamRun stream(scene.options());
  check_weights(json_lines(test::read_text(out)), arkit_weights(scene, "arkit_out", 1), stream.controllers());
  CHECK_THAT(test::read_text(err), Catch::Matchers::Contains("stream: 11 frames, 0 dropped, 0 malformed"));

  // Options that do not go with --stream, and a bundle without a rig.
  CHECK(run_stream_cli(common + " --out x", scene.take, out, err) == 2);
  CHECK_THAT(test::read_text(err), Catch::Matchers::Contains("--out: not with --stream"));
  const std::string plain = test::tiny_bundle(scene.dir / "plain");
  CHECK(run_stream_cli("--stream --bundle '" + plain + "' --face-model '" + scene.face_model + "'", scene.take, out,
                       err) == 2);
  CHECK_THAT(test::read_text(err), Catch::Matchers::Contains("this bundle has no rig"));
  CHECK(run_stream_cli("--stream --bundle '" + scene.bundle + "'", scene.take, out, err) == 2);
  CHECK_THAT(test::read_text(err), Catch::Matchers::Contains("--face-model: required with --stream"));
}

}  // namespace stream_run_test
}  // namespace retarget

namespace retarget {
namespace stream_run_test {

// Blendshape animation live: with --rig-map each row's weights go through the map straight to the
// rig's controllers, the weights the rig head gives the same take offline.
TEST_CASE("the stream with the rig head: each row through the map, as retarget-infer --rig-map --arkit", "[stream]") {
  const QuietLog quiet;
  const StreamScene scene("stream_rig_map");
  const Rig rig = *load_bundle(scene.bundle).rig;
  const FaceModel model = test::arkit_test_model();
  ControllerMap map;  // controller c reads shape s with weight 0.1 (c + 1) - 0.05 s
  for (const Controller& c : rig.controllers) map.controllers.push_back(c.name);
  for (const Blendshape& b : model.expressions) map.shapes.push_back(b.name);
  map.matrix.resize(static_cast<Eigen::Index>(map.controllers.size()), static_cast<Eigen::Index>(map.shapes.size()));
  for (Eigen::Index c = 0; c < map.matrix.rows(); ++c)
    for (Eigen::Index s = 0; s < map.matrix.cols(); ++s)
      map.matrix(c, s) = 0.1 * static_cast<double>(c + 1) - 0.05 * static_cast<double>(s);
  map.pairs = 47;
  const std::string map_path = (scene.dir / "map.yaml").string();
  write_controller_map(map_path, map);

  RigHeadRunOptions offline;
  offline.bundle = scene.bundle;
  offline.rig_map = map_path;
  offline.face_model = scene.face_model;
  offline.arkit = scene.take;
  offline.out = (scene.dir / "offline").string();
  const std::vector<std::string> lines = test::lines_of(run_rig_head(offline).weights_csv);
  std::vector<std::vector<double>> expected;
  for (size_t l = 1; l < lines.size(); ++l) {
    std::vector<double> row;
    std::istringstream fields(lines[l]);
    std::string field;
    std::getline(fields, field, ',');
    while (std::getline(fields, field, ',')) row.push_back(std::stod(field));
    row.resize(rig.controllers.size());  // any residual column after the controllers
    expected.push_back(row);
  }

  StreamOptions o = scene.options();
  o.rig_map = map_path;
  StreamRun stream(o);
  std::istringstream in(scene.take_text);
  std::ostringstream out;
  const StreamSummary summary = stream.run(in, out);
  CHECK(summary.frames == 11);
  const std::vector<Json> got = json_lines(out.str());
  REQUIRE(got.size() == expected.size());
  for (size_t f = 0; f < got.size(); ++f) {
    INFO("frame " << f);
    for (size_t k = 0; k < rig.controllers.size(); ++k)
      CHECK(std::abs(got[f]["weights"][rig.controllers[k].name].get<double>() - expected[f][k]) <= 1e-5);
    CHECK(got[f]["residual_mm"].get<double>() == 0);
  }

  // A map from a shape the face model lacks is refused before any row.
  ControllerMap other = map;
  other.shapes.back() = "tongueOut";
  write_controller_map((scene.dir / "other.yaml").string(), other);
  o.rig_map = (scene.dir / "other.yaml").string();
  CHECK_THAT(test::error_of([&] { StreamRun again(o); }), Catch::Contains("tongueOut"));
}

}  // namespace stream_run_test
}  // namespace retarget
