#include "cli/cli.h"

#include <algorithm>
#include <cxxopts.hpp>
#include <filesystem>
#include <functional>
#include <iostream>
#include <map>
#include <optional>

#include "cli/command_options.h"
#include "cli/commands.h"
#include "core/error.h"
#include "core/log.h"
#include "core/option_errors.h"
#include "core/progress.h"
#include "core/timer.h"
#include "geometry/deformation_transfer.h"
#include "geometry/dr_features.h"
#include "geometry/landmarks.h"
#include "geometry/mesh_io.h"
#include "geometry/mesh_validation.h"
#include "geometry/metrics.h"
#include "geometry/reconstruction.h"
#include "geometry/rigid_alignment.h"
#include "geometry/synthetic_deformations.h"
#include "synthetic/geometry_demo.h"

namespace retarget::cli {

namespace fs = std::filesystem;

namespace {

// Reads a mesh and checks it against the rest mesh it is used with.
Mesh read_like(const std::string& path, const Mesh& rest) {
  Mesh mesh = read_mesh(path);
  require_same_topology(rest, mesh);
  return mesh;
}

std::string error_line(const char* label, const VertexError& e, double scale, const char* unit) {
  return fmt::format("{}: mean {:.4g} {}, max {:.4g} {} (vertex {})", label, e.mean, unit, e.max, unit, e.worst_vertex);
}

// Error in the units the user asked for: mm when --mm-per-unit or --eyes is given, else
// the mesh's own units; always also relative to the bounding-box diagonal.
struct Units {
  double scale = 1;
  const char* name = "units";
};
Units units_from(const cxxopts::ParseResult& args, const Mesh& reference) {
  Units u;
  if (args.count("eyes")) {
    u.scale = millimetres_per_unit(reference.vertices, read_eye_landmarks(args["eyes"].as<std::string>()));
    u.name = "mm";
  } else if (args.count("mm-per-unit")) {
    u.scale = args["mm-per-unit"].as<double>();
    u.name = "mm";
  }
  return u;
}

void add_unit_options(cxxopts::Options& options) {
  options.add_options()("mm-per-unit", "millimetres per mesh unit for error reports (ICT: 10)",
                        cxxopts::value<double>())(
      "eyes", "YAML with left_eye/right_eye vertex lists: scale so the eye centres are 10 cm apart",
      cxxopts::value<std::string>());
}

int info(int argc, char** argv) {
  cxxopts::Options options("retarget info", "Check mesh files and report their size and defects.");
  options.add_options()("meshes", "mesh files", cxxopts::value<std::vector<std::string>>());
  options.parse_positional({"meshes"});
  options.positional_help("MESH...");
  const auto args = parse_options(options, argc, argv);
  if (!args) return 0;
  if (!args->count("meshes")) throw Error("retarget info", "give at least one mesh file");
  for (const std::string& path : (*args)["meshes"].as<std::vector<std::string>>()) {
    const Mesh mesh = read_mesh(path);
    const MeshReport r = validate_mesh(mesh);
    std::cout << fmt::format(
        "{}: {} vertices, {} faces ({} triangles), {} degenerate triangles, {} boundary edges, "
        "{} non-manifold edges, {} unreferenced vertices, bounding-box diagonal {:.6g}\n",
        path, r.vertex_count, r.face_count, r.triangle_count, r.degenerate_triangles, r.boundary_edges,
        r.nonmanifold_edges, r.unreferenced_vertices, bounding_box_diagonal(mesh.vertices));
  }
  return 0;
}

int roundtrip(int argc, char** argv) {
  cxxopts::Options options("retarget roundtrip",
                           "DR features of each mesh relative to the rest mesh, reconstructed back to positions;\n"
                           "reports the error after rigid alignment and writes the reconstructions with --out.");
  options.add_options()("rest", "rest mesh", cxxopts::value<std::string>())(
      "weighting", "edge weights: cotangent or uniform", cxxopts::value<std::string>()->default_value("cotangent"))(
      "out", "folder for the reconstructed meshes", cxxopts::value<std::string>())(
      "twist",
      "also test synthetic twists of the rest mesh, AXIS:DEGREES with AXIS x, y or z (e.g. y:90,y:170): the part\n"
      "beyond 30% of the mesh's extent along the axis turns about the axis through the centroid, reaching the full\n"
      "angle at 80%",
      cxxopts::value<std::vector<std::string>>())("meshes", "deformed meshes",
                                                  cxxopts::value<std::vector<std::string>>());
  add_unit_options(options);
  options.parse_positional({"meshes"});
  options.positional_help("--rest REST MESH...");
  const auto args = parse_options(options, argc, argv);
  if (!args) return 0;
  if (!args->count("rest") || (!args->count("meshes") && !args->count("twist")))
    throw Error("retarget roundtrip", "give --rest and at least one mesh or --twist (see --help)");
  const Mesh rest = read_mesh((*args)["rest"].as<std::string>());
  const EdgeWeighting weighting = parse_edge_weighting((*args)["weighting"].as<std::string>(), "--weighting");
  const Units units = units_from(*args, rest);
  Stopwatch setup;
  DrOptions dr;
  dr.weighting = weighting;
  ReconstructionOptions ro;
  ro.weighting = weighting;
  const DrFeatures features(rest, dr);
  const Reconstruction reconstruction(rest, ro);
  log::info("prepared {} vertices in {:.1f} ms (factor: {} non-zeros)", rest.vertex_count(), setup.milliseconds(),
            reconstruction.factor_nonzeros());
  // Each case: a name and the deformed positions (a mesh file, or a twist of the rest mesh).
  std::vector<std::pair<std::string, Positions>> cases;
  if (args->count("twist")) {
    const Eigen::Vector3d centre = rest.vertices.colwise().mean().transpose();
    for (const std::string& spec : (*args)["twist"].as<std::vector<std::string>>()) {
      const size_t colon = spec.find(':');
      const std::string axis_name = spec.substr(0, colon);
      if (colon == std::string::npos || axis_name.size() != 1 || axis_name[0] < 'x' || axis_name[0] > 'z')
        throw Error("--twist " + spec, "expected AXIS:DEGREES with AXIS x, y or z, e.g. y:170");
      double degrees = 0;
      try {
        degrees = std::stod(spec.substr(colon + 1));
      } catch (const std::exception&) {
        throw Error("--twist " + spec, "the angle is not a number");
      }
      const Eigen::Vector3d axis = Eigen::Vector3d::Unit(axis_name[0] - 'x');
      const Eigen::VectorXd t = (rest.vertices.rowwise() - centre.transpose()) * axis;
      const double lo = t.minCoeff(), range = t.maxCoeff() - lo;
      cases.emplace_back("twist " + spec,
                         twist(rest.vertices, axis, centre, degrees, lo + 0.3 * range, lo + 0.8 * range));
    }
  }
  if (args->count("meshes"))
    for (const std::string& path : (*args)["meshes"].as<std::vector<std::string>>())
      cases.emplace_back(path, read_like(path, rest).vertices);

  for (const auto& [name, deformed] : cases) {
    Stopwatch clock;
    const DrFeatureMatrix f = features.compute(deformed);
    const double feature_ms = clock.restart() * 1e3;
    const Positions result = reconstruction.reconstruct(f);
    const double solve_ms = clock.seconds() * 1e3;
    const Positions aligned = rigid_alignment(result, deformed).apply(result);
    const VertexError e = vertex_error(aligned, deformed, units.scale);
    const double diagonal = bounding_box_diagonal(deformed) * units.scale;
    std::cout << fmt::format(
        "{}: mean {:.4g} {}, max {:.4g} {} (vertex {}); relative to the diagonal: mean {:.3g}, "
        "max {:.3g}; features {:.2f} ms, reconstruction {:.2f} ms\n",
        name, e.mean, units.name, e.max, units.name, e.worst_vertex, e.mean / diagonal, e.max / diagonal, feature_ms,
        solve_ms);
    if (args->count("out")) {
      std::string file = fs::path(name).filename().string();
      if (file.rfind("twist ", 0) == 0) file = "twist_" + file.substr(6) + ".obj";
      std::replace(file.begin(), file.end(), ':', '_');
      write_mesh((fs::path((*args)["out"].as<std::string>()) / file).string(), with_positions(rest, aligned));
    }
  }
  return 0;
}

int transfer(int argc, char** argv) {
  cxxopts::Options options("retarget transfer",
                           "Deformation transfer (Sumner & Popovic 2004): carries each source expression\n"
                           "(a deformation of --source-rest) onto --target-rest, of any topology.");
  options.add_options()("source-rest", "source rest mesh", cxxopts::value<std::string>())(
      "target-rest", "target rest mesh", cxxopts::value<std::string>())(
      "landmarks", "YAML landmark pairs (pairs: [[s, t], ...] | source: [...] target: [...] | same: [...])",
      cxxopts::value<std::string>())("landmarks-key", "use this list in the landmark file as identical indices",
                                     cxxopts::value<std::string>()->default_value(""))(
      "out", "output folder (one mesh per expression, same file names)", cxxopts::value<std::string>())(
      "reference", "folder with ground-truth target meshes of the same names, to report errors",
      cxxopts::value<std::string>())("expressions", "source expression meshes",
                                     cxxopts::value<std::vector<std::string>>());
  add_unit_options(options);
  options.parse_positional({"expressions"});
  options.positional_help("--source-rest S --target-rest T --landmarks L EXPRESSION...");
  const auto args = parse_options(options, argc, argv);
  if (!args) return 0;
  for (const char* required : {"source-rest", "target-rest", "landmarks", "expressions"})
    if (!args->count(required))
      throw Error("retarget transfer", std::string("missing --") + required + " (see --help)");
  const Mesh source = read_mesh((*args)["source-rest"].as<std::string>());
  const Mesh target = read_mesh((*args)["target-rest"].as<std::string>());
  const auto landmarks =
      read_landmark_pairs((*args)["landmarks"].as<std::string>(), (*args)["landmarks-key"].as<std::string>());
  check_landmark_pairs(landmarks, source.vertex_count(), source.source, target.vertex_count(), target.source);
  const Units units = units_from(*args, target);

  Stopwatch clock;
  const DeformationTransfer dt(source, target, landmarks);
  const auto& report = dt.report();
  log::info(
      "correspondence: {} landmarks, fitted source {:.4g} mean / {:.4g} max from the target surface, "
      "{} triangle pairs; prepared in {:.2f} s",
      landmarks.size(), report.mean_distance, report.max_distance, report.triangle_pairs, clock.seconds());
  const auto paths = (*args)["expressions"].as<std::vector<std::string>>();
  Progress progress("transfer", static_cast<int64_t>(paths.size()));
  for (const std::string& path : paths) {
    const Mesh expression = read_like(path, source);
    clock.restart();
    const Positions result = dt.transfer(expression.vertices);
    const double ms = clock.milliseconds();
    std::string line = fmt::format("{}: {:.1f} ms", path, ms);
    if (args->count("reference")) {
      const fs::path reference = fs::path((*args)["reference"].as<std::string>()) / fs::path(path).filename();
      const Mesh truth = read_like(reference.string(), target);
      line += "; " + error_line("error", vertex_error(result, truth.vertices, units.scale), units.scale, units.name);
    }
    if (args->count("out")) {
      const fs::path out = fs::path((*args)["out"].as<std::string>()) / fs::path(path).filename();
      write_mesh(out.string(), with_positions(target, result));
    }
    progress.advance();
    log::info("{}", line);
  }
  return 0;
}

int demo(int argc, char** argv) {
  cxxopts::Options options("retarget demo",
                           "The geometry core on synthetic face-like meshes: DR features round trip and\n"
                           "deformation transfer onto a face of another topology, with errors in mm.");
  GeometryDemoOptions demo_options;
  options.add_options()("out", "output folder", cxxopts::value<std::string>()->default_value(demo_options.out));
  const auto args = parse_options(options, argc, argv);
  if (!args) return 0;
  demo_options.out = (*args)["out"].as<std::string>();
  const std::vector<GeometryDemoRow> rows = run_geometry_demo(demo_options);
  std::cout << fmt::format("{:<14}{:>22}{:>22}{:>12}{:>12}{:>12}\n", "expression", "round trip mean/max",
                           "transfer mean/max", "features", "reconstr.", "transfer");
  for (const GeometryDemoRow& r : rows)
    std::cout << fmt::format("{:<14}{:>11.3f}/{:>6.3f} mm{:>11.3f}/{:>6.3f} mm{:>9.2f} ms{:>9.2f} ms{:>9.2f} ms\n",
                             r.expression, r.roundtrip_mean_mm, r.roundtrip_max_mm, r.transfer_mean_mm,
                             r.transfer_max_mm, r.features_ms, r.reconstruction_ms, r.transfer_ms);
  std::cout << "meshes written to " << demo_options.out << " (source/, roundtrip/, target/, target_truth/)\n";
  return 0;
}

const std::map<std::string, std::pair<std::function<int(int, char**)>, const char*>>& commands() {
  static const std::map<std::string, std::pair<std::function<int(int, char**)>, const char*>> table = {
      {"avatar", {avatar_command, "a new avatar from its rig alone: avatar init proposes landmarks, eyes and parts"}},
      {"dataset", {dataset_command, "turn a rig or a face set into a DR-feature dataset"}},
      {"pipeline",
       {pipeline_command, "the whole method from one recipe, resumable (configs/recipes/demo.yaml, real.yaml)"}},
      {"plot", {plot_command, "pictures of training runs and evaluations (gnuplot): curves, errors per method"}},
      {"train", {train_command, "train what a YAML config names (VAEs), with checkpoints and --resume"}},
      {"eval", {eval_command, "evaluate a trained run (eval vae RUN: reconstruction error in mm)"}},
      {"correspond",
       {correspond_command, "geometric correspondences: DT of the human references, y0 and nearest groups"}},
      {"annotate",
       {annotate_command, "annotation projects: tournaments over the groups (init, simulate, terminal, ...)"}},
      {"export", {export_command, "write a trained VAE as TorchScript encoder.pt / decoder.pt with metadata"}},
      {"faces", {faces_command, "write a human dataset's held-out people as mesh files (inputs for retarget-infer)"}},
      {"gltf-animation",
       {gltf_animation_command, "controller weights per frame (weights.csv) as a glTF morph-target animation"}},
      {"rig-map",
       {rig_map_command, "the rig head: human blendshape weights -> controller weights learnt from the champions"}},
      {"render", {render_command, "draw meshes to PNG (front and 3/4 views, captioned grids)"}},
      {"synth", {synth_command, "write the bundled synthetic face model and avatars"}},
      {"demo", {demo, "the geometry core on synthetic faces (round trip and deformation transfer)"}},
      {"info", {info, "check mesh files and report their size and defects"}},
      {"roundtrip", {roundtrip, "DR features -> reconstruction of meshes, with the error"}},
      {"transfer", {transfer, "deformation transfer of expressions onto another mesh"}},
  };
  return table;
}

void usage(std::ostream& out) {
  out << "retarget " << RETARGET_VERSION << ": facial expression retargeting\n\nUsage: retarget COMMAND [options]\n\n";
  for (const auto& [name, entry] : commands()) out << fmt::format("  {:<16}{}\n", name, entry.second);
  out << "\n'retarget COMMAND --help' describes each command.\n";
}

}  // namespace

int run(int argc, char** argv) {
  if (argc < 2 || std::string(argv[1]) == "--help" || std::string(argv[1]) == "-h") {
    usage(std::cout);
    return argc < 2 ? 2 : 0;
  }
  if (std::string(argv[1]) == "--version") {
    std::cout << RETARGET_VERSION << "\n";
    return 0;
  }
  const auto it = commands().find(argv[1]);
  if (it == commands().end()) {
    std::cerr << "retarget: unknown command '" << argv[1] << "'\n\n";
    usage(std::cerr);
    return 2;
  }
  try {
    return it->second.first(argc - 1, argv + 1);
  } catch (const Error& e) {
    std::cerr << "retarget " << argv[1] << ": " << e.what() << "\n";
  } catch (const cxxopts::exceptions::exception& e) {
    std::cerr << "retarget " << argv[1] << ": " << explain_option_error(e.what(), argc - 1, argv + 1)
              << " (see --help)\n";
  } catch (...) {
    // Out of memory, a LibTorch error, anything a library throws: a message, never an abort.
    std::cerr << "retarget " << argv[1] << ": " << describe_current_exception() << "\n";
  }
  return 1;
}

}  // namespace retarget::cli
