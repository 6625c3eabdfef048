#include "infer/rig_head_run.h"

#include <fmt/format.h>

#include <filesystem>
#include <map>
#include <memory>
#include <optional>

#include "bundle/bundle_format.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/timer.h"
#include "geometry/controller_map.h"
#include "geometry/face_model_fit.h"
#include "geometry/mesh_io.h"
#include "geometry/mesh_validation.h"
#include "infer/arkit_faces.h"
#include "infer/arkit_take.h"
#include "infer/gltf_animation.h"
#include "infer/input_files.h"

namespace retarget {

namespace fs = std::filesystem;

// Named, not anonymous: a unity batch shares one anonymous namespace among its files.
namespace rig_head_run_detail {

// One frame to write: its output name (without extension) and its blendshape weights by name.
struct Frame {
  std::string name;
  std::map<std::string, double> weights;
};

// The frames of a take: its weights as the face model's expressions name them.
std::vector<Frame> take_frames(const ArkitTake& take) {
  std::vector<Frame> frames(static_cast<size_t>(take.frames()));
  for (int f = 0; f < take.frames(); ++f) {
    frames[static_cast<size_t>(f)].name = fmt::format("frame_{:06d}", f);
    for (size_t k = 0; k < take.expressions.size(); ++k)
      frames[static_cast<size_t>(f)].weights[take.expressions[k]] = take.weights(f, static_cast<Eigen::Index>(k));
  }
  return frames;
}

// The map's shapes must be the face model's: a shape it lacks would read as 0 in every frame.
void check_map_shapes(const ControllerMap& map, const FaceModel& model, const std::string& where) {
  for (const std::string& shape : map.shapes)
    if (model.expression_index(shape) < 0)
      throw Error(where, fmt::format("maps from the shape \"{}\", which the face model {} does not have (a map "
                                     "fitted for another face model?)",
                                     shape, model.source));
}

}  // namespace rig_head_run_detail

void RigHeadRunOptions::validate() const {
  if (bundle.empty()) throw Error("--bundle", "required: the bundle whose rig the map drives");
  if (rig_map.empty()) throw Error("--rig-map", "required");
  if (face_model.empty())
    throw Error("--face-model", "required with --rig-map: the face model whose blendshapes the map reads");
  if (arkit.empty() == inputs.empty())
    throw Error("--arkit", arkit.empty() ? "give an ARKit take or human meshes to retarget"
                                         : "give an ARKit take or human meshes, not both");
  if (out.empty()) throw Error("--out", "required: the folder to write");
  if (format != "obj" && format != "ply") throw Error("--format", "expected obj or ply, got \"" + format + "\"");
}

RigHeadRunSummary run_rig_head(const RigHeadRunOptions& options) {
  using namespace rig_head_run_detail;
  const Stopwatch clock;
  options.validate();
  const LoadedBundle bundle = load_bundle(options.bundle);
  if (!bundle.rig)
    throw Error(options.bundle, "this bundle carries no rig (format_version " +
                                    std::to_string(bundle.metadata.format_version) +
                                    "); export it again from an avatar dataset whose rig loads");
  const Rig& rig = *bundle.rig;
  const ControllerMap map = load_controller_map(options.rig_map);
  map.on_rig({}, rig, options.rig_map);  // the map's controllers are the rig's, before any work
  const FaceModel model = load_face_model(options.face_model);
  check_face_model_for_bundle(model, bundle.human_rest, bundle.metadata.human.units);
  check_map_shapes(map, model, options.rig_map);
  GltfAnimationOptions gltf;
  gltf.fps = options.fps;
  if (!options.gltf.empty()) {
    gltf.validate();
    gltf_scale_to_metres(rig.units, gltf);  // unknown units: refused now, not after the frames
  }

  std::vector<Frame> frames;
  std::vector<std::string> meshes;  // with mesh inputs: the files, one per frame
  std::unique_ptr<ArkitTake> take;
  if (!options.arkit.empty()) {
    std::vector<std::string> names;
    for (const Blendshape& b : model.expressions) names.push_back(b.name);
    take = std::make_unique<ArkitTake>(read_arkit_take(options.arkit, names));
    frames = take_frames(*take);
  } else {
    for (const InputFile& input : expand_inputs(options.inputs)) {
      if (!input.problem.empty()) throw Error(input.path, input.problem);
      meshes.push_back(input.path);
      frames.push_back({fs::path(input.path).stem().string(), {}});
    }
  }

  fs::create_directories(options.out);
  RigHeadRunSummary summary;
  summary.out = options.out;
  summary.avatar = rig.name;
  summary.controllers = rig.controller_count();
  summary.pairs = map.pairs;
  // Factorised once, and only when there are meshes to fit (a take brings its own weights).
  std::optional<FaceModelFit> fit;
  if (!meshes.empty()) fit.emplace(model);
  std::vector<Eigen::VectorXd> weights;
  std::string csv = "frame";
  for (const std::string& name : map.controllers) csv += "," + name;
  csv += "\n";
  for (size_t f = 0; f < frames.size(); ++f) {
    if (!meshes.empty()) {
      const Mesh face = read_mesh(meshes[f]);
      require_same_topology(model.neutral, face);
      frames[f].weights = fit->fit(face.vertices);
    }
    const Eigen::VectorXd w = map.on_rig(frames[f].weights, rig, options.rig_map);
    const std::string path = (fs::path(options.out) / (frames[f].name + "." + options.format)).string();
    write_mesh(path, with_positions(rig.neutral, rig.evaluate(w)), MeshWriteOptions{options.format == "ply"});
    summary.outputs.push_back(path);
    csv += frames[f].name;
    for (Eigen::Index i = 0; i < w.size(); ++i) csv += fmt::format(",{:.6g}", w(i));
    csv += "\n";
    weights.push_back(w);
  }
  summary.frames = static_cast<int>(frames.size());
  summary.weights_csv = (fs::path(options.out) / "weights.csv").string();
  write_file_atomically(summary.weights_csv, [&](std::ostream& out) { out << csv; });
  if (take)
    write_file_atomically((fs::path(options.out) / "frames.csv").string(),
                          [&](std::ostream& out) { out << arkit_frames_csv(*take); });
  if (!options.gltf.empty() && !weights.empty()) {
    write_gltf_animation(gltf_animation_input(rig, weights), gltf, options.gltf);
    summary.gltf = options.gltf;
  }
  summary.seconds = clock.seconds();
  return summary;
}

std::string format_rig_head_summary(const RigHeadRunSummary& s) {
  std::string text = fmt::format(
      "rig head: {} frame{} onto {} ({} controllers, a map of {} annotated pairs) in {:.2f} s -> {}\n  weights: {}\n",
      s.frames, s.frames == 1 ? "" : "s", s.avatar, s.controllers, s.pairs, s.seconds, s.out, s.weights_csv);
  if (!s.gltf.empty()) text += fmt::format("  glTF animation: {}\n", s.gltf);
  return text;
}

}  // namespace retarget
