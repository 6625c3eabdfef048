#include "infer/stream_run.h"

#include <fmt/format.h>
#include <torch/torch.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <csignal>
#include <deque>
#include <filesystem>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <thread>

#include "core/cpu_threads.h"
#include "core/error.h"
#include "core/log.h"
#include "geometry/controller_map.h"
#include "geometry/face_model.h"
#include "geometry/mesh_io.h"
#include "geometry/rig_weight_fit.h"
#include "infer/arkit_faces.h"
#include "infer/memory_reuse.h"
#include "infer/retargeter.h"
#include "infer/stream_socket.h"
#include "infer/weights_output.h"

namespace retarget {

// Named, not anonymous: a unity batch shares one anonymous namespace among its files.
namespace stream_run_detail {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using StreamJson = nlohmann::ordered_json;

// A frame read and waiting for the worker.
struct Pending {
  ArkitRow row;
  int frame = 0;
  Clock::time_point arrival;
};

double milliseconds(Clock::time_point from, Clock::time_point to) {
  return std::chrono::duration<double, std::milli>(to - from).count();
}

bool blank(const std::string& text) {
  return std::all_of(text.begin(), text.end(), [](char c) { return std::isspace(static_cast<unsigned char>(c)); });
}

// One line of the input, read up to kMaxTakeLineBytes + 1 bytes (so a longer one is told without
// being read whole): `line` ends with a line break (not kept), `last` does not (the input closed
// mid-line), `end` is the end of the input.
enum class LineRead { line, last, end };
LineRead read_capped_line(std::istream& in, std::string& text) {
  text.clear();
  std::streambuf* buffer = in.rdbuf();
  while (true) {
    const int c = buffer->sbumpc();
    if (c == std::char_traits<char>::eof()) return text.empty() ? LineRead::end : LineRead::last;
    if (c == '\n') return LineRead::line;
    text.push_back(static_cast<char>(c));
    if (text.size() > kMaxTakeLineBytes) return LineRead::line;  // the parser refuses it
  }
}

// The format by the first non-blank line: '{' JSON lines, else CSV.
ArkitTakeFormat line_format(const std::string& line) {
  for (char c : line)
    if (!std::isspace(static_cast<unsigned char>(c)) && c != '\xEF' && c != '\xBB' && c != '\xBF')
      return c == '{' ? ArkitTakeFormat::jsonl : ArkitTakeFormat::csv;
  return ArkitTakeFormat::csv;
}

// The rows waiting, shared by the reader thread and the worker.
struct RowQueue {
  std::mutex mutex;
  std::condition_variable ready;
  std::deque<Pending> rows;
  bool ended = false;
  void push(Pending&& pending) {
    {
      const std::lock_guard<std::mutex> lock(mutex);
      rows.push_back(std::move(pending));
    }
    ready.notify_one();
  }
  void end() {
    {
      const std::lock_guard<std::mutex> lock(mutex);
      ended = true;
    }
    ready.notify_one();
  }
};

// A CSV header's reports as soon as it is read (unused names, expressions no column drives).
void report_names(const ArkitRowParser& parser) {
  ArkitTake reports = parser.reports();
  reports.clamped = 0;
  report_arkit_take(reports);
}

}  // namespace stream_run_detail

void StreamOptions::validate() const {
  if (bundle.empty()) throw Error("--bundle", "required: the bundle folder the stream runs through");
  if (face_model.empty())
    throw Error("--face-model",
                "required with --stream: the face model the rows' weights drive (face_model.yaml or its folder)");
  for (size_t i = 0; i < identity.size(); ++i)
    if (!std::isfinite(identity[i]))
      throw Error("--identity", fmt::format("entry {}: expected a finite number, got {}", i + 1, identity[i]));
  if (listen < -1 || listen > 65535)
    throw Error("--listen", fmt::format("expected a TCP port from 1 to 65535, got {}", listen));
  if (!(max_latency_ms >= 0) || !std::isfinite(max_latency_ms))
    throw Error("--max-latency-ms", fmt::format("expected milliseconds > 0, got {}", max_latency_ms));
  WeightsOutputOptions weights;
  weights.ridge = weights_ridge;
  weights.smoothness = weights_smoothness;
  weights.validate();
  checked_thread_count(threads, "--threads");
}

double StreamSummary::latency_percentile(double p) const {
  if (latency_ms.empty()) return 0;
  std::vector<double> sorted = latency_ms;
  std::sort(sorted.begin(), sorted.end());
  const double rank = std::ceil(p / 100.0 * static_cast<double>(sorted.size()));
  const size_t index = static_cast<size_t>(std::clamp(rank, 1.0, static_cast<double>(sorted.size()))) - 1;
  return sorted[index];
}

std::string format_stream_summary(const StreamSummary& s) {
  std::string text = fmt::format("stream: {} frame{}, {} dropped, {} malformed", s.frames, s.frames == 1 ? "" : "s",
                                 s.dropped, s.malformed);
  if (s.frames > 0)
    text += fmt::format("; latency p50 {:.2f} ms, p99 {:.2f} ms, max {:.2f} ms; residual mean {:.4g} {}, max {:.4g} {}",
                        s.latency_percentile(50), s.latency_percentile(99), s.latency_percentile(100), s.residual_mean,
                        s.residual_unit, s.residual_max, s.residual_unit);
  if (s.incomplete_line) text += "; the input ended mid-line (that line not used)";
  if (s.meshes_failed > 0)
    text += fmt::format("; {} mesh{} not written", s.meshes_failed, s.meshes_failed == 1 ? "" : "es");
  if (s.output_closed) text += "; the output closed (stopped there)";
  return text + "\n";
}

struct StreamRun::State {
  StreamOptions options;
  Retargeter retargeter;
  ArkitFaces faces;
  RigWeightFit fit;
  double scale = 1;  // residual units per rig unit
  std::string residual_unit;
  std::vector<std::string> controllers;
  ArkitTake scratch;                       // one frame: the weights ArkitFaces reads
  std::optional<ControllerMap> map;        // --rig-map: the rig head instead of the network
  std::map<std::string, double> by_shape;  // --rig-map: the row's weights by the face model's shape names

  State(StreamOptions o, LoadedBundle bundle, const RetargeterOptions& retargeter_options, ArkitFaces f,
        const RigWeightFitOptions& fit_options)
      : options(std::move(o)),
        retargeter(std::move(bundle), retargeter_options),
        faces(std::move(f)),
        fit(*retargeter.bundle().rig, fit_options) {}
};

namespace stream_run_detail {

LoadedBundle load_rig_bundle(const std::string& folder) {
  LoadedBundle bundle = load_bundle(folder);
  if (!bundle.rig || !bundle.metadata.rig)
    throw Error("--stream", fmt::format("{}: this bundle has no rig (format_version {}); the stream writes the avatar "
                                        "rig's weights: re-export it with `retarget export RUN` (format {})",
                                        folder, bundle.metadata.format_version, kBundleFormatVersion));
  return bundle;
}

// The next row to retarget, waiting for it, and the frames dropped before it (--drop: all but the
// newest; --max-latency-ms: those that waited longer); none once the queue has ended empty.
std::optional<Pending> take_next(RowQueue& queue, const StreamOptions& options, std::vector<int>& dropped) {
  std::unique_lock<std::mutex> lock(queue.mutex);
  queue.ready.wait(lock, [&] { return !queue.rows.empty() || queue.ended; });
  if (queue.rows.empty()) return std::nullopt;
  if (options.drop) {
    while (queue.rows.size() > 1) {
      dropped.push_back(queue.rows.front().frame);
      queue.rows.pop_front();
    }
  } else if (options.max_latency_ms > 0) {
    const Clock::time_point now = Clock::now();
    while (queue.rows.size() > 1 && milliseconds(queue.rows.front().arrival, now) > options.max_latency_ms) {
      dropped.push_back(queue.rows.front().frame);
      queue.rows.pop_front();
    }
  }
  Pending next = std::move(queue.rows.front());
  queue.rows.pop_front();
  return next;
}

}  // namespace stream_run_detail

StreamRun::StreamRun(StreamOptions options) {
  using namespace stream_run_detail;
  options.validate();
  const int threads = checked_thread_count(options.threads, "--threads");
  torch::set_num_threads(threads);
  if (options.reuse_memory) reuse_tensor_memory();
  RetargeterOptions retargeter_options;
  retargeter_options.align_to_rest = options.align_to_rest;
  retargeter_options.anchors = options.anchors;
  retargeter_options.part_motion = options.part_motion;
  retargeter_options.threads = threads;
  LoadedBundle bundle = load_rig_bundle(options.bundle);
  ArkitFaces faces =
      load_arkit_faces(options.face_model, options.identity, bundle.human_rest, bundle.metadata.human.units);
  RigWeightFitOptions fit;
  fit.ridge = options.weights_ridge;
  fit.smoothness = options.weights_smoothness;
  const double mm = bundle.metadata.rig->millimetres_per_unit;
  state_ = std::make_unique<State>(std::move(options), std::move(bundle), retargeter_options, std::move(faces), fit);
  State& s = *state_;
  const Rig& rig = *s.retargeter.bundle().rig;
  const ResidualUnit unit = residual_unit(rig, mm);
  s.scale = unit.scale;
  s.residual_unit = unit.name;
  for (const Controller& c : rig.controllers) s.controllers.push_back(c.name);
  s.scratch.source = "stream";
  s.scratch.expressions = s.faces.expression_names();
  s.scratch.weights = Eigen::MatrixXd::Zero(1, static_cast<Eigen::Index>(s.scratch.expressions.size()));
  s.scratch.timecodes = {""};
  s.scratch.lines = {0};
  if (!s.options.rig_map.empty()) {
    s.map = load_controller_map(s.options.rig_map);
    s.map->on_rig({}, rig, s.options.rig_map);  // the map's controllers are the rig's, before any row
    for (const std::string& shape : s.map->shapes)
      if (std::find(s.scratch.expressions.begin(), s.scratch.expressions.end(), shape) == s.scratch.expressions.end())
        throw Error(s.options.rig_map, fmt::format("maps from the shape \"{}\", which the face model {} does not have",
                                                   shape, s.options.face_model));
    for (const std::string& shape : s.scratch.expressions) s.by_shape[shape] = 0;
  }
  // Two frames of the neutral face through the pipeline, so the first live row does not pay for
  // LibTorch's first forwards (allocations, the TorchScript executor's profiling runs).
  const Positions neutral = s.faces.frame(s.scratch, 0);
  for (int k = 0; k < 2; ++k) s.retargeter.retarget({&neutral});
  if (!s.options.meshes.empty()) {
    std::error_code ec;
    fs::create_directories(s.options.meshes, ec);
    if (ec || !fs::is_directory(s.options.meshes))
      throw Error("--stream-meshes",
                  s.options.meshes + ": cannot create the folder" + (ec ? ": " + ec.message() : std::string()));
  }
}

StreamRun::~StreamRun() = default;

const StreamOptions& StreamRun::options() const { return state_->options; }
std::vector<std::string> StreamRun::expressions() const { return state_->faces.expression_names(); }
const std::vector<std::string>& StreamRun::controllers() const { return state_->controllers; }

StreamSummary StreamRun::run(std::istream& in, std::ostream& out) {
  using namespace stream_run_detail;
  State& s = *state_;
  const StreamOptions& options = s.options;
  const Rig& rig = *s.retargeter.bundle().rig;
  const std::string source = options.source.empty() ? "stdin" : options.source;
  StreamSummary summary;
  summary.residual_unit = s.residual_unit;

  // The reader: lines -> rows (parsed here, so a malformed one is reported as it arrives).
  RowQueue queue;
  std::optional<ArkitRowParser> parser;
  std::string fatal;  // a bad header: the stream cannot go on
  int malformed = 0;
  bool incomplete = false;
  if (!options.arkit_columns.empty()) {
    parser.emplace(source, ArkitTakeFormat::csv, s.scratch.expressions);
    try {
      parser->header(options.arkit_columns, 1);
    } catch (const Error& e) {
      throw Error("--arkit-columns", e.detail());
    }
    report_names(*parser);
  }
  std::thread reader([&] {
    std::string text;
    int line = 0, frame = 0;
    for (LineRead read; (read = read_capped_line(in, text)) != LineRead::end;) {
      ++line;
      const Clock::time_point arrival = Clock::now();
      if (read == LineRead::last) {  // no line break: the input closed mid-line
        if (!blank(text)) {
          incomplete = true;
          log::error("{}:{}: the input ended in the middle of the line; not used", source, line);
        }
        break;
      }
      if (!parser) {
        if (blank(text)) continue;
        parser.emplace(source, line_format(text), s.scratch.expressions);
      }
      try {
        const bool had_header = parser->has_header();
        std::optional<ArkitRow> row = parser->row(text, line);
        if (row) queue.push({std::move(*row), frame++, arrival});
        if (!had_header && parser->has_header()) report_names(*parser);
      } catch (const UnreadableTake& e) {
        fatal = e.what();
        break;
      } catch (const Error& e) {
        if (!parser->has_header()) {
          fatal = e.what();
          break;
        }
        ++malformed;
        log::error("{} (row skipped)", e.what());
      } catch (const std::exception& e) {
        ++malformed;
        log::error("{}:{}: {} (row skipped)", source, line, e.what());
      }
    }
    queue.end();
  });

  // The worker: this thread.
  Eigen::VectorXd previous;  // the last frame written's weights (the smoothness term)
  double residual_sum = 0;
  auto write_line = [&](const std::string& line) {
    out << line << '\n';
    out.flush();
    if (!out) summary.output_closed = true;
    return !summary.output_closed;
  };
  try {
    while (!summary.output_closed) {
      std::vector<int> dropped;
      std::optional<Pending> taken = take_next(queue, options, dropped);
      if (!taken) break;
      Pending next = std::move(*taken);
      for (const int frame : dropped) {
        ++summary.dropped;
        if (!write_line(StreamJson{{"frame", frame}, {"dropped", true}}.dump())) break;
      }
      if (summary.output_closed) break;
      if (options.before_frame) options.before_frame(next.frame);

      std::vector<Positions> avatar;
      Eigen::VectorXd weights;
      double residual = 0;
      if (s.map) {  // blendshape animation: the row's weights through the map, the rig's own mesh
        for (size_t k = 0; k < s.scratch.expressions.size(); ++k)
          s.by_shape[s.scratch.expressions[k]] = next.row.weights(static_cast<Eigen::Index>(k));
        weights = s.map->on_rig(s.by_shape, rig);
        if (!options.meshes.empty()) avatar.push_back(rig.evaluate(weights));
      } else {
        s.scratch.weights.row(0) = next.row.weights.transpose();
        const Positions human = s.faces.frame(s.scratch, 0);
        avatar = s.retargeter.retarget({&human});
        weights = s.fit.fit(avatar[0], previous);
        residual = s.fit.residual(avatar[0], weights) * s.scale;
      }
      previous = weights;
      if (!options.meshes.empty()) {
        // A mesh that cannot be written does not hold the weights back: reported, counted, the stream goes on.
        try {
          write_mesh((fs::path(options.meshes) / fmt::format("frame_{:06d}.obj", next.frame)).string(),
                     with_positions(s.retargeter.bundle().avatar_rest, avatar[0]));
        } catch (const std::exception& e) {
          ++summary.meshes_failed;
          log::error("frame {}: {} (its mesh not written)", next.frame, e.what());
        }
      }

      StreamJson named = StreamJson::object();
      for (size_t k = 0; k < s.controllers.size(); ++k) named[s.controllers[k]] = weights(static_cast<Eigen::Index>(k));
      StreamJson line = {{"frame", next.frame}};
      line["timecode"] = next.row.timecode.empty() ? StreamJson(nullptr) : StreamJson(next.row.timecode);
      line["weights"] = std::move(named);
      line["residual_mm"] = residual;
      const double latency = milliseconds(next.arrival, Clock::now());
      line["latency_ms"] = latency;
      if (!write_line(line.dump(-1, ' ', false, StreamJson::error_handler_t::replace))) break;
      ++summary.frames;
      summary.latency_ms.push_back(latency);
      residual_sum += residual;
      summary.residual_max = std::max(summary.residual_max, residual);
    }
  } catch (...) {
    if (auto* socket = dynamic_cast<FdStream*>(&in)) socket->shutdown_read();
    reader.join();
    throw;
  }
  if (summary.output_closed)
    if (auto* socket = dynamic_cast<FdStream*>(&in)) socket->shutdown_read();
  reader.join();
  summary.malformed = malformed;
  summary.incomplete_line = incomplete;
  summary.residual_mean = summary.frames > 0 ? residual_sum / summary.frames : 0;
  if (parser && parser->frames() > 0) {
    // CSV: the names were reported with the header; JSON lines bring theirs line by line.
    ArkitTake reports = parser->reports();
    if (!options.arkit_columns.empty() || reports.format == ArkitTakeFormat::csv) {
      reports.unused.clear();
      reports.missing.clear();
    }
    report_arkit_take(reports);
  }
  if (!fatal.empty()) throw UnreadableTake(fatal + " (the stream ends here: no further line can be read)");
  return summary;
}

StreamSummary StreamRun::serve() {
  const StreamOptions& options = state_->options;
  LoopbackListener listener(std::max(0, options.listen));
  log::info("listening on 127.0.0.1:{} for one client", listener.port());
  if (options.on_listening) options.on_listening(listener.port());
  std::unique_ptr<FdStream> client = listener.accept();
  const std::string previous = state_->options.source;
  if (state_->options.source.empty()) state_->options.source = fmt::format("127.0.0.1:{}", listener.port());
  // Two streams on the connection: the reader thread's end of input must not stop the writes
  // (an ostream does not write once its state is not good()).
  FdStream writer(client->fd(), false);
  StreamSummary summary = run(*client, writer);
  state_->options.source = previous;
  return summary;
}

StreamSummary run_stream(const StreamOptions& options) {
  StreamRun stream(options);
  if (options.listen >= 0) return stream.serve();
  std::ios::sync_with_stdio(false);
  // A reader that goes away is a failed write (the summary still comes), not a killed process.
  std::signal(SIGPIPE, SIG_IGN);
  return stream.run(std::cin, std::cout);
}

}  // namespace retarget
