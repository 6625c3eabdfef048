#include "eval/error_ladder.h"

#include <fmt/format.h>
#include <torch/torch.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <functional>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <regex>
#include <set>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/log.h"
#include "core/timer.h"
#include "correspond/correspondence.h"
#include "data/dataset.h"
#include "data/still_vertices.h"
#include "data/test_faces.h"
#include "geometry/controller_correspondence.h"
#include "geometry/dr_features.h"
#include "geometry/expression_sampling.h"
#include "geometry/face_model.h"
#include "geometry/mesh_io.h"
#include "geometry/metrics.h"
#include "geometry/part_motion.h"
#include "geometry/reconstruction.h"
#include "geometry/rig.h"
#include "geometry/rig_footprint.h"
#include "geometry/rig_weight_fit.h"
#include "geometry/topology_fingerprint.h"
#include "train/vae_run.h"
#include "translate/translation_run.h"

namespace retarget {

namespace fs = std::filesystem;

void ErrorLadderOptions::validate() const {
  if (correspondences.empty())
    throw Error("--correspondences", "expected a correspondence folder (written by `retarget correspond`)");
  if (!fs::is_directory(correspondences)) throw Error("--correspondences", "no such folder: " + correspondences);
  if (translation.empty()) throw Error("--translation", "expected a translation run folder");
  if (!fs::is_directory(translation)) throw Error("--translation", "no such folder: " + translation);
  static const std::regex stage("stage[1-9][0-9]*");
  if (checkpoint != "last" && !std::regex_match(checkpoint, stage))
    throw Error("--checkpoint", fmt::format("expected 'last' or 'stage<N>', got '{}'", checkpoint));
  if (!table.empty() && !fs::is_regular_file(table)) throw Error("--table", "no such file: " + table);
  if (batch < 1) throw Error("--batch", fmt::format("expected at least 1, got {}", batch));
}

namespace {

constexpr double kStillMillimetres = 0.1;  // a vertex moving less than this counts as still

double not_a_number() { return std::numeric_limits<double>::quiet_NaN(); }

std::string absolute_path(const std::string& path) { return fs::absolute(path).lexically_normal().string(); }

bool same_folder(const std::string& a, const std::string& b) {
  std::error_code ea, eb;
  const fs::path ca = fs::weakly_canonical(a, ea), cb = fs::weakly_canonical(b, eb);
  return !ea && !eb ? ca == cb : absolute_path(a) == absolute_path(b);
}

// Millimetres per unit of a rest mesh from its eye landmarks; without them, mesh units.
struct Scale {
  double mm_per_unit = 1;
  std::string unit = "mm";
};

Scale scale_of(const Positions& rest, const EyeLandmarks& eyes, const std::string& what) {
  if (eyes.left.empty() || eyes.right.empty()) {
    log::warn("{}: no eye landmarks; its rungs are in mesh units, not mm", what);
    return {1.0, "units"};
  }
  return {millimetres_per_unit(rest, eyes), "mm"};
}

// Calls body(begin, end) over [0, n) in steps of `batch`.
void for_batches(int64_t n, int64_t batch, const std::function<void(int64_t, int64_t)>& body) {
  for (int64_t begin = 0; begin < n; begin += batch) body(begin, std::min(n, begin + batch));
}

// codes [B, latent] float32 -> B meshes (#V x 3, the dataset's rest units): the VAE's decoder,
// its dataset's denormalisation, then `reconstruction` (built on that dataset's rest mesh).
std::vector<Positions> decoded_meshes(TrainedVae& vae, const torch::Tensor& codes,
                                      const Reconstruction& reconstruction) {
  const Normaliser& out = decoder_normaliser(vae.dataset, vae.config.data);
  const torch::Tensor features =
      out.denormalise(vae.vae->decode(codes.to(torch::kFloat32))).to(torch::kFloat32).contiguous();
  return reconstruction.reconstruct_batch(features.data_ptr<float>(), static_cast<int>(features.size(0)));
}

// Meshes -> their DR features [B, V, 9] float32 against `dr`'s rest.
torch::Tensor dr_features_of(const DrFeatures& dr, const std::vector<Positions>& meshes) {
  torch::Tensor out = torch::empty({static_cast<int64_t>(meshes.size()), dr.vertex_count(), kDrWidth}, torch::kFloat32);
  std::vector<const Positions*> pointers;
  for (const Positions& m : meshes) pointers.push_back(&m);
  if (!meshes.empty()) dr.compute_batch(pointers, out.data_ptr<float>());
  return out;
}

// rows[begin, end) as an index tensor [end - begin] int64.
torch::Tensor index_tensor(const std::vector<int64_t>& rows, int64_t begin, int64_t end) {
  return torch::tensor(std::vector<int64_t>(rows.begin() + begin, rows.begin() + end), torch::kInt64);
}

// One rung's running sums: each output against its truth, and the trivial answer against the
// same truth (given when the caller has it already, else computed).
class RungScorer {
 public:
  RungScorer(LadderRung& rung, const RigFootprint& footprint, const Positions& trivial, double scale)
      : rung_(rung), footprint_(footprint), trivial_(trivial), scale_(scale) {}

  void add(const Positions& output, const Positions& truth, const std::string& expression = "",
           const ExpressionError* trivial = nullptr) {
    const ExpressionError e = expression_error(output, truth, scale_, footprint_);
    const ExpressionError t = trivial ? *trivial : expression_error(trivial_, truth, scale_, footprint_);
    error_.add(e);
    trivial_error_.add(t);
    if (!expression.empty()) {
      expression_error_[expression].add(e);
      expression_trivial_[expression].add(t);
    }
  }

  void finish(double seconds) {
    rung_.samples = error_.count;
    rung_.error = error_.averaged();
    rung_.trivial_error = trivial_error_.averaged();
    const bool scored = rung_.samples > 0;
    rung_.fraction =
        scored && rung_.trivial_error.mean > 0 ? rung_.error.mean / rung_.trivial_error.mean : not_a_number();
    rung_.moving_fraction = scored && rung_.trivial_error.moving_mean > 0
                                ? rung_.error.moving_mean / rung_.trivial_error.moving_mean
                                : not_a_number();
    for (const auto& [expression, sum] : expression_error_) rung_.expression_error[expression] = sum.averaged();
    for (const auto& [expression, sum] : expression_trivial_) rung_.expression_trivial[expression] = sum.averaged();
    rung_.seconds = seconds;
    if (!scored) log::warn("error ladder: rung {} ({}) has no samples", rung_.number, rung_.name);
  }

 private:
  LadderRung& rung_;
  const RigFootprint& footprint_;
  const Positions& trivial_;
  double scale_;
  ExpressionErrorSum error_, trivial_error_;
  std::map<std::string, ExpressionErrorSum> expression_error_, expression_trivial_;
};

LadderRung make_rung(int number, std::string key, std::string name, std::string side, std::string truth,
                     std::string trivial, const std::string& unit) {
  LadderRung r;
  r.number = number;
  r.key = std::move(key);
  r.name = std::move(name);
  r.side = std::move(side);
  r.truth = std::move(truth);
  r.trivial = std::move(trivial);
  r.unit = unit;
  return r;
}

nlohmann::json number_or_null(double value) { return std::isfinite(value) ? nlohmann::json(value) : nlohmann::json(); }

nlohmann::ordered_json sum_json(const ExpressionErrorSum& s, bool scored) {
  nlohmann::ordered_json j;
  j["mean"] = scored ? number_or_null(s.mean) : nlohmann::json();
  j["moving_mean"] = scored ? number_or_null(s.moving_mean) : nlohmann::json();
  j["mean_of_max"] = scored ? number_or_null(s.mean_of_max) : nlohmann::json();
  j["max"] = scored ? number_or_null(s.max) : nlohmann::json();
  nlohmann::ordered_json regions = nlohmann::ordered_json::object();
  for (const auto& [region, value] : s.region_mean) regions[region] = number_or_null(value);
  j["regions"] = regions;
  return j;
}

nlohmann::ordered_json footprint_json(int vertices, int moving, const std::map<std::string, int>& regions) {
  nlohmann::ordered_json j;
  j["vertices"] = vertices;
  j["moving"] = moving;
  j["regions"] = regions;
  return j;
}

nlohmann::ordered_json ladder_json(const ErrorLadder& l) {
  nlohmann::ordered_json j;
  j["format"] = "retarget-error-ladder";
  j["format_version"] = 1;
  j["translation"] = l.translation;
  j["checkpoint"] = l.checkpoint;
  j["epoch"] = l.translation_epoch;
  j["correspondences"] = l.correspondences;
  j["human_vae"] = {{"run", l.human_vae}, {"checkpoint", l.human_checkpoint}};
  j["avatar_vae"] = {{"run", l.avatar_vae}, {"checkpoint", l.avatar_checkpoint}};
  j["human_dataset"] = l.human_dataset;
  j["avatar_dataset"] = l.avatar_dataset;
  j["rig"] = l.rig;
  j["table"] = l.table;
  j["avatar_mm_per_unit"] = l.avatar_mm_per_unit;
  j["human_mm_per_unit"] = l.human_mm_per_unit;
  j["footprint"]["avatar"] = footprint_json(l.avatar_vertices, l.avatar_moving, l.avatar_regions);
  j["footprint"]["human"] = footprint_json(l.human_vertices, l.human_moving, l.human_regions);
  j["rungs"] = nlohmann::ordered_json::array();
  for (const LadderRung& r : l.rungs) {
    const bool scored = r.samples > 0;
    nlohmann::ordered_json rung;
    rung["rung"] = r.number;
    rung["key"] = r.key;
    rung["name"] = r.name;
    rung["side"] = r.side;
    rung["truth"] = r.truth;
    rung["trivial"] = r.trivial;
    rung["unit"] = r.unit;
    rung["samples"] = r.samples;
    rung["error"] = sum_json(r.error, scored);
    rung["trivial_error"] = sum_json(r.trivial_error, scored);
    rung["fraction"] = number_or_null(r.fraction);
    rung["moving_fraction"] = number_or_null(r.moving_fraction);
    nlohmann::ordered_json expressions = nlohmann::ordered_json::object();
    for (const auto& [expression, e] : r.expression_error) {
      const ExpressionErrorSum& t = r.expression_trivial.at(expression);
      expressions[expression] = {{"samples", e.count},
                                 {"mean", e.mean},
                                 {"moving_mean", e.moving_mean},
                                 {"trivial_mean", t.mean},
                                 {"trivial_moving_mean", t.moving_mean}};
    }
    rung["expressions"] = expressions;
    rung["seconds"] = r.seconds;
    j["rungs"].push_back(rung);
  }
  j["seconds"] = l.seconds;
  return j;
}

// What every rung reads: the runs, their datasets, the rig, the ground truth of each reference
// expression, units, footprints and reconstructions.
struct LadderInputs {
  Correspondences corr;
  TrainedTranslation f;
  TrainedVae human, avatar;
  Rig rig;
  std::string table_path;
  ControllerCorrespondence table;
  std::vector<ExpressionRecipe> recipes;
  std::vector<Positions> truth;                  // [K] the rig expression of each reference expression
  std::vector<ExpressionError> truth_trivial;    // [K] the neutral mesh against it
  std::map<int64_t, int64_t> correspondence_of;  // human expression index -> k
  Scale avatar_scale, human_scale;
  RigFootprint avatar_footprint, human_footprint;
  std::unique_ptr<const Reconstruction> avatar_reconstruction, human_reconstruction;
  std::vector<Positions> target_meshes;  // [E] the identity-averaged human targets as meshes

  const Dataset& hd() const { return human.dataset; }
  const Dataset& ad() const { return avatar.dataset; }
  const Positions& neutral() const { return rig.neutral.vertices; }
  const ExpressionRecipe* recipe_of(const std::string& expression) const {
    for (const ExpressionRecipe& r : recipes)
      if (r.name == expression) return &r;
    return nullptr;
  }
};

// The runs and their datasets, checked against each other.
void load_runs(const ErrorLadderOptions& options, LadderInputs& in) {
  in.corr = load_correspondences(options.correspondences);
  in.f = load_trained_translation(options.translation, options.checkpoint);
  const TranslationDataOptions& data = in.f.config.data;
  if (!same_folder(data.avatar_vae, in.corr.avatar_vae_run))
    throw Error(
        "--correspondences",
        fmt::format("{} were built with the avatar VAE {}, but the translation run {} maps into the codes of {}",
                    options.correspondences, in.corr.avatar_vae_run, options.translation, data.avatar_vae));
  if (!same_folder(data.correspondences, options.correspondences))
    log::info("error ladder: the translation run was trained with the correspondences {}; scoring with {}",
              data.correspondences, options.correspondences);
  in.human = load_trained_vae(data.human_vae, data.human_checkpoint);
  in.avatar = load_trained_vae(in.corr.avatar_vae_run, in.corr.avatar_vae_checkpoint);
  check_correspondences(in.corr, in.human.dataset, in.avatar.dataset);
  in.human.vae->eval();
  in.avatar.vae->eval();
  in.f.translation->eval();
}

// The rig and the controller table (--table, or correspondence.yaml beside the rig); returns
// each controller's human shapes (the footprint's regions).
std::map<std::string, std::vector<std::string>> load_rig_and_table(const ErrorLadderOptions& options, LadderInputs& in,
                                                                   ControllerCorrespondence& table) {
  const Dataset& ad = in.ad();
  in.rig = load_dataset_rig(ad);
  std::vector<std::string> controllers;
  for (const Controller& c : in.rig.controllers) controllers.push_back(c.name);
  if (!ad.controllers.empty() && controllers != ad.controllers)
    throw Error(ad.source, fmt::format("the rig's controllers ({}) are not the avatar dataset's ({}: {})",
                                       fmt::join(controllers, ", "), ad.folder, fmt::join(ad.controllers, ", ")));

  const fs::path rig_path(ad.source);
  in.table_path =
      !options.table.empty()
          ? options.table
          : ((fs::is_directory(rig_path) ? rig_path : rig_path.parent_path()) / "correspondence.yaml").string();
  if (!fs::is_regular_file(in.table_path))
    throw Error(in.table_path, "no controller table for the ground truth (give one with --table)");
  table = load_controller_correspondence(in.table_path);
  std::vector<std::string> table_shapes;
  std::map<std::string, std::vector<std::string>> controller_shapes;
  for (const auto& [controller, row] : table)
    for (const auto& [shape, weight] : row) {
      table_shapes.push_back(shape);
      controller_shapes[controller].push_back(shape);
    }
  check_controller_correspondence(table, controllers, table_shapes, in.table_path);

  const Dataset& hd = in.hd();
  if (hd.recipes.empty())
    throw Error(hd.folder,
                "the human dataset has no expression recipes (it was built from a face folder), so its expressions "
                "have no ground truth on the avatar");
  if (!fs::is_regular_file(hd.recipes)) throw Error(hd.folder, "its expression recipes " + hd.recipes + " are missing");
  in.recipes = load_expression_recipes(hd.recipes);
  std::set<std::string> unmapped;
  for (const ExpressionRecipe& r : in.recipes)
    for (const auto& [shape, weight] : r.weights)
      if (std::find(table_shapes.begin(), table_shapes.end(), shape) == table_shapes.end()) unmapped.insert(shape);
  if (!unmapped.empty())
    log::warn("{}: no controller stands for the human shapes {} (their recipe weights are ignored)", in.table_path,
              fmt::join(unmapped, ", "));
  return controller_shapes;
}

// Ground truth of each reference expression k of the correspondences, on the rig.
void load_truth(const ErrorLadderOptions& options, const ControllerCorrespondence& table, LadderInputs& in) {
  const Dataset& hd = in.hd();
  in.truth.reserve(in.corr.expressions.size());
  for (const std::string& expression : in.corr.expressions) {
    const ExpressionRecipe* recipe = in.recipe_of(expression);
    if (!recipe)
      throw Error(hd.recipes, fmt::format("no recipe for the expression \"{}\" of the correspondences in {}",
                                          expression, options.correspondences));
    in.truth.push_back(in.rig.evaluate(rig_weights_from_human(table, in.rig, recipe->weights)));
  }
  for (int64_t e = 0; e < static_cast<int64_t>(hd.expressions.size()); ++e) {
    const auto it = std::find(in.corr.expressions.begin(), in.corr.expressions.end(), hd.expressions[e]);
    if (it != in.corr.expressions.end()) in.correspondence_of[e] = it - in.corr.expressions.begin();
  }
}

// Units, footprints and reconstructions on both sides.
void prepare_scoring(const ErrorLadderOptions& options,
                     const std::map<std::string, std::vector<std::string>>& controller_shapes, LadderInputs& in) {
  const Dataset& hd = in.hd();
  const Dataset& ad = in.ad();
  in.avatar_scale = scale_of(in.rig.neutral.vertices, ad.eyes.left.empty() ? in.rig.eyes : ad.eyes, ad.folder);
  in.human_scale = scale_of(hd.rest.vertices, hd.eyes, hd.folder);
  in.avatar_footprint = rig_footprint(in.rig, kStillMillimetres / in.avatar_scale.mm_per_unit, controller_shapes);
  ReconstructionOptions reconstruction_options;
  reconstruction_options.weighting = ad.dr.weighting;
  if (options.anchors) reconstruction_options.anchors = still_vertices(ad);  // as the bundle rebuilds avatar meshes
  if (options.part_motion)
    if (std::vector<std::vector<int>> parts = rig_parts_to_move(in.rig); !parts.empty())
      reconstruction_options.parts = std::make_shared<const PartMotion>(in.rig, std::move(parts));
  in.avatar_reconstruction = std::make_unique<const Reconstruction>(ad.rest, reconstruction_options);
  reconstruction_options.anchors.clear();
  reconstruction_options.parts.reset();
  reconstruction_options.weighting = hd.dr.weighting;
  in.human_reconstruction = std::make_unique<const Reconstruction>(hd.rest, reconstruction_options);

  // The identity-averaged human targets as meshes, and where they move: each target is a
  // "controller" classified by its recipe's blendshapes.
  const torch::Tensor targets = hd.targets.to(torch::kFloat32).contiguous();
  in.target_meshes =
      in.human_reconstruction->reconstruct_batch(targets.data_ptr<float>(), static_cast<int>(targets.size(0)));
  Rig expressions;
  expressions.neutral = hd.rest;
  std::map<std::string, std::vector<std::string>> shapes;
  for (size_t e = 0; e < hd.expressions.size(); ++e) {
    expressions.controllers.push_back({hd.expressions[e], Positions(in.target_meshes[e] - hd.rest.vertices)});
    if (const ExpressionRecipe* r = in.recipe_of(hd.expressions[e]))
      for (const auto& [shape, weight] : r->weights) shapes[hd.expressions[e]].push_back(shape);
  }
  in.human_footprint = rig_footprint(expressions, kStillMillimetres / in.human_scale.mm_per_unit, shapes);

  for (const Positions& t : in.truth)
    in.truth_trivial.push_back(expression_error(in.neutral(), t, in.avatar_scale.mm_per_unit, in.avatar_footprint));
}

const char* const kAvatarTruth = "the rig expression the controller table gives for the recipe";
const char* const kAvatarTrivial = "the avatar's neutral mesh";

// A rung on the avatar side, scored by `score(scorer)` against the neutral mesh.
LadderRung avatar_rung(const LadderInputs& in, int number, const std::string& key, const std::string& name,
                       const std::string& truth, const std::function<void(RungScorer&)>& score) {
  const Stopwatch clock;
  LadderRung rung = make_rung(number, key, name, "avatar", truth, kAvatarTrivial, in.avatar_scale.unit);
  RungScorer scorer(rung, in.avatar_footprint, in.neutral(), in.avatar_scale.mm_per_unit);
  score(scorer);
  scorer.finish(clock.seconds());
  return rung;
}

// Scores meshes[i] against truth[k] for the reference expressions k = first + i.
void score_expressions(const LadderInputs& in, RungScorer& scorer, const std::vector<Positions>& meshes,
                       int64_t first) {
  for (size_t i = 0; i < meshes.size(); ++i) {
    const int64_t k = first + static_cast<int64_t>(i);
    scorer.add(meshes[i], in.truth[k], in.corr.expressions[k], &in.truth_trivial[k]);
  }
}

// Rung 1: the avatar VAE on held-out rig samples.
LadderRung avatar_vae_rung(LadderInputs& in, int64_t batch) {
  return avatar_rung(in, 1, "avatar_vae_test", "avatar VAE, held-out rig samples",
                     "the rig at the sample's stored weights", [&](RungScorer& scorer) {
                       const Dataset& ad = in.ad();
                       const std::vector<int64_t>& rows = ad.test;
                       for_batches(static_cast<int64_t>(rows.size()), batch, [&](int64_t begin, int64_t end) {
                         const torch::Tensor idx = index_tensor(rows, begin, end);
                         const torch::Tensor x =
                             ad.normaliser.normalise(ad.features.index_select(0, idx)).to(torch::kFloat32);
                         const std::vector<Positions> meshes =
                             decoded_meshes(in.avatar, in.avatar.vae->encode(x).mean, *in.avatar_reconstruction);
                         const torch::Tensor w = ad.weights.index_select(0, idx).to(torch::kFloat64).contiguous();
                         const Eigen::MatrixXd weights =
                             Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
                                 w.data_ptr<double>(), w.size(0), w.size(1));
                         const std::vector<Positions> truths = evaluate_samples(in.rig, weights);
                         for (size_t i = 0; i < meshes.size(); ++i) scorer.add(meshes[i], truths[i]);
                       });
                     });
}

// Rung 2: the ground-truth avatar code through the decoder (the best any F could do). The truth
// is encoded within the training range, as the correspondences encode avatar samples.
LadderRung avatar_truth_rung(LadderInputs& in, int64_t batch) {
  return avatar_rung(
      in, 2, "avatar_vae_truth", "avatar VAE, ground-truth expressions", kAvatarTruth, [&](RungScorer& scorer) {
        const DrFeatures dr(in.ad().rest, in.ad().dr);
        for_batches(in.corr.expression_count(), batch, [&](int64_t begin, int64_t end) {
          const std::vector<Positions> part(in.truth.begin() + begin, in.truth.begin() + end);
          const torch::Tensor codes = encoder_means(in.avatar, dr_features_of(dr, part), /*clamp_to_range=*/true);
          score_expressions(in, scorer, decoded_meshes(in.avatar, codes, *in.avatar_reconstruction), begin);
        });
      });
}

// Rung 3: the human VAE on unseen people, against the identity-averaged targets.
LadderRung human_vae_rung(LadderInputs& in, int64_t batch) {
  const Stopwatch clock;
  const Dataset& hd = in.hd();
  LadderRung rung = make_rung(3, "human_vae_test", "human VAE, unseen people", "human",
                              "the identity-averaged target of the expression", "the human rest mesh (the mean face)",
                              in.human_scale.unit);
  std::vector<ExpressionError> target_trivial;
  for (const Positions& t : in.target_meshes)
    target_trivial.push_back(expression_error(hd.rest.vertices, t, in.human_scale.mm_per_unit, in.human_footprint));
  RungScorer scorer(rung, in.human_footprint, hd.rest.vertices, in.human_scale.mm_per_unit);
  const std::vector<int64_t>& rows = hd.test;
  for_batches(static_cast<int64_t>(rows.size()), batch, [&](int64_t begin, int64_t end) {
    const torch::Tensor idx = index_tensor(rows, begin, end);
    const torch::Tensor x = hd.normaliser.normalise(hd.features.index_select(0, idx)).to(torch::kFloat32);
    const std::vector<Positions> meshes =
        decoded_meshes(in.human, in.human.vae->encode(x).mean, *in.human_reconstruction);
    const torch::Tensor expression = hd.expression.index_select(0, idx).contiguous();
    const auto expression_of = expression.accessor<int64_t, 1>();
    for (size_t i = 0; i < meshes.size(); ++i) {
      const int64_t e = expression_of[static_cast<int64_t>(i)];
      scorer.add(meshes[i], in.target_meshes[e], hd.expressions[e], &target_trivial[e]);
    }
  });
  scorer.finish(clock.seconds());
  return rung;
}

// Rung 4: the deformation-transfer results (their meshes as written, else rebuilt from their
// stored features); `dt_meshes` gets them for rung 5.
LadderRung dt_rung(const ErrorLadderOptions& options, const LadderInputs& in, std::vector<Positions>& dt_meshes) {
  return avatar_rung(in, 4, "dt", "deformation transfer (DT) result", kAvatarTruth, [&](RungScorer& scorer) {
    const torch::Tensor dt_features = in.corr.dt_features.to(torch::kFloat32).contiguous();
    const Positions& neutral = in.neutral();
    for (int64_t k = 0; k < in.corr.expression_count(); ++k) {
      const fs::path file = fs::path(options.correspondences) / "dt" / (in.corr.expressions[k] + ".obj");
      Positions mesh;
      if (fs::is_regular_file(file)) {
        mesh = read_mesh(file.string()).vertices;
        if (mesh.rows() != neutral.rows())
          throw Error(file.string(), fmt::format("has {} vertices; the avatar has {}", mesh.rows(), neutral.rows()));
      } else {
        mesh = in.avatar_reconstruction->reconstruct(dt_features[k].contiguous().data_ptr<float>());
      }
      scorer.add(mesh, in.truth[k], in.corr.expressions[k], &in.truth_trivial[k]);
      dt_meshes.push_back(std::move(mesh));
    }
  });
}

// Rung 5: the DT results projected onto the rig (what y0 starts from with initial: rig).
LadderRung dt_rig_rung(const LadderInputs& in, const std::vector<Positions>& dt_meshes) {
  return avatar_rung(in, 5, "dt_rig", "DT projected onto the rig", kAvatarTruth, [&](RungScorer& scorer) {
    const RigWeightFit fit(in.rig);
    for (int64_t k = 0; k < in.corr.expression_count(); ++k)
      scorer.add(fit.project(dt_meshes[k]), in.truth[k], in.corr.expressions[k], &in.truth_trivial[k]);
  });
}

// Rung 6: y0 through the avatar decoder.
LadderRung y0_rung(LadderInputs& in, int64_t batch) {
  return avatar_rung(in, 6, "y0", "y0 through the decoder", kAvatarTruth, [&](RungScorer& scorer) {
    for_batches(in.corr.expression_count(), batch, [&](int64_t begin, int64_t end) {
      score_expressions(in, scorer,
                        decoded_meshes(in.avatar, in.corr.y0.slice(0, begin, end), *in.avatar_reconstruction), begin);
    });
  });
}

// Rungs 7, 8: the whole chain, human mesh -> human encoder mean -> F -> avatar decoder -> mesh,
// on the samples of `split` whose expression has a correspondence.
LadderRung f_rung(LadderInputs& in, int64_t batch, int number, const std::string& key, const std::string& name,
                  const std::vector<int64_t>& split) {
  return avatar_rung(in, number, key, name, kAvatarTruth, [&](RungScorer& scorer) {
    const Dataset& hd = in.hd();
    std::vector<int64_t> rows;
    const torch::Tensor expression = hd.expression.contiguous();
    const auto expression_of = expression.accessor<int64_t, 1>();
    for (int64_t row : split)
      if (in.correspondence_of.count(expression_of[row])) rows.push_back(row);
    for_batches(static_cast<int64_t>(rows.size()), batch, [&](int64_t begin, int64_t end) {
      const torch::Tensor idx = index_tensor(rows, begin, end);
      const torch::Tensor x = encoder_means(in.human, hd.features.index_select(0, idx));
      const torch::Tensor y = in.f.translation->forward(x);
      const std::vector<Positions> meshes = decoded_meshes(in.avatar, y, *in.avatar_reconstruction);
      for (size_t i = 0; i < meshes.size(); ++i) {
        const int64_t k = in.correspondence_of.at(expression_of[rows[begin + static_cast<int64_t>(i)]]);
        scorer.add(meshes[i], in.truth[k], in.corr.expressions[k], &in.truth_trivial[k]);
      }
    });
  });
}

// The blends of a faces folder (`retarget faces --blends N`), checked against the human dataset,
// with their truth: the rig at each blend's recipe weights through the table.
struct LadderBlends {
  TestFaces faces;
  std::vector<const TestFace*> blends;  // into faces
  std::vector<Positions> truth;         // per blend
};
LadderBlends ladder_blends(const ErrorLadderOptions& options, const LadderInputs& in) {
  LadderBlends b{load_test_faces(options.faces), {}, {}};
  if (b.faces.fingerprint != in.hd().fingerprint)
    throw Error(options.faces, fmt::format("faces of topology {} but the human dataset {} has {}", b.faces.fingerprint,
                                           in.hd().folder, in.hd().fingerprint));
  for (const TestFace& f : b.faces.faces)
    if (f.set == kBlendSet) b.blends.push_back(&f);
  if (b.blends.empty()) throw Error(options.faces, "has no blends (write them with `retarget faces --blends N`)");
  for (const TestFace* f : b.blends)
    b.truth.push_back(in.rig.evaluate(rig_weights_from_human(in.table, in.rig, f->weights)));
  return b;
}

// Rung 9: the whole chain on the unseen blends of a faces folder, each against the rig at its
// blend's weights through the table.
LadderRung f_blends_rung(const ErrorLadderOptions& options, const LadderBlends& b, LadderInputs& in, int64_t batch) {
  return avatar_rung(
      in, 9, "f_blends", "F, unseen blends", "the rig at the blend's weights through the table",
      [&](RungScorer& scorer) {
        const DrFeatures dr(in.hd().rest, in.hd().dr);
        for_batches(static_cast<int64_t>(b.blends.size()), batch, [&](int64_t begin, int64_t end) {
          std::vector<Positions> inputs;
          for (int64_t i = begin; i < end; ++i)
            inputs.push_back(
                read_mesh((fs::path(options.faces) / b.blends[static_cast<size_t>(i)]->file).string()).vertices);
          const torch::Tensor x = encoder_means(in.human, dr_features_of(dr, inputs));
          const std::vector<Positions> meshes =
              decoded_meshes(in.avatar, in.f.translation->forward(x), *in.avatar_reconstruction);
          for (size_t i = 0; i < meshes.size(); ++i) {
            const size_t k = static_cast<size_t>(begin) + i;
            scorer.add(meshes[i], b.truth[k], b.blends[k]->expression);
          }
        });
      });
}

// Rung 10: each blend's ground-truth rig mesh through the avatar VAE (encoded within the training
// range, as rung 2): the best any F could do on the blends, the floor of every method that goes
// through the avatar decoder.
LadderRung avatar_blends_rung(const LadderBlends& b, LadderInputs& in, int64_t batch) {
  return avatar_rung(
      in, 10, "avatar_vae_blends", "avatar VAE, ground-truth blends",
      "the rig at the blend's weights through the table", [&](RungScorer& scorer) {
        const DrFeatures dr(in.ad().rest, in.ad().dr);
        for_batches(static_cast<int64_t>(b.blends.size()), batch, [&](int64_t begin, int64_t end) {
          const std::vector<Positions> truth(b.truth.begin() + begin, b.truth.begin() + end);
          const torch::Tensor codes = encoder_means(in.avatar, dr_features_of(dr, truth), /*clamp_to_range=*/true);
          const std::vector<Positions> meshes = decoded_meshes(in.avatar, codes, *in.avatar_reconstruction);
          for (size_t i = 0; i < meshes.size(); ++i)
            scorer.add(meshes[i], truth[i], b.blends[static_cast<size_t>(begin) + i]->expression);
        });
      });
}

// The report's provenance and footprints.
void describe(const ErrorLadderOptions& options, const LadderInputs& in, ErrorLadder& ladder) {
  ladder.translation = absolute_path(options.translation);
  ladder.checkpoint = options.checkpoint;
  ladder.translation_epoch = in.f.state.epoch;
  ladder.correspondences = absolute_path(options.correspondences);
  ladder.table = absolute_path(in.table_path);
  ladder.human_vae = absolute_path(in.human.folder);
  ladder.human_checkpoint = in.f.config.data.human_checkpoint;
  ladder.avatar_vae = absolute_path(in.avatar.folder);
  ladder.avatar_checkpoint = in.corr.avatar_vae_checkpoint;
  ladder.human_dataset = absolute_path(in.hd().folder);
  ladder.avatar_dataset = absolute_path(in.ad().folder);
  ladder.rig = in.ad().source;
  ladder.avatar_mm_per_unit = in.avatar_scale.mm_per_unit;
  ladder.human_mm_per_unit = in.human_scale.mm_per_unit;
  ladder.avatar_vertices = in.rig.neutral.vertex_count();
  ladder.avatar_moving = static_cast<int>(in.avatar_footprint.moving.size());
  for (const auto& [region, vertices] : in.avatar_footprint.regions)
    ladder.avatar_regions[region] = static_cast<int>(vertices.size());
  ladder.human_vertices = in.hd().vertex_count();
  ladder.human_moving = static_cast<int>(in.human_footprint.moving.size());
  for (const auto& [region, vertices] : in.human_footprint.regions)
    ladder.human_regions[region] = static_cast<int>(vertices.size());
}

}  // namespace

ErrorLadder error_ladder(const ErrorLadderOptions& options) {
  options.validate();
  const Stopwatch clock;
  torch::NoGradGuard no_grad;

  LadderInputs in;
  load_runs(options, in);
  ControllerCorrespondence table;
  const auto controller_shapes = load_rig_and_table(options, in, table);
  in.table = table;
  load_truth(options, table, in);
  prepare_scoring(options, controller_shapes, in);

  ErrorLadder ladder;
  const int64_t batch = options.batch;
  ladder.rungs.push_back(avatar_vae_rung(in, batch));
  ladder.rungs.push_back(avatar_truth_rung(in, batch));
  ladder.rungs.push_back(human_vae_rung(in, batch));
  std::vector<Positions> dt_meshes;  // [K], rung 4 -> rung 5
  ladder.rungs.push_back(dt_rung(options, in, dt_meshes));
  ladder.rungs.push_back(dt_rig_rung(in, dt_meshes));
  ladder.rungs.push_back(y0_rung(in, batch));
  ladder.rungs.push_back(f_rung(in, batch, 7, "f_train", "F, training people", in.hd().train));
  ladder.rungs.push_back(f_rung(in, batch, 8, "f_test", "F, unseen people", in.hd().test));
  if (!options.faces.empty()) {
    const LadderBlends blends = ladder_blends(options, in);
    ladder.rungs.push_back(f_blends_rung(options, blends, in, batch));
    ladder.rungs.push_back(avatar_blends_rung(blends, in, batch));
  }

  describe(options, in, ladder);
  const fs::path out = options.out.empty() ? fs::path(options.translation) / "ladder" : fs::path(options.out);
  fs::create_directories(out);
  ladder.json_path = (out / "ladder.json").string();
  ladder.seconds = clock.seconds();
  const nlohmann::ordered_json report = ladder_json(ladder);
  write_file_atomically(ladder.json_path, [&](std::ostream& s) { s << report.dump(2) << "\n"; });
  return ladder;
}

std::string ladder_table(const ErrorLadder& ladder) {
  auto figure = [](double value, int precision) {
    return std::isfinite(value) ? fmt::format("{:.{}f}", value, precision) : std::string("-");
  };
  std::string text = fmt::format("{:<44}{:>6}{:>10}{:>11}{:>12}{:>19}{:>21}\n", "rung", "n", "mean mm", "moving mm",
                                 "neutral mm", "neutral moving mm", "x neutral (moving)");
  bool units = false;
  for (const LadderRung& r : ladder.rungs) {
    const bool scored = r.samples > 0;
    const double nan = not_a_number();
    units = units || r.unit != "mm";
    text += fmt::format("{:<44}{:>6}{:>10}{:>11}{:>12}{:>19}{:>21}\n",
                        fmt::format("{} {}{}", r.number, r.name, r.unit != "mm" ? " *" : ""), r.samples,
                        figure(scored ? r.error.mean : nan, 3), figure(scored ? r.error.moving_mean : nan, 3),
                        figure(scored ? r.trivial_error.mean : nan, 3),
                        figure(scored ? r.trivial_error.moving_mean : nan, 3),
                        fmt::format("{} ({})", figure(r.fraction, 2), figure(r.moving_fraction, 2)));
  }
  if (units) text += "* in mesh units: the dataset has no eye landmarks\n";
  return text;
}

}  // namespace retarget
