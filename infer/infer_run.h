// One retarget-infer run: human mesh files -> avatar mesh files through a bundle, in batches.
//
// Per batch: read the meshes (in parallel) and check each against the bundle's human topology;
// DR features against the bundle's human rest (parallel over meshes); one bundle.pt forward
// under torch::InferenceMode; reconstruction with the avatar's prefactored solver (parallel over
// frames), aligned to the avatar rest pose unless told otherwise; write OUT/<input stem>.<format>
// with the avatar's own faces (atomic writes, in parallel); optionally OUT/<input stem>.png
// (input | output side by side). A file that fails (unreadable, another topology, an output name
// taken by an earlier input, a write error) is reported and skipped; with `strict` the run stops
// at the first such file instead. Outputs keep the inputs' order and names.
// With `weights`, each frame written is also solved for the avatar rig's controller weights, in
// input order (infer/weights_output.h): OUT/weights.csv and OUT/weights.jsonl, appended as frames
// complete and renamed into place at the end of the run.
// With `arkit`, the inputs are the frames of an ARKit take (infer/arkit_take.h) instead of mesh
// files: each frame a face of `face_model` (infer/arkit_faces.h; the model is checked against the
// bundle's human rest and the take read before anything is written), written
// OUT/frame_<index, 6 digits>.<format> (and .png), with OUT/frames.csv (frame, timecode).
// With `animation`, the frames written also become one animation (render/animation.h: .mp4
// through ffmpeg, .gif, .png/.apng) of human | avatar pictures like --render's, one frame per
// input written, in input order, at `fps`; each side framed once for the whole sequence (from
// the first frame, with room to move) so that the heads do not jump. Streamed: each batch's
// pictures go to the encoder as the batch completes; the file is renamed into place at the end.
#pragma once

#include <cstdint>
#include <iostream>
#include <string>
#include <vector>

#include "infer/network_precision.h"

namespace retarget {

struct InferOptions {
  std::string bundle;               // the bundle folder (bundle/bundle_format.h), required
  std::vector<std::string> inputs;  // mesh files, folders and glob patterns (infer/input_files.h), >= 1
  // Or an ARKit take in their place (a Live Link Face .csv or .jsonl), whose frames become faces of
  // `face_model` (face_model.yaml or its folder, required: bundles do not record theirs), the mean
  // face or the person of `identity` (coefficients, at most one per identity mode).
  std::string arkit;
  std::string face_model;
  std::vector<double> identity;
  std::string out;             // output folder, created if needed, required
  std::string format = "obj";  // of the output meshes: "obj" or "ply" (binary)
  bool strict = false;         // stop at the first input that fails
  // Frames per network forward, >= 1. Memory grows with it (an 11k-vertex human: about 130 MB
  // a frame); speed barely does (measured: batch 4, 16 and 32 within 5%).
  int batch = 8;
  int threads = 0;            // CPU threads for every stage (and LibTorch's); 0 = all cores
  bool render = false;        // also OUT/<stem>.png: input | output
  bool align_to_rest = true;  // rigidly align outputs to the avatar rest pose
  bool anchors = true;        // hold the avatar's still vertices at rest (RetargeterOptions::anchors)
  bool part_motion = true;    // move the rigid parts with the rig (RetargeterOptions::part_motion)
  // The network products' precision where the CPU has it (RetargeterOptions::precision).
  NetworkPrecision precision = NetworkPrecision::float32;
  // Give LibTorch a CPU allocator that keeps freed large blocks for the next batch
  // (infer/memory_reuse.h; process-wide, stays installed): about 3x faster network passes.
  bool reuse_memory = true;
  // Also write the avatar's controller weights per frame (needs a bundle with a rig, format 3).
  bool weights = false;
  double weights_ridge = 1e-4;          // towards the neutral, >= 0 (WeightsOutputOptions::ridge)
  double weights_smoothness = 0;        // towards the previous frame, >= 0 (WeightsOutputOptions::smoothness)
  std::string weights_format = "both";  // "csv", "jsonl" or "both"
  // With weights: also the frames' weights as a glTF 2.0 animation of the avatar's morph targets
  // (infer/gltf_animation.h), .glb or .gltf; frame k at k / fps seconds. Empty: none.
  std::string gltf;
  // The human | avatar pictures of the frames written as one animation (render/animation.h), by
  // extension: .mp4 (needs the ffmpeg program), .gif or .png/.apng; frame k at k / fps seconds.
  // Empty: none.
  std::string animation;
  double fps = 30;                      // > 0; with animation, 0.1 to 240
  std::ostream* progress = &std::cerr;  // progress bar (nullptr: none)

  void validate() const;  // throws retarget::Error naming the option ("--batch", "--weights-ridge", ...)
};

// Wall-clock seconds of each stage, summed over the batches.
struct InferTimings {
  double setup = 0;           // bundle load, DR setup, reconstruction factorisation, output folder
  double read = 0;            // reading and checking the input meshes
  double features = 0;        // human DR features
  double network = 0;         // bundle.pt forwards
  double reconstruction = 0;  // avatar positions from DR features
  double write = 0;           // output meshes
  double render = 0;          // pictures (with render or animation only), the animation's encoding too
  double weights = 0;         // controller weights and their files (with weights only)
  double total = 0;           // the whole run_inference call
};

struct InferFailure {
  std::string input;    // the file (or the pattern / folder that gave none)
  std::string message;  // what went wrong, naming the file
};

struct InferSummary {
  std::string out;     // the output folder
  std::string take;    // with arkit: the take (the inputs are its frames)
  std::string avatar;  // the bundle's avatar name
  int avatar_vertices = 0;
  int inputs = 0;                    // entries after expanding folders and patterns
  int done = 0;                      // outputs written
  std::vector<std::string> outputs;  // their paths, in input order
  std::vector<InferFailure> failures;
  bool stopped = false;  // strict: the run stopped at the first failure
  InferTimings seconds;
  // With weights: the files written, the frames solved (= done) and their residuals.
  std::vector<std::string> weight_files;
  int weight_frames = 0;
  double residual_mean = 0, residual_max = 0;
  std::string residual_unit;  // "mm", or the avatar's units when the bundle has no mm scale
  std::string gltf;           // with gltf: the animation written
  std::string animation;      // with animation: the file written ("" when no frame was)
  int animation_frames = 0;   // its frames (= done)
  double animation_fps = 0;   // and their rate

  int failed() const { return static_cast<int>(failures.size()); }
  // Frames per second of a stage (or of the whole run: seconds.total) over the frames done.
  double frames_per_second(double stage_seconds) const { return stage_seconds > 0 ? done / stage_seconds : 0; }
};

// Runs the pipeline above. Failures of single inputs are collected in the summary (and logged as
// errors as they happen); throws retarget::Error for invalid options, a bundle that does not load
// (load_bundle's messages), weights from a bundle without a rig (before any work) and an output
// folder that cannot be created.
InferSummary run_inference(const InferOptions& options);

// The thread count run_inference uses for InferOptions::threads: `threads` itself if positive,
// else every CPU this process may run on (core/cpu_threads.h: checked_thread_count; throws
// retarget::Error naming --threads above 4 per CPU). LibTorch's own default can be lower (1 on
// VMs whose vCPUs look like threads of one core).
int infer_threads(int threads);

// The summary for people: files done and failed, then frames per second for the whole run and
// for each stage, e.g.
//   300 of 300 files done, 0 failed -> out/ (avatar 'lapin', 2,562 vertices)
//   whole run        12.31 s   24.4 frames/s   (setup 0.52 s)
//   read              0.61 s    492 frames/s
//   ...
//   weights: out/weights.csv, out/weights.jsonl (300 frames); residual mean 0.21 mm, max 0.64 mm
//   animation: take.mp4 (300 frames, MP4 at 30 fps)
std::string format_summary(const InferSummary& summary);

}  // namespace retarget
