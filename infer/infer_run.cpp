#include "infer/infer_run.h"

#include <fmt/format.h>
#include <omp.h>
#include <torch/torch.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <thread>
#include <utility>

#include "bundle/bundle_format.h"
#include "core/atomic_file.h"
#include "core/cpu_threads.h"
#include "core/error.h"
#include "core/log.h"
#include "core/progress.h"
#include "core/timer.h"
#include "geometry/face_model.h"
#include "geometry/mesh_io.h"
#include "geometry/mesh_validation.h"
#include "infer/arkit_faces.h"
#include "infer/arkit_take.h"
#include "infer/gltf_animation.h"
#include "infer/input_files.h"
#include "infer/memory_reuse.h"
#include "infer/retargeter.h"
#include "infer/weights_output.h"
#include "render/animation.h"
#include "render/render.h"

namespace retarget {

namespace {

namespace fs = std::filesystem;

// 11248 -> "11,248"
std::string grouped(int64_t n) {
  std::string digits = std::to_string(n < 0 ? -n : n), out;
  for (size_t i = 0; i < digits.size(); ++i) {
    if (i > 0 && (digits.size() - i) % 3 == 0) out += ',';
    out += digits[i];
  }
  return n < 0 ? "-" + out : out;
}

// One input on its way through the pipeline.
struct Item {
  std::string input;  // the file (or the pattern / folder that gave none)
  std::string output;
  std::string picture;  // with --render
  std::string problem;  // non-empty: failed
  int frame = -1;       // with arkit: the take's frame (from 0) the mesh is made from
  Mesh mesh;
};

// The name of an item's outputs: the input's stem, or frame_<index> for a take's frame.
std::string item_name(const Item& item) {
  return item.frame >= 0 ? fmt::format("frame_{:06d}", item.frame) : fs::path(item.input).stem().string();
}

// What the topology check says about a mesh of another face than the bundle's.
void require_bundle_topology(const Mesh& mesh, const LoadedBundle& bundle) {
  const Mesh& rest = bundle.human_rest;
  const std::string name = bundle.metadata.human.name;
  if (mesh.vertex_count() != rest.vertex_count()) {
    throw Error(mesh.source, "has " + grouped(mesh.vertex_count()) + " vertices but the bundle's human topology ('" +
                                 name + "') has " + grouped(rest.vertex_count()) +
                                 "; only meshes of that topology can be retargeted");
  }
  if (mesh.faces.size() != rest.faces.size()) {
    throw Error(mesh.source, "has " + grouped(mesh.faces.size()) + " faces but the bundle's human topology ('" + name +
                                 "') has " + grouped(rest.faces.size()) + " (both have " +
                                 grouped(rest.vertex_count()) + " vertices)");
  }
  require_same_topology(rest, mesh);  // the same faces, vertex for vertex
}

}  // namespace

int infer_threads(int threads) { return checked_thread_count(threads, "--threads"); }

namespace {

// Paths of the outputs; an output name already taken by an earlier input is a problem.
void assign_outputs(std::vector<Item>& items, const InferOptions& options) {
  std::map<std::string, std::string> taken;  // output path -> input
  const fs::path out(options.out);
  for (Item& item : items) {
    if (!item.problem.empty()) continue;
    const std::string stem = fs::path(item.input).stem().string();
    item.output = (out / (stem + "." + options.format)).string();
    if (options.render) item.picture = (out / (stem + ".png")).string();
    const auto [it, inserted] = taken.emplace(item.output, item.input);
    if (!inserted) {
      item.problem = item.input + ": its output " + item.output + " would replace that of " + it->second +
                     " (inputs with the same name from different folders); rename one";
    }
  }
}

// The boxes the camera frames on each side of an animation, fixed for the whole sequence.
struct SequenceFraming {
  Eigen::AlignedBox3d human, avatar;
};

// From the first frame: its human mesh, and the avatar's rest and first output, each box grown by
// a tenth of its size on every side, so that later expressions (an opening jaw) stay in view.
SequenceFraming sequence_framing(const Mesh& human, const Mesh& avatar_rest, const Positions& avatar) {
  auto grown = [](Eigen::AlignedBox3d box) {
    const Eigen::Vector3d pad = 0.1 * box.sizes();
    return Eigen::AlignedBox3d(box.min() - pad, box.max() + pad);
  };
  Eigen::AlignedBox3d avatar_box = frame_box(avatar_rest.vertices);
  avatar_box.extend(frame_box(avatar));
  return {grown(frame_box(human.vertices)), grown(avatar_box)};
}

// input | output, 2 x 384 pixels wide with captions. Each side framed by its own mesh, or with
// `framing` by the sequence's boxes (the same picture otherwise).
Image side_by_side(const Mesh& input, const Mesh& avatar_rest, const Positions& output, const std::string& caption,
                   const std::string& avatar_name, const SequenceFraming* framing = nullptr) {
  GridOptions grid;
  grid.render.width = grid.render.height = 384;
  grid.share_frame = false;  // two meshes in their own units and frames
  std::vector<GridCell> cells(2);
  cells[0].mesh = std::shared_ptr<const Mesh>(&input, [](const Mesh*) {});
  cells[0].caption = "input: " + caption;
  cells[1].mesh = std::shared_ptr<const Mesh>(&avatar_rest, [](const Mesh*) {});
  cells[1].vertices = output;
  cells[1].caption = "output: " + avatar_name;
  if (!framing) return render_grid(cells, 2, grid);
  // One grid per side, each with its box (a grid frames all its cells with one box).
  grid.render.frame = framing->human;
  const Image human = render_grid({cells[0]}, 1, grid);
  grid.render.frame = framing->avatar;
  const Image avatar = render_grid({cells[1]}, 1, grid);
  return hconcat({human, avatar}, grid.render.background);
}

std::string error_text(const std::exception& e) { return e.what(); }

// --arkit: the take and the faces its frames become, the face model checked against the bundle.
struct ArkitInput {
  ArkitFaces faces;
  ArkitTake take;
};

ArkitInput load_arkit_input(const InferOptions& options, const LoadedBundle& bundle) {
  ArkitFaces faces =
      load_arkit_faces(options.face_model, options.identity, bundle.human_rest, bundle.metadata.human.units);
  ArkitTake take = read_arkit_take(options.arkit, faces.expression_names());
  log::info("{}: {} frames through the face model {} ({} of its {} expressions driven)", take.source, take.frames(),
            faces.model().source, take.expressions.size() - take.missing.size(), take.expressions.size());
  return {std::move(faces), std::move(take)};
}

// One item per frame of the take: OUT/frame_<index>.<format>.
std::vector<Item> arkit_items(const ArkitTake& take, const InferOptions& options) {
  std::vector<Item> items(take.frames());
  const fs::path out(options.out);
  for (int f = 0; f < take.frames(); ++f) {
    Item& item = items[f];
    item.frame = f;
    item.input = fmt::format("{} frame {} (line {})", take.source, f, take.lines[f]);
    item.output = (out / (item_name(item) + "." + options.format)).string();
    if (options.render) item.picture = (out / (item_name(item) + ".png")).string();
  }
  return items;
}

WeightsOutputOptions weights_output_options(const InferOptions& options) {
  WeightsOutputOptions w;
  w.ridge = options.weights_ridge;
  w.smoothness = options.weights_smoothness;
  w.csv = options.weights_format != "jsonl";
  w.jsonl = options.weights_format != "csv";
  return w;
}

// --weights needs the avatar's rig, which bundles carry from format 3 on (when it loaded at export).
void require_rig(const LoadedBundle& bundle, const std::string& folder) {
  if (bundle.rig) return;
  throw Error("--weights", fmt::format("{}: this bundle has no rig (format_version {}); re-export it with `retarget "
                                       "export RUN` from its translation run (this build writes format {}, with the "
                                       "avatar dataset's rig when that still loads), or leave out --weights",
                                       folder, bundle.metadata.format_version, kBundleFormatVersion));
}

}  // namespace

void InferOptions::validate() const {
  if (bundle.empty()) throw Error("--bundle", "give the bundle folder");
  if (arkit.empty()) {
    if (!face_model.empty()) throw Error("--face-model", "only with --arkit");
    if (!identity.empty()) throw Error("--identity", "only with --arkit");
    if (inputs.empty()) throw Error("retarget-infer", "give at least one input mesh, folder or pattern");
  } else {
    if (!inputs.empty())
      throw Error("--arkit", "a take takes the place of input meshes; give the take or meshes, not both");
    if (face_model.empty())
      throw Error("--face-model",
                  "give the face model the take's weights drive (face_model.yaml or its folder), the one the "
                  "bundle's human dataset was made from; bundles do not record it");
  }
  if (out.empty()) throw Error("--out", "give the output folder");
  if (format != "obj" && format != "ply") throw Error("--format", "expected obj or ply, got \"" + format + "\"");
  if (batch < 1) throw Error("--batch", "expected a batch size >= 1, got " + std::to_string(batch));
  checked_thread_count(threads, "--threads");
  if (weights_format != "csv" && weights_format != "jsonl" && weights_format != "both")
    throw Error("--weights-format", "expected csv, jsonl or both, got \"" + weights_format + "\"");
  weights_output_options(*this).validate();
  if (!gltf.empty()) {
    if (!weights) throw Error("--gltf", "the animation plays the solved controller weights: give --weights too");
    const std::string ext = fs::path(gltf).extension().string();
    if (ext != ".glb" && ext != ".gltf")
      throw Error("--gltf", "expected a .glb or .gltf file name, got \"" + gltf + "\"");
  }
  if (!(fps > 0) || !std::isfinite(fps))
    throw Error("--fps", fmt::format("expected frames per second > 0, got {}", fps));
  if (!animation.empty()) {
    animation_format(animation, "--animation");
    if (!(fps >= 0.1 && fps <= 240))
      throw Error("--fps", fmt::format("with --animation: expected 0.1 to 240 frames per second, got {}", fps));
  }
}

namespace {

RetargeterOptions retargeter_options(const InferOptions& options, int threads) {
  RetargeterOptions out;
  out.align_to_rest = options.align_to_rest;
  out.anchors = options.anchors;
  out.part_motion = options.part_motion;
  out.precision = options.precision;
  out.threads = threads;
  return out;
}

// The animation's encoder is checked now (for .mp4: that ffmpeg is there), written from the first
// frame on; none without --animation.
void open_animation(const InferOptions& options, std::optional<AnimationWriter>& animation) {
  if (!options.animation.empty()) {
    AnimationOptions animation_options;
    animation_options.fps = options.fps;
    animation.emplace(options.animation, animation_options);
  }
}

void make_output_folder(const std::string& out) {
  std::error_code ec;
  fs::create_directories(out, ec);
  if (ec || !fs::is_directory(out)) {
    throw Error(out, "cannot create the output folder" + (ec ? ": " + ec.message() : std::string()));
  }
}

// The run's items: the take's frames (its frames.csv written into the output folder), or the
// input files with their outputs.
std::vector<Item> input_items(const InferOptions& options, const std::optional<ArkitInput>& arkit) {
  std::vector<Item> items;
  if (arkit) {
    items = arkit_items(arkit->take, options);
    write_file_atomically((fs::path(options.out) / "frames.csv").string(),
                          [&](std::ostream& out) { out << arkit_frames_csv(arkit->take); });
    return items;
  }
  for (InputFile& file : expand_inputs(options.inputs)) {
    Item item;
    item.input = std::move(file.path);
    if (!file.problem.empty()) item.problem = item.input + ": " + file.problem;
    items.push_back(std::move(item));
  }
  assign_outputs(items, options);
  return items;
}

// The batches of one run, in input order: read, compute, write, and whatever else the options
// ask for (pictures, an animation, weights), each step timed into the summary.
struct BatchLoop {
  const InferOptions& options;
  const int threads;
  Retargeter& retargeter;
  const std::optional<ArkitInput>& arkit;
  std::vector<Item>& items;
  std::optional<AnimationWriter>& animation;
  std::optional<WeightsOutput>& weights;
  std::vector<Eigen::VectorXd>& frame_weights;  // with gltf: every frame's, in order
  InferSummary& summary;
  Progress& progress;
  Stopwatch clock;
  std::optional<SequenceFraming> framing;  // from the first frame written
  // Plain runs (no pictures, animation or weights, not strict) write each batch's meshes on a
  // thread of their own while the next batch is read and computed: the writes wait on the disk,
  // not on the CPU, and the batch's files are flushed to it at once (a FlushGroup: one syncfs, not
  // an fsync per file, whose interrupts slowed the next batch's features); the batch's frames are
  // counted when its writes end. On the 2-core AMD EPYC with 2 threads each step gained 5-10%
  // (docs/experiments/2026-11-29-writes-behind.md); an earlier build, whose OpenMP threads spun
  // while they waited, lost with writes behind (25 -> 20 frames/s). Reading the next batch on a
  // thread of its own costs the network more than it saves: the reader preempts OpenMP's threads,
  // which then wait for each other (measured there).
  bool overlap_writes = false;
  std::thread writer;
  std::vector<int> writing;  // the items the writer has

  BatchLoop(const InferOptions& options, int threads, Retargeter& retargeter, const std::optional<ArkitInput>& arkit,
            std::vector<Item>& items, std::optional<AnimationWriter>& animation, std::optional<WeightsOutput>& weights,
            std::vector<Eigen::VectorXd>& frame_weights, InferSummary& summary, Progress& progress)
      : options(options),
        threads(threads),
        retargeter(retargeter),
        arkit(arkit),
        items(items),
        animation(animation),
        weights(weights),
        frame_weights(frame_weights),
        summary(summary),
        progress(progress) {}
  BatchLoop(const BatchLoop&) = delete;
  BatchLoop& operator=(const BatchLoop&) = delete;
  ~BatchLoop() {
    if (writer.joinable()) writer.join();
  }
  const LoadedBundle& bundle() const { return retargeter.bundle(); }
  InferTimings& t() { return summary.seconds; }

  void run() {
    overlap_writes = !options.render && !animation && !weights && !options.strict;
    const int count = summary.inputs;
    for (int begin = 0; begin < count && !summary.stopped; begin += options.batch) {
      const int end = std::min(count, begin + options.batch);
      clock.restart();
      read(begin, end);
      t().read += clock.restart();
      const std::vector<int> good = good_items(begin, end);
      if (!good.empty()) retarget_batch(good);
      progress.advance(end - begin);
    }
    clock.restart();
    count_written();
    t().write += clock.restart();
  }

  void read(int begin, int end) {
#pragma omp parallel for num_threads(threads) schedule(dynamic, 1)
    for (int i = begin; i < end; ++i) {
      Item& item = items[i];
      if (!item.problem.empty()) continue;
      try {
        item.mesh = item.frame >= 0 ? arkit->faces.mesh(arkit->take, item.frame) : read_mesh(item.input);
        require_bundle_topology(item.mesh, bundle());
      } catch (const std::exception& e) {
        item.problem = error_text(e);
      }
    }
  }

  // Failures in input order; with strict, nothing after the first one runs.
  void fail(Item& item) {
    summary.failures.push_back({item.input, item.problem});
    item.mesh = Mesh();
    if (options.strict) {
      summary.stopped = true;
      log::error("{} (stopping: --strict)", item.problem);
    } else {
      log::error("{} (skipped)", item.problem);
    }
  }

  // The batch's items that were read; the others fail.
  std::vector<int> good_items(int begin, int end) {
    // (A failed read waits for the previous batch's writes, which come first.)
    for (int i = begin; i < end; ++i)
      if (!items[i].problem.empty()) {
        count_written();
        break;
      }
    std::vector<int> good;
    for (int i = begin; i < end; ++i) {
      if (items[i].problem.empty()) {
        good.push_back(i);
        continue;
      }
      fail(items[i]);
      if (summary.stopped) break;
    }
    return good;
  }

  // Waits for the writer and counts what it wrote.
  void count_written() {
    if (!writer.joinable()) return;
    writer.join();
    for (const int i : writing) {
      Item& item = items[i];
      if (!item.problem.empty()) {
        summary.failures.push_back({item.input, item.problem});
        log::error("{} (skipped)", item.problem);
      } else {
        summary.outputs.push_back(item.output);
        ++summary.done;
      }
      item.mesh = Mesh();
    }
    writing.clear();
  }

  void retarget_batch(const std::vector<int>& good) {
    const int n = static_cast<int>(good.size());
    std::vector<const Positions*> human(n);
    for (int k = 0; k < n; ++k) human[k] = &items[good[k]].mesh.vertices;
    clock.restart();
    const torch::Tensor x = retargeter.features(human);
    t().features += clock.restart();
    const torch::Tensor y = retargeter.translate(x);
    t().network += clock.restart();
    std::vector<Positions> avatar = retargeter.reconstruct(y);
    t().reconstruction += clock.restart();
    if (overlap_writes) {
      write_in_background(good, std::move(avatar));
      return;
    }
    write_meshes(good, avatar);
    if (options.render) render_pictures(good, avatar);
    if (animation) add_animation_frames(good, avatar);
    if (weights) add_weights(good, avatar);
    count_batch(good);
  }

  void write_in_background(const std::vector<int>& good, std::vector<Positions> avatar) {
    count_written();  // the previous batch's
    t().write += clock.restart();
    writing = good;
    writer = std::thread([&items = items, &bundle = bundle(), good, avatar = std::move(avatar)] {
      FlushGroup group;  // the batch's files flushed to disk at once, then moved into place
      for (size_t k = 0; k < good.size(); ++k) {
        Item& item = items[good[k]];
        try {
          write_mesh(item.output, with_positions(bundle.avatar_rest, avatar[k]), MeshWriteOptions());
        } catch (const std::exception& e) {
          item.problem = error_text(e);
        }
      }
      for (const auto& [path, message] : group.commit())
        for (const int i : good)
          if (items[i].output == path) items[i].problem = message;
    });
  }

  void write_meshes(const std::vector<int>& good, const std::vector<Positions>& avatar) {
    const int n = static_cast<int>(good.size());
    MeshWriteOptions write_options;
#pragma omp parallel for num_threads(threads) schedule(dynamic, 1)
    for (int k = 0; k < n; ++k) {
      Item& item = items[good[k]];
      try {
        write_mesh(item.output, with_positions(bundle().avatar_rest, avatar[k]), write_options);
      } catch (const std::exception& e) {
        item.problem = error_text(e);
      }
    }
    t().write += clock.restart();
  }

  void render_pictures(const std::vector<int>& good, const std::vector<Positions>& avatar) {
    const int n = static_cast<int>(good.size());
#pragma omp parallel for num_threads(threads) schedule(dynamic, 1)
    for (int k = 0; k < n; ++k) {
      Item& item = items[good[k]];
      if (!item.problem.empty()) continue;
      try {
        write_png(item.picture, side_by_side(item.mesh, bundle().avatar_rest, avatar[k],
                                             fs::path(item.input).filename().string(), summary.avatar));
      } catch (const std::exception& e) {
        item.problem = error_text(e);
      }
    }
    t().render += clock.restart();
  }

  // The animation's frames of this batch, drawn in parallel, added in input order.
  void add_animation_frames(const std::vector<int>& good, const std::vector<Positions>& avatar) {
    const int n = static_cast<int>(good.size());
    for (int k = 0; k < n && !framing; ++k) {
      const Item& item = items[good[k]];
      if (item.problem.empty()) framing = sequence_framing(item.mesh, bundle().avatar_rest, avatar[k]);
    }
    std::vector<Image> frames(n);
#pragma omp parallel for num_threads(threads) schedule(dynamic, 1)
    for (int k = 0; k < n; ++k) {
      Item& item = items[good[k]];
      if (!item.problem.empty()) continue;
      try {
        frames[k] = side_by_side(item.mesh, bundle().avatar_rest, avatar[k], fs::path(item.input).filename().string(),
                                 summary.avatar, &*framing);
      } catch (const std::exception& e) {
        item.problem = error_text(e);
      }
    }
    // A failure of the encoder (ffmpeg stopped, disk full) ends the run: the file cannot go on.
    for (int k = 0; k < n; ++k)
      if (items[good[k]].problem.empty()) animation->add(frames[k]);
    t().render += clock.restart();
  }

  // Weights in input order (the smoothness term needs the previous frame), for the frames
  // written. A failure here stops the run: the rows would no longer follow the frames.
  void add_weights(const std::vector<int>& good, const std::vector<Positions>& avatar) {
    for (size_t k = 0; k < good.size(); ++k) {
      const Item& item = items[good[k]];
      if (!item.problem.empty()) continue;
      const FrameWeights w = weights->add(item_name(item), avatar[k]);
      if (!options.gltf.empty()) frame_weights.push_back(w.weights);
    }
    t().weights += clock.restart();
  }

  // Every frame of the batch was written (or failed) by now, so all are counted, even with
  // strict after a failed write.
  void count_batch(const std::vector<int>& good) {
    for (const int i : good) {
      Item& item = items[i];
      if (!item.problem.empty()) {
        fail(item);
      } else {
        summary.outputs.push_back(item.output);
        ++summary.done;
      }
      item.mesh = Mesh();  // the batch's meshes are not needed any more
    }
  }
};

// Closes the animation and the weights (and writes the glTF animation from them).
void finish_outputs(const InferOptions& options, const LoadedBundle& bundle, std::optional<AnimationWriter>& animation,
                    std::optional<WeightsOutput>& weights, std::vector<Eigen::VectorXd> frame_weights,
                    const GltfAnimationOptions& gltf_options, InferSummary& summary) {
  InferTimings& t = summary.seconds;
  Stopwatch clock;
  if (animation && animation->frames() > 0) {
    clock.restart();
    animation->finish();
    summary.animation = options.animation;
    summary.animation_frames = animation->frames();
    summary.animation_fps = options.fps;
    t.render += clock.restart();
  }
  if (!weights) return;
  clock.restart();
  weights->finish();
  t.weights += clock.restart();
  summary.weight_files = weights->files();
  summary.weight_frames = weights->frames();
  summary.residual_mean = weights->residual_mean();
  summary.residual_max = weights->residual_max();
  summary.residual_unit = weights->residual_unit();
  if (!options.gltf.empty() && !frame_weights.empty()) {
    write_gltf_animation(gltf_animation_input(*bundle.rig, std::move(frame_weights)), gltf_options, options.gltf);
    summary.gltf = options.gltf;
    t.weights += clock.restart();
  }
}

}  // namespace

InferSummary run_inference(const InferOptions& options) {
  const Stopwatch whole;
  options.validate();
  InferSummary summary;
  summary.out = options.out;
  const int threads = infer_threads(options.threads);
  torch::set_num_threads(threads);  // LibTorch's intra-op threads, OpenMP's and so OpenBLAS's
  if (options.reuse_memory) reuse_tensor_memory();

  // Each check refuses a bad input before the output folder is made.
  Stopwatch clock;
  LoadedBundle loaded = load_bundle(options.bundle);
  if (options.weights) require_rig(loaded, options.bundle);
  GltfAnimationOptions gltf_options;
  gltf_options.fps = options.fps;
  if (!options.gltf.empty()) gltf_scale_to_metres(loaded.rig->units, gltf_options);  // unknown units: refused now
  std::optional<AnimationWriter> animation;
  open_animation(options, animation);
  Retargeter retargeter(std::move(loaded), retargeter_options(options, threads));
  const LoadedBundle& bundle = retargeter.bundle();
  summary.avatar = bundle.metadata.avatar.name;
  summary.avatar_vertices = retargeter.avatar_vertices();
  std::optional<ArkitInput> arkit;  // the face model and the take
  if (!options.arkit.empty()) {
    arkit.emplace(load_arkit_input(options, bundle));
    summary.take = arkit->take.source;
  }
  make_output_folder(options.out);
  std::vector<Item> items = input_items(options, arkit);
  summary.inputs = static_cast<int>(items.size());
  std::optional<WeightsOutput> weights;  // the Gram matrix is computed here, once
  std::vector<Eigen::VectorXd> frame_weights;
  if (options.weights)
    weights.emplace(*bundle.rig, bundle.metadata.rig->millimetres_per_unit, options.out,
                    weights_output_options(options));
  summary.seconds.setup = clock.restart();

  Progress progress(arkit ? "frames" : "inputs", summary.inputs, options.progress);
  {
    BatchLoop batches(options, threads, retargeter, arkit, items, animation, weights, frame_weights, summary, progress);
    batches.run();
  }
  progress.finish();
  finish_outputs(options, bundle, animation, weights, std::move(frame_weights), gltf_options, summary);
  summary.seconds.total = whole.seconds();
  return summary;
}

std::string format_summary(const InferSummary& s) {
  std::string text =
      fmt::format("{} of {} {} done, {} failed -> {} (avatar '{}', {} vertices)\n", s.done, s.inputs,
                  s.take.empty() ? "files" : "frames", s.failed(), s.out, s.avatar, grouped(s.avatar_vertices));
  if (!s.take.empty())
    text += fmt::format("  frames of the take {}; their timecodes in {}/frames.csv\n", s.take, s.out);
  const InferTimings& t = s.seconds;
  auto line = [&](const char* stage, double seconds) {
    text += fmt::format("  {:<16}{:>9.3f} s {:>10.1f} frames/s\n", stage, seconds, s.frames_per_second(seconds));
  };
  text += fmt::format("  {:<16}{:>9.3f} s {:>10.1f} frames/s  (setup {:.3f} s: bundle, DR setup, factorisation)\n",
                      "whole run", t.total, s.frames_per_second(t.total), t.setup);
  line("read", t.read);
  line("DR features", t.features);
  line("network", t.network);
  line("reconstruction", t.reconstruction);
  line("write", t.write);
  if (t.render > 0) line("render", t.render);
  if (!s.animation.empty())
    text += fmt::format("animation: {} ({} frame{}, {} at {} fps)\n", s.animation, s.animation_frames,
                        s.animation_frames == 1 ? "" : "s", animation_format_name(animation_format(s.animation)),
                        s.animation_fps);
  if (!s.weight_files.empty()) {
    line("weights", t.weights);
    std::string files;
    for (const std::string& f : s.weight_files) files += (files.empty() ? "" : ", ") + f;
    text +=
        fmt::format("weights: {} ({} frame{}); residual mean {:.4g} {}, max {:.4g} {}\n", files, s.weight_frames,
                    s.weight_frames == 1 ? "" : "s", s.residual_mean, s.residual_unit, s.residual_max, s.residual_unit);
    if (!s.gltf.empty()) text += fmt::format("animation: {} (glTF morph-target weights)\n", s.gltf);
  }
  if (s.failed() > 0) {
    text += fmt::format("{} input{} failed{}:\n", s.failed(), s.failed() == 1 ? "" : "s",
                        s.stopped ? " (stopped there: --strict)" : "");
    for (const InferFailure& f : s.failures) text += "  " + f.message + "\n";
  }
  return text;
}

}  // namespace retarget
