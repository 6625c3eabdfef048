#include "train/retarget_evaluation.h"

#include <fmt/format.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <set>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/log.h"
#include "core/timer.h"
#include "geometry/controller_correspondence.h"
#include "geometry/deformation_transfer.h"
#include "geometry/mesh_io.h"
#include "geometry/metrics.h"
#include "geometry/render.h"
#include "geometry/rig.h"
#include "geometry/rigid_alignment.h"
#include "geometry/topology_fingerprint.h"
#include "train/correspondence.h"
#include "train/dataset.h"
#include "train/test_faces.h"

namespace retarget {

namespace fs = std::filesystem;

namespace {

// Controller weights w in [lo, hi] minimising |sum_c w_c offset_c - d|^2: projected coordinate
// descent on the normal equations (the rigs have tens of controllers).
class WeightFit {
 public:
  explicit WeightFit(const Rig& rig) : rig_(rig) {
    const int c = rig.controller_count();
    const int64_t n = rig.neutral.vertex_count() * 3;
    basis_.resize(n, c);
    for (int k = 0; k < c; ++k) {
      const Positions& o = rig.controllers[k].offset;
      for (int v = 0; v < rig.neutral.vertex_count(); ++v)
        for (int a = 0; a < 3; ++a) basis_(v * 3 + a, k) = o(v, a);
    }
    gram_ = basis_.transpose() * basis_;
  }

  Eigen::VectorXd fit(const Positions& deformed) const {
    const int c = rig_.controller_count();
    const Positions d = deformed - rig_.neutral.vertices;
    Eigen::VectorXd flat(d.rows() * 3);
    for (int v = 0; v < d.rows(); ++v)
      for (int a = 0; a < 3; ++a) flat(v * 3 + a) = d(v, a);
    const Eigen::VectorXd h = basis_.transpose() * flat;
    Eigen::VectorXd w = Eigen::VectorXd::Zero(c);
    for (int sweep = 0; sweep < 500; ++sweep) {
      double change = 0;
      for (int k = 0; k < c; ++k) {
        if (gram_(k, k) <= 0) continue;
        const double step = (h(k) - gram_.row(k).dot(w)) / gram_(k, k);
        const double next = std::clamp(w(k) + step, rig_.controllers[k].min, rig_.controllers[k].max);
        change = std::max(change, std::abs(next - w(k)));
        w(k) = next;
      }
      if (change < 1e-9) break;
    }
    return w;
  }

 private:
  const Rig& rig_;
  Eigen::MatrixXd basis_;
  Eigen::MatrixXd gram_;
};

std::string stem(const std::string& file) { return fs::path(file).stem().string(); }

// The method's mesh for face `file`: <folder>/<stem>.obj, .ply or .off.
std::string method_file(const std::string& folder, const std::string& file) {
  for (const char* ext : {".obj", ".ply", ".off"}) {
    const fs::path p = fs::path(folder) / (stem(file) + ext);
    if (fs::exists(p)) return p.string();
  }
  throw Error(folder, fmt::format("has no output for {} (looked for {}.obj, .ply, .off)", file, stem(file)));
}

// Up to `rows` face indices for the sheet: one per expression first (cycling through the
// subjects), then the rest in order.
std::vector<size_t> sheet_faces(const TestFaces& faces, int rows) {
  std::vector<size_t> picked;
  std::set<std::string> seen_expressions;
  std::map<std::string, int> subject_turn;
  std::vector<std::string> subjects;
  for (const TestFace& f : faces.faces)
    if (std::find(subjects.begin(), subjects.end(), f.subject) == subjects.end()) subjects.push_back(f.subject);
  // Interesting expressions first: skip "neutral" unless nothing else is left.
  for (int pass = 0; pass < 2 && static_cast<int>(picked.size()) < rows; ++pass)
    for (size_t i = 0; i < faces.faces.size() && static_cast<int>(picked.size()) < rows; ++i) {
      const TestFace& f = faces.faces[i];
      if (seen_expressions.count(f.expression) || (pass == 0 && f.expression == "neutral")) continue;
      const std::string& want = subjects[seen_expressions.size() % subjects.size()];
      if (pass == 0 && f.subject != want) continue;
      seen_expressions.insert(f.expression);
      picked.push_back(i);
    }
  for (size_t i = 0; i < faces.faces.size() && static_cast<int>(picked.size()) < rows; ++i)
    if (std::find(picked.begin(), picked.end(), i) == picked.end()) picked.push_back(i);
  return picked;
}

}  // namespace

void RetargetEvaluationOptions::validate() const {
  if (faces.empty()) throw Error("--faces", "expected the folder written by `retarget faces`");
  if (correspondences.empty()) throw Error("--correspondences", "expected a correspondence folder");
  if (out.empty()) throw Error("--out", "expected an output folder");
  if (methods.empty() && !deformation_transfer) throw Error("--method", "nothing to evaluate");
  std::set<std::string> names;
  if (deformation_transfer) names.insert("dt");
  for (const auto& [name, folder] : methods) {
    if (name.empty() || folder.empty()) throw Error("--method", "expected NAME=FOLDER");
    if (!names.insert(name).second) throw Error("--method", fmt::format("the name '{}' is used twice", name));
  }
  if (sheet_rows < 1) throw Error("--sheet-rows", "expected at least 1");
  if (render_size < 32 || render_size > 2048) throw Error("--render-size", "expected 32..2048 pixels");
}

RetargetEvaluation evaluate_retargeting(const RetargetEvaluationOptions& options) {
  options.validate();
  const Stopwatch clock;
  const TestFaces faces = load_test_faces(options.faces);
  if (faces.faces.empty()) throw Error(options.faces, "faces.yaml lists no faces");
  const Correspondences corr = load_correspondences(options.correspondences);
  const Dataset human = load_dataset(corr.human_dataset);
  const Dataset avatar = load_dataset(corr.avatar_dataset);
  check_correspondences(corr, human, avatar);
  if (faces.fingerprint != human.fingerprint)
    throw Error(options.faces, fmt::format("faces of topology {} but the correspondences' human dataset {} has {}",
                                           faces.fingerprint, corr.human_dataset, human.fingerprint));
  const Rig rig = load_rig(avatar.source);
  if (topology_fingerprint(rig.neutral) != avatar.fingerprint)
    throw Error(avatar.source, "the rig's neutral differs in topology from the avatar dataset " + corr.avatar_dataset);
  const double mm = millimetres_per_unit(rig.neutral.vertices, avatar.eyes);

  RetargetEvaluation result;
  result.ground_truth =
      std::all_of(faces.faces.begin(), faces.faces.end(),
                  [](const TestFace& f) { return !f.weights.empty() || f.expression == "neutral"; }) &&
      !faces.recipes.empty();
  ControllerCorrespondence table;
  std::vector<Eigen::VectorXd> truth_weights;
  std::vector<Positions> truth;
  if (result.ground_truth) {
    const fs::path rig_path(avatar.source);
    const std::string table_path =
        !options.table.empty()
            ? options.table
            : ((fs::is_directory(rig_path) ? rig_path : rig_path.parent_path()) / "correspondence.yaml").string();
    if (!fs::exists(table_path))
      throw Error(table_path, "no controller table for the ground truth (give one with --table)");
    table = load_controller_correspondence(table_path);
    std::vector<std::string> controllers;
    for (const Controller& c : rig.controllers) controllers.push_back(c.name);
    std::vector<std::string> shapes;
    for (const auto& [controller, row] : table)
      for (const auto& [shape, weight] : row) shapes.push_back(shape);
    check_controller_correspondence(table, controllers, shapes, table_path);
    for (const TestFace& f : faces.faces) {
      const std::map<std::string, double> mapped = controller_weights_from_human(table, f.weights);
      Eigen::VectorXd w = Eigen::VectorXd::Zero(rig.controller_count());
      for (int c = 0; c < rig.controller_count(); ++c) {
        const auto it = mapped.find(rig.controllers[c].name);
        if (it != mapped.end()) w(c) = it->second;
      }
      truth.push_back(rig.evaluate(w));
      truth_weights.push_back(std::move(w));
    }
  }

  // The human inputs, read once (the DT baseline and the contact sheet use them).
  std::vector<Positions> inputs;
  inputs.reserve(faces.faces.size());
  for (const TestFace& f : faces.faces)
    inputs.push_back(read_mesh((fs::path(options.faces) / f.file).string()).vertices);

  fs::create_directories(options.out);
  std::vector<std::string> names;
  std::vector<std::vector<Positions>> outputs;  // [method][face], as written

  if (options.deformation_transfer) {
    // DT alone: the face's displacement from its subject's neutral, applied to the mean face
    // the correspondences' transfer starts from.
    // The landmark pairs the correspondences were built with (their manifest records them).
    const Stopwatch dt_clock;
    const DeformationTransfer transfer(human.rest, avatar.rest, corr.landmarks);
    std::map<std::string, const Positions*> neutral_of;
    for (size_t i = 0; i < faces.faces.size(); ++i)
      if (faces.faces[i].expression == "neutral") neutral_of[faces.faces[i].subject] = &inputs[i];
    std::vector<Positions> sources;
    for (size_t i = 0; i < faces.faces.size(); ++i) {
      const Positions& face = inputs[i];
      const auto n = neutral_of.find(faces.faces[i].subject);
      sources.push_back(n != neutral_of.end() ? Positions(human.rest.vertices + (face - *n->second)) : face);
    }
    std::vector<Positions> moved = transfer.transfer(sources);
    fs::create_directories(fs::path(options.out) / "dt");
    for (size_t i = 0; i < moved.size(); ++i) {
      write_mesh((fs::path(options.out) / "dt" / (stem(faces.faces[i].file) + ".obj")).string(),
                 with_positions(rig.neutral, moved[i]));
    }
    log::info("deformation transfer of {} faces in {:.1f} s", moved.size(), dt_clock.seconds());
    names.push_back("dt");
    outputs.push_back(std::move(moved));
  }
  for (const auto& [name, folder] : options.methods) {
    std::vector<Positions> meshes;
    for (const TestFace& f : faces.faces) {
      const std::string path = method_file(folder, f.file);
      Positions v = read_mesh(path).vertices;
      if (v.rows() != rig.neutral.vertex_count())
        throw Error(path, fmt::format("has {} vertices; the avatar has {}", v.rows(), rig.neutral.vertex_count()));
      meshes.push_back(std::move(v));
    }
    names.push_back(name);
    outputs.push_back(std::move(meshes));
  }

  nlohmann::ordered_json report;
  report["faces"] = fs::absolute(options.faces).string();
  report["correspondences"] = fs::absolute(options.correspondences).string();
  report["human_dataset"] = corr.human_dataset;
  report["avatar"] = avatar.name;
  report["samples"] = faces.faces.size();
  report["mm_per_unit"] = mm;
  report["ground_truth"] = result.ground_truth ? "recipe weights mapped through the controller table, on the rig"
                                               : "none (faces without recipe weights)";
  if (result.ground_truth) {
    const WeightFit fit(rig);
    for (size_t m = 0; m < names.size(); ++m) {
      MethodScore s;
      s.name = names[m];
      s.samples = static_cast<int>(faces.faces.size());
      std::map<std::string, std::pair<double, int>> per_expression;
      for (size_t i = 0; i < faces.faces.size(); ++i) {
        const Positions& out = outputs[m][i];
        const Positions aligned = rigid_alignment(out, truth[i]).apply(out);
        const VertexError e = vertex_error(aligned, truth[i], mm);
        s.mean_mm += e.mean;
        s.mean_of_max_mm += e.max;
        s.max_mm = std::max(s.max_mm, e.max);
        s.weight_error += (fit.fit(out) - truth_weights[i]).cwiseAbs().mean();
        auto& pe = per_expression[faces.faces[i].expression];
        pe.first += e.mean, pe.second += 1;
      }
      s.mean_mm /= s.samples, s.mean_of_max_mm /= s.samples, s.weight_error /= s.samples;
      for (const auto& [expression, sum] : per_expression) s.expression_mean_mm[expression] = sum.first / sum.second;
      result.methods.push_back(s);
      nlohmann::ordered_json j;
      j["mean_mm"] = s.mean_mm;
      j["max_mm"] = s.max_mm;
      j["mean_of_max_mm"] = s.mean_of_max_mm;
      j["weight_error"] = s.weight_error;
      j["expression_mean_mm"] = s.expression_mean_mm;
      report["methods"][s.name] = j;
    }
  }

  // The contact sheet: human input | each method | ground truth, one face per row.
  const auto human_topology = std::make_shared<const Mesh>(human.rest);
  const auto avatar_topology = std::make_shared<const Mesh>(rig.neutral);
  std::vector<GridCell> cells;
  const std::vector<size_t> rows = sheet_faces(faces, options.sheet_rows);
  for (size_t i : rows) {
    const TestFace& f = faces.faces[i];
    cells.push_back({human_topology, inputs[i], {}, fmt::format("{} {}", f.subject, f.expression)});
    for (size_t m = 0; m < names.size(); ++m) {
      std::string caption = names[m];
      if (result.ground_truth) {
        const Positions aligned = rigid_alignment(outputs[m][i], truth[i]).apply(outputs[m][i]);
        caption += fmt::format(" {:.2f} mm", vertex_error(aligned, truth[i], mm).mean);
      }
      cells.push_back({avatar_topology, outputs[m][i], {}, caption});
    }
    if (result.ground_truth) cells.push_back({avatar_topology, truth[i], {}, "ground truth"});
  }
  GridOptions grid;
  grid.render.width = grid.render.height = options.render_size;
  grid.share_frame = false;
  grid.text_scale = 1;
  grid.title = fmt::format("human | {}{}", fmt::join(names, " | "), result.ground_truth ? " | ground truth" : "");
  const int columns = 1 + static_cast<int>(names.size()) + (result.ground_truth ? 1 : 0);
  result.sheet_path = (fs::path(options.out) / "contact_sheet.png").string();
  write_png(result.sheet_path, render_grid(cells, columns, grid));

  result.metrics_path = (fs::path(options.out) / "metrics.json").string();
  result.seconds = clock.seconds();
  report["seconds"] = result.seconds;
  write_file_atomically(result.metrics_path, [&](std::ostream& s) { s << report.dump(2) << "\n"; });
  return result;
}

}  // namespace retarget
