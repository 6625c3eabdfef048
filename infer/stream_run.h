// Live streaming (retarget-infer --stream): ARKit rows in, one JSON line of avatar controller
// weights out per frame, as soon as it is ready.
//
// Input: the lines of an ARKit take (infer/arkit_take.h, same format and name matching), from
// standard input or one loopback TCP client (infer/stream_socket.h). CSV: the first non-blank line
// is the header (or StreamOptions::arkit_columns gives it and every line is a frame); JSON lines:
// one object per line. The format is the first non-blank line's: '{' JSON lines, else CSV.
// A line counts once its line break arrived: a last line without one (the input closed
// mid-line) is reported and not used.
//
// Each frame: a face of the face model (infer/arkit_faces.h) -> the Retargeter (prefactored once,
// batch 1) -> the bundle rig's weights (geometry/rig_weight_fit.h, as --weights solves them,
// smoothness towards the previous frame written) -> one line, flushed:
//   {"frame":0,"timecode":"12:34:56:07.123","weights":{"bump0":0.41,...},"residual_mm":0.12,"latency_ms":3.2}
// frame: the index of the row among the input's frames (from 0; malformed rows are not frames);
// timecode: as the row has it, null without one; residual_mm: as weights.csv's (mm, or the rig's
// units without a scale); latency_ms: from the row's arrival (its line break read) to the line
// being written. Optionally the avatar mesh too (meshes: DIR/frame_<frame, 6 digits>.obj).
//
// Falling behind: a reader thread queues rows as they arrive; the worker takes them in order, or
// with `drop` the NEWEST waiting row, the older waiting rows dropped; with max_latency_ms, a waiting
// row older than that is dropped when a newer one waits (the newest is always processed). Each
// dropped frame is written as its own line, in frame order before the next processed frame's:
//   {"frame":3,"dropped":true}
//
// Bad input: a malformed row is logged (log::error, "source:line: column N (Name): ...") and
// skipped; the stream goes on; so does a mesh that cannot be written (logged, counted). What
// leaves no further line readable ends the stream (UnreadableTake, infer/arkit_take.h; exit
// status 2): a bad CSV header or one that names no expression of the face model, JSON names none
// of which drives one, bytes that are not text, a line over kMaxTakeLineBytes (1 MiB: the reader
// never holds more of a line than that). End of input (or the
// client closing) ends the stream after the queued rows; a failed write (the reader gone) ends it
// at once. Either way the lines written stay written (each is flushed).
#pragma once

#include <functional>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "infer/arkit_take.h"

namespace retarget {

struct StreamOptions {
  std::string bundle;             // the bundle folder; it must carry a rig (format 3)
  std::string face_model;         // face_model.yaml or its folder: the model the rows drive, required
  std::vector<double> identity;   // the person's identity coefficients (none: the mean face)
  std::string arkit_columns;      // the CSV header given ahead ("Timecode,EyeBlinkLeft,..."); "": read from the input
  int listen = -1;                // a loopback TCP port to accept one client on; -1: stdin / stdout; 0: any free port
  bool drop = false;              // take the newest waiting row, drop the older ones
  double max_latency_ms = 0;      // > 0: drop waiting rows older than this when a newer one waits; 0: off
  std::string meshes;             // also write each frame's avatar mesh here as OBJ (created); "": none
  double weights_ridge = 1e-4;    // WeightsOutputOptions::ridge
  double weights_smoothness = 0;  // WeightsOutputOptions::smoothness (towards the previous frame written)
  // The rig head instead of the network (blendshape animation, the paper's BS): MAP.yaml (retarget
  // rig-map fit) takes each row's weights straight to the rig's controllers; residual_mm is then 0
  // (the rig's own mesh). "": the bundle's network.
  std::string rig_map;
  int threads = 0;            // as retarget-infer --threads; 0 = all cores
  bool align_to_rest = true;  // RetargeterOptions::align_to_rest
  bool anchors = true;        // RetargeterOptions::anchors
  bool part_motion = true;    // RetargeterOptions::part_motion
  bool reuse_memory = true;   // InferOptions::reuse_memory
  std::string source;         // names the input in messages; "": "stdin" or "127.0.0.1:PORT"
  // Tests: called on the worker thread before each frame is processed, with its frame number
  // (a slow worker, to see rows dropped).
  std::function<void(int frame)> before_frame;
  // Tests: called once the listener is bound, with its port (listen = 0 picks a free one).
  std::function<void(int port)> on_listening;

  // Throws retarget::Error naming the option (--bundle, --face-model, --listen, --max-latency-ms,
  // --weights-ridge, --weights-smoothness, --threads).
  void validate() const;
};

struct StreamSummary {
  int frames = 0;                  // lines of weights written
  int dropped = 0;                 // frames dropped (drop / max_latency_ms)
  int malformed = 0;               // rows reported and skipped
  bool incomplete_line = false;    // the input ended mid-line
  int meshes_failed = 0;           // with meshes: frames whose mesh could not be written (logged; their lines were)
  bool output_closed = false;      // a write failed (the reader went away): the stream stopped there
  std::vector<double> latency_ms;  // per frame written, in order
  double residual_mean = 0, residual_max = 0;
  std::string residual_unit;
  // Latency percentiles over latency_ms (nearest rank; 0 without frames).
  double latency_percentile(double p) const;
};

// frames, dropped, malformed; latency p50 / p99 / max, e.g.
//   stream: 300 frames, 12 dropped, 1 malformed; latency p50 4.1 ms, p99 9.8 ms, max 12.3 ms; residual mean 0.2 mm
std::string format_stream_summary(const StreamSummary& summary);

// The prepared pipeline: bundle loaded, Retargeter factorised, rig fit set up, face model checked,
// the network warmed up (two neutral frames), once; then any number of streams.
class StreamRun {
 public:
  // Throws retarget::Error for bad options, a bundle that does not load or has no rig, a face
  // model the bundle cannot take.
  explicit StreamRun(StreamOptions options);
  ~StreamRun();

  const StreamOptions& options() const;
  std::vector<std::string> expressions() const;         // the face model's, in its order
  const std::vector<std::string>& controllers() const;  // the rig's controller names: the weights' keys

  // One stream: rows from `in`, lines to `out` (two stream objects, even on one socket: a reader
  // thread reads `in` while this one writes `out`; each line flushed), until the end of `in`. The
  // smoothness term starts afresh. Throws retarget::Error for a bad CSV header.
  StreamSummary run(std::istream& in, std::ostream& out);

  // options.listen: accepts one client on 127.0.0.1 and runs its stream on the connection.
  StreamSummary serve();

 private:
  struct State;
  std::unique_ptr<State> state_;
};

// StreamRun(options) then serve() (listen >= 0) or run(std::cin, std::cout) (SIGPIPE ignored, so
// that a reader of stdout going away ends the stream with its summary).
StreamSummary run_stream(const StreamOptions& options);

}  // namespace retarget
