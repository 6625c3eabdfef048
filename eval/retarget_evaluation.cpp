#include "eval/retarget_evaluation.h"

#include <fmt/format.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <set>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/log.h"
#include "core/timer.h"
#include "correspond/correspondence.h"
#include "data/dataset.h"
#include "data/test_faces.h"
#include "geometry/controller_correspondence.h"
#include "geometry/deformation_transfer.h"
#include "geometry/expression_error.h"
#include "geometry/mesh_io.h"
#include "geometry/metrics.h"
#include "geometry/rig.h"
#include "geometry/rig_footprint.h"
#include "geometry/rig_weight_fit.h"
#include "geometry/rigid_alignment.h"
#include "geometry/topology_fingerprint.h"
#include "render/render.h"

namespace retarget {

namespace fs = std::filesystem;

namespace {

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

// Up to `rows` faces, one per expression, whose `error` is largest, worst first (neutral last).
std::vector<size_t> worst_faces(const TestFaces& faces, const std::vector<double>& error, int rows) {
  std::map<std::string, size_t> worst_of;  // expression -> its worst face
  for (size_t i = 0; i < faces.faces.size(); ++i) {
    const auto it = worst_of.find(faces.faces[i].expression);
    if (it == worst_of.end() || error[i] > error[it->second]) worst_of[faces.faces[i].expression] = i;
  }
  std::vector<size_t> picked;
  for (const auto& entry : worst_of) picked.push_back(entry.second);
  std::stable_sort(picked.begin(), picked.end(), [&](size_t a, size_t b) { return error[a] > error[b]; });
  if (static_cast<int>(picked.size()) > rows) picked.resize(static_cast<size_t>(rows));
  return picked;
}

constexpr double kActiveWeight = 0.05;  // a controller counts as active above this weight
constexpr double kStillMm = 0.1;        // a vertex the rig moves less than this never moves

}  // namespace

void RetargetEvaluationOptions::validate() const {
  if (faces.empty()) throw Error("--faces", "expected the folder written by `retarget faces`");
  if (correspondences.empty()) throw Error("--correspondences", "expected a correspondence folder");
  if (out.empty()) throw Error("--out", "expected an output folder");
  if (methods.empty() && !deformation_transfer && !neutral) throw Error("--method", "nothing to evaluate");
  std::set<std::string> names;
  if (neutral) names.insert("neutral");
  if (deformation_transfer) names.insert("dt");
  if (deformation_transfer && rig_projection) names.insert("dt_rig");
  for (const auto& [name, folder] : methods) {
    if (name.empty() || folder.empty()) throw Error("--method", "expected NAME=FOLDER");
    if (!names.insert(name).second) throw Error("--method", fmt::format("the name '{}' is used twice", name));
  }
  if (sheet_rows < 1) throw Error("--sheet-rows", "expected at least 1");
  if (sheet != "worst" && sheet != "first") throw Error("--sheet", "expected 'worst' or 'first', got '" + sheet + "'");
  if (!sheet_method.empty() && !names.count(sheet_method))
    throw Error("--sheet-method", "'" + sheet_method + "' is not one of the methods evaluated");
  if (render_size < 32 || render_size > 2048) throw Error("--render-size", "expected 32..2048 pixels");
}

namespace {

// What every step reads: the test faces, both datasets, the rig and, when the faces carry
// recipe weights, the ground truth on the rig.
struct EvaluationInputs {
  TestFaces faces;
  Correspondences corr;
  Dataset human, avatar;
  Rig rig;
  double mm = 1;  // millimetres per avatar unit
  ControllerCorrespondence table;
  std::vector<Eigen::VectorXd> truth_weights;  // [face] controller weights (ground truth only)
  std::vector<Positions> truth;                // [face] the rig at those weights
  std::vector<Positions> inputs;               // [face] the human meshes
};

// The ground truth: each face's recipe weights mapped through the controller table (--table, or
// correspondence.yaml beside the rig) and evaluated on the rig.
void load_ground_truth(const RetargetEvaluationOptions& options, EvaluationInputs& in) {
  const fs::path rig_path(in.avatar.source);
  const std::string table_path =
      !options.table.empty()
          ? options.table
          : ((fs::is_directory(rig_path) ? rig_path : rig_path.parent_path()) / "correspondence.yaml").string();
  if (!fs::exists(table_path))
    throw Error(table_path, "no controller table for the ground truth (give one with --table)");
  in.table = load_controller_correspondence(table_path);
  std::vector<std::string> controllers;
  for (const Controller& c : in.rig.controllers) controllers.push_back(c.name);
  std::vector<std::string> shapes;
  for (const auto& [controller, row] : in.table)
    for (const auto& [shape, weight] : row) shapes.push_back(shape);
  check_controller_correspondence(in.table, controllers, shapes, table_path);
  for (const TestFace& f : in.faces.faces) {
    Eigen::VectorXd w = rig_weights_from_human(in.table, in.rig, f.weights);
    in.truth.push_back(in.rig.evaluate(w));
    in.truth_weights.push_back(std::move(w));
  }
}

EvaluationInputs load_inputs(const RetargetEvaluationOptions& options, bool& ground_truth) {
  EvaluationInputs in;
  in.faces = load_test_faces(options.faces);
  if (in.faces.faces.empty()) throw Error(options.faces, "faces.yaml lists no faces");
  in.corr = load_correspondences(options.correspondences);
  in.human = load_dataset(in.corr.human_dataset);
  in.avatar = load_dataset(in.corr.avatar_dataset);
  check_correspondences(in.corr, in.human, in.avatar);
  if (in.faces.fingerprint != in.human.fingerprint)
    throw Error(options.faces, fmt::format("faces of topology {} but the correspondences' human dataset {} has {}",
                                           in.faces.fingerprint, in.corr.human_dataset, in.human.fingerprint));
  if (in.avatar.eyes.left.empty() || in.avatar.eyes.right.empty())
    throw Error(in.corr.avatar_dataset,
                "the avatar dataset has no eyes, and the evaluation measures in mm from their distance: add `eyes:` to "
                "its rig " +
                    in.avatar.source +
                    " (or name a glTF avatar's eye meshes EyeLeft/EyeRight; geometry/rig.h) and rebuild the dataset "
                    "with `retarget dataset`");
  in.rig = load_dataset_rig(in.avatar);
  in.mm = millimetres_per_unit(in.rig.neutral.vertices, in.avatar.eyes);

  ground_truth = std::all_of(in.faces.faces.begin(), in.faces.faces.end(),
                             [](const TestFace& f) { return !f.weights.empty() || f.expression == "neutral"; }) &&
                 !in.faces.recipes.empty();
  if (ground_truth) load_ground_truth(options, in);

  // The human inputs, read once (the DT baseline and the contact sheet use them).
  in.inputs.reserve(in.faces.faces.size());
  for (const TestFace& f : in.faces.faces)
    in.inputs.push_back(read_mesh((fs::path(options.faces) / f.file).string()).vertices);
  return in;
}

// Every method's avatar meshes, [method][face], in the order of `names`.
struct MethodOutputs {
  std::vector<std::string> names;
  std::vector<std::vector<Positions>> meshes;
  void add(std::string name, std::vector<Positions> m) {
    names.push_back(std::move(name));
    meshes.push_back(std::move(m));
  }
};

// Deformation transfer alone: the face's displacement from its subject's neutral, applied to
// the mean face the correspondences' transfer starts from, with the landmark pairs the
// correspondences were built with (their manifest records them). Written to out/dt/.
std::vector<Positions> transfer_faces(const RetargetEvaluationOptions& options, const EvaluationInputs& in) {
  const Stopwatch dt_clock;
  const DeformationTransfer transfer(in.human.rest, in.avatar.rest, in.corr.landmarks);
  const std::vector<TestFace>& faces = in.faces.faces;
  std::map<std::string, const Positions*> neutral_of;
  for (size_t i = 0; i < faces.size(); ++i)
    if (faces[i].expression == "neutral") neutral_of[faces[i].subject] = &in.inputs[i];
  std::vector<Positions> sources;
  for (size_t i = 0; i < faces.size(); ++i) {
    const Positions& face = in.inputs[i];
    const auto n = neutral_of.find(faces[i].subject);
    sources.push_back(n != neutral_of.end() ? Positions(in.human.rest.vertices + (face - *n->second)) : face);
  }
  std::vector<Positions> moved = transfer.transfer(sources);
  fs::create_directories(fs::path(options.out) / "dt");
  for (size_t i = 0; i < moved.size(); ++i)
    write_mesh((fs::path(options.out) / "dt" / (stem(faces[i].file) + ".obj")).string(),
               with_positions(in.rig.neutral, moved[i]));
  log::info("deformation transfer of {} faces in {:.1f} s", moved.size(), dt_clock.seconds());
  return moved;
}

// The meshes of a method given as a folder of retarget-infer outputs, one per face.
std::vector<Positions> read_method(const std::string& folder, const EvaluationInputs& in) {
  std::vector<Positions> meshes;
  for (const TestFace& f : in.faces.faces) {
    const std::string path = method_file(folder, f.file);
    Positions v = read_mesh(path).vertices;
    if (v.rows() != in.rig.neutral.vertex_count())
      throw Error(path, fmt::format("has {} vertices; the avatar has {}", v.rows(), in.rig.neutral.vertex_count()));
    meshes.push_back(std::move(v));
  }
  return meshes;
}

MethodOutputs collect_outputs(const RetargetEvaluationOptions& options, const EvaluationInputs& in,
                              const RigWeightFit& fit) {
  MethodOutputs out;
  if (options.neutral) out.add("neutral", std::vector<Positions>(in.faces.faces.size(), in.rig.neutral.vertices));
  if (options.deformation_transfer) {
    std::vector<Positions> moved = transfer_faces(options, in);
    // The rig's own expression nearest to each DT result: what DT alone gives when the answer
    // must be one the rig can make.
    std::vector<Positions> projected;
    if (options.rig_projection) {
      projected.reserve(moved.size());
      for (const Positions& m : moved) projected.push_back(fit.project(m));
    }
    out.add("dt", std::move(moved));
    if (options.rig_projection) out.add("dt_rig", std::move(projected));
  }
  for (const auto& [name, folder] : options.methods) out.add(name, read_method(folder, in));
  return out;
}

// Every face's error against the ground truth, computed once per method and summed per set.
struct FaceScore {
  ExpressionError mesh;
  Eigen::VectorXd weight_diff;  // |fitted - true| per controller
  double truth_sum = 0;         // sum |true|
  int active = 0;               // controllers > kActiveWeight in either answer
  double active_sum = 0;        // sum of weight_diff over them
};

std::vector<FaceScore> score_faces(const std::vector<Positions>& outputs, const EvaluationInputs& in,
                                   const RigFootprint& footprint, const RigWeightFit& fit) {
  std::vector<FaceScore> scores(in.faces.faces.size());
  for (size_t i = 0; i < scores.size(); ++i) {
    FaceScore& f = scores[i];
    f.mesh = expression_error(outputs[i], in.truth[i], in.mm, footprint);
    const Eigen::VectorXd& t = in.truth_weights[i];
    const Eigen::VectorXd w = fit.fit(outputs[i]);
    f.weight_diff = (w - t).cwiseAbs();
    f.truth_sum = t.cwiseAbs().sum();
    for (Eigen::Index c = 0; c < t.size(); ++c)
      if (std::abs(t(c)) > kActiveWeight || std::abs(w(c)) > kActiveWeight)
        f.active_sum += f.weight_diff(c), ++f.active;
  }
  return scores;
}

// One method's figures over the faces `which` (indices into the test faces).
MethodScore summarise(const std::string& name, const std::vector<FaceScore>& faces, const EvaluationInputs& in,
                      const std::vector<size_t>& which) {
  MethodScore s;
  s.name = name;
  s.samples = static_cast<int>(which.size());
  std::map<std::string, std::array<double, 3>> per_expression;  // mean, moving, count
  ExpressionErrorSum sum;
  int active_faces = 0, moving_faces = 0;
  for (size_t i : which) {
    const FaceScore& f = faces[i];
    sum.add(f.mesh);
    s.weight_error += f.weight_diff.mean();
    if (f.active > 0) s.weight_error_active += f.active_sum / f.active, ++active_faces;
    if (f.truth_sum > 0) s.weight_error_relative += f.weight_diff.sum() / f.truth_sum, ++moving_faces;
    auto& pe = per_expression[in.faces.faces[i].expression];
    pe[0] += f.mesh.mean, pe[1] += f.mesh.moving_mean, pe[2] += 1;
  }
  const ExpressionErrorSum a = sum.averaged();
  s.mean_mm = a.mean, s.moving_mm = a.moving_mean, s.max_mm = a.max, s.mean_of_max_mm = a.mean_of_max;
  s.region_mm = a.region_mean;
  if (s.samples) s.weight_error /= s.samples;
  if (active_faces) s.weight_error_active /= active_faces;
  if (moving_faces) s.weight_error_relative /= moving_faces;
  for (const auto& [expression, v] : per_expression) {
    s.expression_mean_mm[expression] = v[0] / v[2];
    s.expression_moving_mm[expression] = v[1] / v[2];
  }
  return s;
}

// Each method's figures as fractions of the neutral answer's (NaN without it).
void add_fractions_of_neutral(std::vector<MethodScore>& methods) {
  const auto neutral =
      std::find_if(methods.begin(), methods.end(), [](const MethodScore& s) { return s.name == "neutral"; });
  const auto ratio = [&](double a, double MethodScore::*field) {
    if (neutral == methods.end()) return std::nan("");
    const double b = (*neutral).*field;
    return b > 0 ? a / b : std::nan("");
  };
  for (MethodScore& s : methods) {
    s.fraction_of_neutral = ratio(s.mean_mm, &MethodScore::mean_mm);
    s.moving_fraction_of_neutral = ratio(s.moving_mm, &MethodScore::moving_mm);
    s.weight_active_fraction_of_neutral = ratio(s.weight_error_active, &MethodScore::weight_error_active);
  }
}

// Identity independence (the paper's Fig. 11): the same expression from several people should give
// the same avatar face. Per expression among `rows` with at least two people, the mean over them of
// the mean distance (mm, over the moving vertices) of each one's output from their mean output;
// then the mean over those expressions. 0 when no expression has two people.
double identity_spread(const std::vector<Positions>& meshes, const EvaluationInputs& in,
                       const std::vector<size_t>& rows, const std::vector<int>& moving) {
  std::map<std::string, std::vector<size_t>> by_expression;
  for (size_t i : rows) by_expression[in.faces.faces[i].expression].push_back(i);
  double total = 0;
  int expressions = 0;
  for (const auto& [expression, faces] : by_expression) {
    if (faces.size() < 2) continue;
    Positions mean = Positions::Zero(meshes[faces.front()].rows(), 3);
    for (size_t i : faces) mean += meshes[i];
    mean /= static_cast<double>(faces.size());
    double sum = 0;
    for (size_t i : faces) {
      double face = 0;
      for (int v : moving) face += (meshes[i].row(v) - mean.row(v)).norm();
      sum += moving.empty() ? 0.0 : face / static_cast<double>(moving.size());
    }
    total += in.mm * sum / static_cast<double>(faces.size());
    ++expressions;
  }
  return expressions ? total / expressions : 0.0;
}

nlohmann::ordered_json score_json(const MethodScore& s) {
  const auto number = [](double v) { return std::isfinite(v) ? nlohmann::ordered_json(v) : nlohmann::ordered_json(); };
  nlohmann::ordered_json j;
  j["mean_mm"] = s.mean_mm;
  j["moving_mm"] = s.moving_mm;
  j["fraction_of_neutral"] = number(s.fraction_of_neutral);
  j["moving_fraction_of_neutral"] = number(s.moving_fraction_of_neutral);
  j["max_mm"] = s.max_mm;
  j["mean_of_max_mm"] = s.mean_of_max_mm;
  j["region_mm"] = s.region_mm;
  j["weight_error"] = s.weight_error;
  j["weight_error_active"] = s.weight_error_active;
  j["identity_spread_mm"] = s.identity_spread_mm;
  j["weight_active_fraction_of_neutral"] = number(s.weight_active_fraction_of_neutral);
  j["weight_error_relative"] = s.weight_error_relative;
  j["expression_mean_mm"] = s.expression_mean_mm;
  j["expression_moving_mm"] = s.expression_moving_mm;
  return j;
}

// The contact sheet: human input | each method | ground truth, one face per row. It leaves out
// the neutral answer's column (the rest mesh in every row) but gives its error in the ground
// truth's caption. `face_moving`: [method][face] moving-vertex error (empty without truth).
// One row per method and set ("all", then each set), the columns users compare methods by.
std::string comparison_csv(const RetargetEvaluation& r) {
  std::string csv =
      "set,method,faces,mean_mm,moving_mm,moving_x_neutral,max_mm,weight_error_active,weights_x_neutral,"
      "identity_spread_mm\n";
  auto rows = [&csv](const std::string& set, const std::vector<MethodScore>& scores) {
    for (const MethodScore& m : scores)
      csv += fmt::format("{},{},{},{:.5f},{:.5f},{:.4f},{:.4f},{:.5f},{:.4f},{:.5f}\n", set, m.name, m.samples,
                         m.mean_mm, m.moving_mm, m.moving_fraction_of_neutral, m.max_mm, m.weight_error_active,
                         m.weight_active_fraction_of_neutral, m.identity_spread_mm);
  };
  rows("all", r.methods);
  for (const auto& [set, scores] : r.sets) rows(set, scores);
  return csv;
}

void write_contact_sheet(const RetargetEvaluationOptions& options, const EvaluationInputs& in,
                         const MethodOutputs& outputs, const std::vector<std::vector<double>>& face_moving,
                         RetargetEvaluation& result) {
  const std::vector<std::string>& names = outputs.names;
  const auto human_topology = std::make_shared<const Mesh>(in.human.rest);
  const auto avatar_topology = std::make_shared<const Mesh>(in.rig.neutral);
  const auto neutral_index = std::find(names.begin(), names.end(), "neutral") - names.begin();
  std::vector<size_t> rows;
  if (result.ground_truth && options.sheet == "worst") {
    const std::string by = !options.sheet_method.empty() ? options.sheet_method : names.back();
    rows = worst_faces(in.faces, face_moving[std::find(names.begin(), names.end(), by) - names.begin()],
                       options.sheet_rows);
  } else {
    rows = sheet_faces(in.faces, options.sheet_rows);
  }
  std::vector<GridCell> cells;
  for (size_t i : rows) {
    const TestFace& f = in.faces.faces[i];
    cells.push_back({human_topology, in.inputs[i], {}, fmt::format("{} {}", f.subject, f.expression)});
    result.sheet_expressions.push_back(fmt::format("{} {}", f.subject, f.expression));
    for (size_t m = 0; m < names.size(); ++m) {
      if (static_cast<std::ptrdiff_t>(m) == neutral_index) continue;
      std::string caption = names[m];
      if (result.ground_truth) caption += fmt::format(" {:.2f} mm", face_moving[m][i]);
      cells.push_back({avatar_topology, outputs.meshes[m][i], {}, caption});
    }
    if (result.ground_truth)
      cells.push_back({avatar_topology,
                       in.truth[i],
                       {},
                       neutral_index < static_cast<std::ptrdiff_t>(names.size())
                           ? fmt::format("truth (neutral {:.2f})", face_moving[neutral_index][i])
                           : std::string("ground truth")});
  }
  GridOptions grid;
  grid.render.width = grid.render.height = options.render_size;
  grid.share_frame = false;
  grid.text_scale = 1;
  std::vector<std::string> shown;
  for (size_t m = 0; m < names.size(); ++m)
    if (static_cast<std::ptrdiff_t>(m) != neutral_index) shown.push_back(names[m]);
  grid.title =
      fmt::format("human | {}{}{}", fmt::join(shown, " | "), result.ground_truth ? " | ground truth" : "",
                  result.ground_truth
                      ? " (moving-vertex mean mm" + std::string(options.sheet == "worst" ? "; worst faces first)" : ")")
                      : "");
  const int columns = 1 + static_cast<int>(shown.size()) + (result.ground_truth ? 1 : 0);
  result.sheet_path = (fs::path(options.out) / "contact_sheet.png").string();
  write_png(result.sheet_path, render_grid(cells, columns, grid));
}

}  // namespace

RetargetEvaluation evaluate_retargeting(const RetargetEvaluationOptions& options) {
  options.validate();
  const Stopwatch clock;
  RetargetEvaluation result;
  const EvaluationInputs in = load_inputs(options, result.ground_truth);
  fs::create_directories(options.out);
  const RigWeightFit fit(in.rig);
  const MethodOutputs outputs = collect_outputs(options, in, fit);

  nlohmann::ordered_json report;
  report["faces"] = fs::absolute(options.faces).string();
  report["correspondences"] = fs::absolute(options.correspondences).string();
  report["human_dataset"] = in.corr.human_dataset;
  report["avatar"] = in.avatar.name;
  report["samples"] = in.faces.faces.size();
  report["mm_per_unit"] = in.mm;
  report["ground_truth"] = result.ground_truth ? "recipe weights mapped through the controller table, on the rig"
                                               : "none (faces without recipe weights)";
  // Where the rig moves, by region (regions named by the table rows' human shapes).
  std::map<std::string, std::vector<std::string>> row_names;
  for (const auto& [controller, row] : in.table)
    for (const auto& [shape, weight] : row) row_names[controller].push_back(shape);
  const RigFootprint footprint = rig_footprint(in.rig, kStillMm / in.mm, row_names);
  result.moving_vertices = static_cast<int>(footprint.moving.size());
  for (const auto& [region, vertices] : footprint.regions)
    result.region_vertices[region] = static_cast<int>(vertices.size());
  report["moving_vertices"] = result.moving_vertices;
  report["region_vertices"] = result.region_vertices;
  report["weight_active_threshold"] = kActiveWeight;

  std::vector<std::vector<double>> face_moving(outputs.names.size());  // [method][face]
  if (result.ground_truth) {
    std::vector<size_t> all(in.faces.faces.size());
    for (size_t i = 0; i < all.size(); ++i) all[i] = i;
    const std::vector<std::string> sets = in.faces.sets();
    for (size_t m = 0; m < outputs.names.size(); ++m) {
      const std::vector<FaceScore> faces = score_faces(outputs.meshes[m], in, footprint, fit);
      for (const FaceScore& f : faces) face_moving[m].push_back(f.mesh.moving_mean);
      result.methods.push_back(summarise(outputs.names[m], faces, in, all));
      result.methods.back().identity_spread_mm = identity_spread(outputs.meshes[m], in, all, footprint.moving);
      // Per set only when there is more than one: otherwise the set is the whole.
      for (size_t k = 0; sets.size() > 1 && k < sets.size(); ++k) {
        std::vector<size_t> which;
        for (size_t i : all)
          if (in.faces.faces[i].set == sets[k]) which.push_back(i);
        result.sets[sets[k]].push_back(summarise(outputs.names[m], faces, in, which));
        result.sets[sets[k]].back().identity_spread_mm =
            identity_spread(outputs.meshes[m], in, which, footprint.moving);
      }
    }
    add_fractions_of_neutral(result.methods);
    for (const MethodScore& s : result.methods) report["methods"][s.name] = score_json(s);
    for (auto& [set, scores] : result.sets) {
      add_fractions_of_neutral(scores);
      report["sets"][set]["samples"] = scores.front().samples;
      for (const MethodScore& s : scores) report["sets"][set]["methods"][s.name] = score_json(s);
    }
  }
  write_contact_sheet(options, in, outputs, face_moving, result);

  result.metrics_path = (fs::path(options.out) / "metrics.json").string();
  result.seconds = clock.seconds();
  report["seconds"] = result.seconds;
  write_file_atomically(result.metrics_path, [&](std::ostream& s) { s << report.dump(2) << "\n"; });
  if (result.ground_truth) {
    result.table_path = (fs::path(options.out) / "comparison.csv").string();
    write_file_atomically(result.table_path, [&](std::ostream& s) { s << comparison_csv(result); });
  }
  return result;
}

}  // namespace retarget
