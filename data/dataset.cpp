#include "data/dataset.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <ctime>
#include <exception>
#include <filesystem>
#include <set>

#include "core/atomic_file.h"
#include "core/config.h"
#include "core/error.h"
#include "core/log.h"
#include "core/progress.h"
#include "core/random.h"
#include "core/tensor_io.h"
#include "core/timer.h"
#include "geometry/expression_sampling.h"
#include "geometry/face_folder.h"
#include "geometry/mesh_io.h"
#include "geometry/mesh_validation.h"
#include "geometry/rig.h"
#include "geometry/topology_fingerprint.h"

namespace retarget {

namespace fs = std::filesystem;

namespace {

constexpr const char* kManifest = "manifest.yaml";
constexpr const char* kRest = "rest.obj";
constexpr const char* kFeatures = "features.pt";
constexpr const char* kNormaliser = "normaliser.pt";

// The split's shuffle gets a seed of its own (mix_seed), so that changing --samples does not
// reshuffle which kind of samples are held out in a way correlated with the sampling stream,
// which uses the seed itself. The trainers' streams are 1-6.
constexpr uint64_t kSplitStream = 100;

struct Split {
  std::vector<int64_t> train, test;  // ascending
};
Split split(int64_t n, int64_t test_count, uint64_t seed) {
  const std::vector<int64_t> order = Random(mix_seed(seed, kSplitStream)).permutation(n);
  Split s;
  s.test.assign(order.begin(), order.begin() + test_count);
  s.train.assign(order.begin() + test_count, order.end());
  std::sort(s.test.begin(), s.test.end());
  std::sort(s.train.begin(), s.train.end());
  return s;
}

// ---- Folder handling

// Refuses a non-empty folder unless `force`, before any work is done.
void check_folder(const std::string& folder, bool force) {
  if (folder.empty()) throw Error("--out", "give a folder for the dataset");
  if (!fs::exists(folder)) return;
  if (!fs::is_directory(folder)) throw Error(folder, "exists and is not a folder");
  if (!fs::is_empty(folder) && !force)
    throw Error(folder, "exists and is not empty; pass --force to replace the dataset in it");
}

// check_folder(), then creates the folder; with force, removes the old manifest first, so a
// build that fails half-way never leaves a manifest beside mismatched files.
void prepare_folder(const std::string& folder, bool force) {
  check_folder(folder, force);
  fs::remove(fs::path(folder) / kManifest);
  fs::create_directories(folder);
}

std::string absolute_path(const std::string& path) { return fs::absolute(path).lexically_normal().string(); }

std::vector<std::string> names_of(const std::vector<std::string>& all, const std::vector<int64_t>& indices) {
  std::vector<std::string> out;
  for (int64_t i : indices) out.push_back(all[i]);
  return out;
}

// ---- Writing

void write_manifest(const Dataset& d, const AvatarDatasetOptions* avatar) {
  YAML::Emitter y;
  y.SetDoublePrecision(17);
  y << YAML::BeginMap;
  y << YAML::Key << "format" << YAML::Value << kDatasetFormat;
  y << YAML::Key << "kind" << YAML::Value << to_string(d.kind);
  y << YAML::Key << "name" << YAML::Value << d.name;
  y << YAML::Key << "software_version" << YAML::Value << d.software_version;
  y << YAML::Key << "created" << YAML::Value << d.created;
  y << YAML::Key << "source" << YAML::Value << d.source;
  if (!d.gltf_meshes.empty()) y << YAML::Key << "gltf_meshes" << YAML::Value << YAML::Flow << d.gltf_meshes;
  y << YAML::Key << "units" << YAML::Value << d.units;
  y << YAML::Key << "vertex_count" << YAML::Value << d.vertex_count();
  y << YAML::Key << "topology_fingerprint" << YAML::Value << d.fingerprint;
  y << YAML::Key << "dr" << YAML::Value << YAML::Flow << YAML::BeginMap;
  y << YAML::Key << "weighting" << YAML::Value << to_string(d.dr.weighting);
  y << YAML::Key << "normal_term" << YAML::Value << d.dr.normal_term;
  y << YAML::Key << "normal_weight" << YAML::Value << d.dr.normal_weight << YAML::EndMap;
  y << YAML::Key << "seed" << YAML::Value << d.seed;
  y << YAML::Key << "sample_count" << YAML::Value << d.sample_count();
  if (d.kind == DatasetKind::avatar) {
    y << YAML::Key << "sampling" << YAML::Value << YAML::Flow << YAML::BeginMap;
    y << YAML::Key << "min_active" << YAML::Value << avatar->min_active;
    y << YAML::Key << "max_active" << YAML::Value << avatar->max_active;
    y << YAML::Key << "include_neutral" << YAML::Value << true << YAML::EndMap;
    y << YAML::Key << "controllers" << YAML::Value << YAML::Flow << d.controllers;
    y << YAML::Key << "split" << YAML::Value << YAML::BeginMap;
    y << YAML::Key << "test_fraction" << YAML::Value << avatar->test_fraction;
    y << YAML::Key << "train" << YAML::Value << YAML::Flow << d.train;
    y << YAML::Key << "test" << YAML::Value << YAML::Flow << d.test;
    y << YAML::EndMap;
  } else {
    if (!d.recipes.empty()) y << YAML::Key << "recipes" << YAML::Value << d.recipes;
    y << YAML::Key << "subjects" << YAML::Value << YAML::Flow << d.subjects;
    y << YAML::Key << "expressions" << YAML::Value << YAML::Flow << d.expressions;
    y << YAML::Key << "split" << YAML::Value << YAML::BeginMap;
    y << YAML::Key << "train" << YAML::Value << YAML::Flow << d.train_subjects;
    y << YAML::Key << "test" << YAML::Value << YAML::Flow << d.test_subjects;
    y << YAML::EndMap;
  }
  if (!d.landmarks.empty()) {
    y << YAML::Key << "landmarks" << YAML::Value << YAML::Flow << YAML::BeginMap;
    for (const auto& [name, index] : d.landmarks) y << YAML::Key << name << YAML::Value << index;
    y << YAML::EndMap;
  }
  if (!d.eyes.left.empty() || !d.eyes.right.empty()) {
    y << YAML::Key << "eyes" << YAML::Value << YAML::BeginMap;
    y << YAML::Key << "left" << YAML::Value << YAML::Flow << d.eyes.left;
    y << YAML::Key << "right" << YAML::Value << YAML::Flow << d.eyes.right << YAML::EndMap;
  }
  y << YAML::Key << "files" << YAML::Value << YAML::BeginMap;
  y << YAML::Key << "rest" << YAML::Value << kRest;
  y << YAML::Key << "features" << YAML::Value << kFeatures;
  y << YAML::Key << "normaliser" << YAML::Value << kNormaliser << YAML::EndMap;
  y << YAML::EndMap;
  if (!y.good()) throw Error(d.folder, "cannot write the manifest: " + y.GetLastError());
  write_file_atomically((fs::path(d.folder) / kManifest).string(), [&](std::ostream& out) {
    out << "# retarget dataset (see data/dataset.h); features.pt and normaliser.pt load with torch.load\n"
        << y.c_str() << "\n";
  });
}

void write_dataset(const Dataset& d, const AvatarDatasetOptions* avatar) {
  const Stopwatch clock;
  const fs::path dir(d.folder);
  remove_stale_temporaries(d.folder);  // a killed earlier write's features.pt.tmp.*
  write_mesh((dir / kRest).string(), d.rest);
  TensorMap tensors{{"features", d.features}};
  if (d.kind == DatasetKind::avatar) {
    tensors["weights"] = d.weights;
  } else {
    tensors["subject"] = d.subject;
    tensors["expression"] = d.expression;
    tensors["targets"] = d.targets;
    if (d.identity.defined()) tensors["identity"] = d.identity;
  }
  save_tensors((dir / kFeatures).string(), tensors);
  d.normaliser.save((dir / kNormaliser).string());
  write_manifest(d, avatar);
  log::debug("wrote {} in {:.2f} s", d.folder, clock.seconds());
}

// Fills the common fields of a dataset about to be written.
void describe(Dataset& d, const std::string& folder, DatasetKind kind, const std::string& source, Mesh rest,
              const DrOptions& dr, uint64_t seed) {
  d.folder = folder;
  d.kind = kind;
  d.software_version = RETARGET_VERSION;
  d.created = utc_timestamp();
  d.source = absolute_path(source);
  d.rest = std::move(rest);
  d.fingerprint = topology_fingerprint(d.rest);
  d.dr = dr;
  d.seed = seed;
}

// ---- Summary

// The normalised range of the given rows and the share of values with |y| > 1, in one pass
// over chunks of them.
struct Range {
  double min = 0, max = 0, outside = 0;
};
Range normalised_range(const Normaliser& n, const torch::Tensor& features, const std::vector<int64_t>& rows) {
  Range r;
  if (rows.empty()) return r;
  r.min = INFINITY;
  r.max = -INFINITY;
  int64_t outside = 0, total = 0;
  const torch::Tensor index = torch::tensor(rows, torch::kInt64);
  for (int64_t begin = 0; begin < index.size(0); begin += 256) {
    const torch::Tensor y =
        n.normalise(features.index_select(0, index.slice(0, begin, std::min<int64_t>(begin + 256, index.size(0)))));
    const auto [lo, hi] = torch::aminmax(y);
    r.min = std::min(r.min, lo.item<double>());
    r.max = std::max(r.max, hi.item<double>());
    outside += (y.abs() > 1).sum().item<int64_t>();
    total += y.numel();
  }
  r.outside = static_cast<double>(outside) / static_cast<double>(total);
  return r;
}

DatasetSummary summarise(const Dataset& d, const Stopwatch& clock, double features_seconds) {
  const Stopwatch summary_clock;
  DatasetSummary s;
  s.folder = d.folder;
  s.kind = d.kind;
  s.samples = d.sample_count();
  s.train = static_cast<int64_t>(d.train.size());
  s.test = static_cast<int64_t>(d.test.size());
  s.vertices = d.vertex_count();
  s.subjects = static_cast<int>(d.subjects.size());
  s.expressions = static_cast<int>(d.expressions.size());
  s.controllers = static_cast<int>(d.controllers.size());
  s.gltf_meshes = d.gltf_meshes;
  s.widened = (d.normaliser.max - d.normaliser.min <= kMinimumRange * (1 + 1e-3)).sum().item<int64_t>();
  const Range test = normalised_range(d.normaliser, d.features, d.test);
  s.test_min = test.min;
  s.test_max = test.max;
  s.test_outside = test.outside;
  if (d.targets.defined()) {
    const auto [lo, hi] = torch::aminmax(d.normaliser.normalise(d.targets));
    s.targets_min = lo.item<double>();
    s.targets_max = hi.item<double>();
  }
  for (const char* file : {kManifest, kRest, kFeatures, kNormaliser})
    s.file_bytes[file] = static_cast<int64_t>(fs::file_size(fs::path(d.folder) / file));
  s.features_seconds = features_seconds;
  s.seconds = clock.seconds();
  log::debug("summary in {:.2f} s", summary_clock.seconds());
  return s;
}

int64_t default_test_people(int64_t subjects, int test_people) {
  if (test_people >= 0) return test_people;
  if (subjects < 2) return 0;
  return std::max<int64_t>(1, std::llround(0.2 * static_cast<double>(subjects)));
}

}  // namespace

int64_t default_people(int64_t modes, int test_people) {
  int64_t people = kDefaultPeople;
  const int64_t training = modes + (modes + 2) / 3 + 1;
  while (people - default_test_people(people, test_people) < training) ++people;
  return people;
}

namespace {

// DR features of `meshes` into out ([#meshes, V, 9] floats).
void dr_batch(const DrFeatures& dr, const std::vector<Positions>& meshes, float* out) {
  std::vector<const Positions*> pointers;
  for (const Positions& m : meshes) pointers.push_back(&m);
  dr.compute_batch(pointers, out);
}

float* sample_pointer(torch::Tensor& features, int64_t sample) {
  return features.data_ptr<float>() + sample * features.size(1) * kDrWidth;
}

// The identity-averaged target of every expression: the DR features of the mean of the
// training subjects' meshes (sums / count) against the rest.
torch::Tensor targets_from(const DrFeatures& dr, std::vector<Positions>& sums, int64_t train_subjects) {
  for (Positions& s : sums) s /= static_cast<double>(train_subjects);
  torch::Tensor targets = torch::empty({static_cast<int64_t>(sums.size()), dr.vertex_count(), kDrWidth});
  dr_batch(dr, sums, targets.data_ptr<float>());
  return targets;
}

void require_test_split(int64_t subjects, int64_t test, const std::string& what) {
  if (test >= subjects)
    throw Error(what, std::to_string(test) + " test subjects of " + std::to_string(subjects) +
                          " leave none to train on; hold out fewer");
}

// The common end of both human builders: identity-averaged targets from the training
// subjects' summed meshes, per-sample subject/expression indices (samples are ordered subject
// by subject), the split by subject, the normaliser, and the files.
DatasetSummary finish_human_dataset(Dataset& d, const DrFeatures& dr, std::vector<Positions>& sums, const Split& s,
                                    int64_t expressions, const Stopwatch& clock, const Stopwatch& features_clock) {
  const int64_t subjects = static_cast<int64_t>(s.train.size() + s.test.size());
  d.targets = targets_from(dr, sums, static_cast<int64_t>(s.train.size()));
  const double features_seconds = features_clock.seconds();

  d.subject = torch::arange(subjects, torch::kInt64).repeat_interleave(expressions);
  d.expression = torch::arange(expressions, torch::kInt64).repeat(subjects);
  for (int64_t p : s.train)
    for (int64_t e = 0; e < expressions; ++e) d.train.push_back(p * expressions + e);
  for (int64_t p : s.test)
    for (int64_t e = 0; e < expressions; ++e) d.test.push_back(p * expressions + e);
  d.normaliser = Normaliser::fit(d.features, d.train, d.targets);
  write_dataset(d, nullptr);
  return summarise(d, clock, features_seconds);
}

// What the steps after the dataset need of an avatar rig, checked before its features are
// built: the eyes (the millimetre scale of `eval retarget`) and landmarks (`correspond`).
void check_rig_for_later_steps(const Rig& rig, bool require_eyes) {
  std::string extension = fs::path(rig.source).extension().string();
  for (char& ch : extension) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  const bool bare_gltf = extension == ".glb" || extension == ".gltf";
  const std::string where_to_add = bare_gltf ? "a glTF file cannot hold them: write a rig.yaml beside it with `gltf: " +
                                                   fs::path(rig.source).filename().string() +
                                                   "` and pass that as --rig (geometry/rig.h, docs/usage/formats.md)"
                                             : "add them to " + rig.source;
  if (require_eyes && (rig.eyes.left.empty() || rig.eyes.right.empty()))
    throw Error(rig.source,
                "no eyes: `retarget eval retarget` measures errors in mm from the distance of the eyes, so an avatar "
                "dataset needs them; " +
                    where_to_add +
                    " (`eyes: {left: [vertex, ...], right: [...]}`, or in a glTF file name the eye meshes "
                    "EyeLeft/EyeRight, eye_L/eye_R, ... so they are found), or run `retarget avatar init` to propose "
                    "them; or build without (--allow-no-eyes: errors stay in mesh units, and `eval retarget` will "
                    "refuse the avatar)");
  const std::vector<std::string> still = rig.still_controllers();
  if (!still.empty())
    log::warn(
        "{}: {} of {} controllers move no vertex (target = neutral): {}; they are sampled but change nothing. "
        "Give them their shapes, or remove them from {} if they are placeholders",
        rig.source, still.size(), rig.controller_count(), fmt::join(still, ", "),
        bare_gltf ? "the glTF file's morph targets" : rig.source);
  if (rig.landmarks.size() < 3)
    log::warn(
        "{}: {} landmark(s); `retarget correspond` pairs at least 3 by name with the human's, so it will need "
        "--landmarks FILE; {} (`landmarks: {{nose_tip: vertex, ...}}`, or `retarget avatar init` proposes them)",
        rig.source, rig.landmarks.size(), where_to_add);
}

}  // namespace

Rig load_dataset_rig(const Dataset& avatar) {
  std::string meshes;
  for (const std::string& mesh : avatar.gltf_meshes) meshes += (meshes.empty() ? "" : ", ") + mesh;
  Rig rig;
  try {
    rig = load_rig(avatar.source, avatar.gltf_meshes);
  } catch (const Error& e) {
    throw Error(avatar.folder, "the avatar dataset's rig does not load" +
                                   (meshes.empty() ? std::string() : " (glTF meshes " + meshes + ")") + ": " +
                                   e.what());
  }
  if (topology_fingerprint(rig.neutral) != avatar.fingerprint)
    throw Error(avatar.source, "the rig's neutral" +
                                   (meshes.empty() ? std::string() : " (glTF meshes " + meshes + ")") + " has " +
                                   std::to_string(rig.neutral.vertex_count()) + " vertices of topology " +
                                   topology_fingerprint(rig.neutral) + ", not the avatar dataset " + avatar.folder +
                                   "'s " + std::to_string(avatar.vertex_count()) + " vertices of topology " +
                                   avatar.fingerprint + "; rebuild the dataset from the rig as it is now");
  return rig;
}

const char* to_string(DatasetKind kind) { return kind == DatasetKind::avatar ? "avatar" : "human"; }

void AvatarDatasetOptions::validate() const {
  require(samples >= 2 && samples <= 1000000, "--samples",
          "expected 2 to 1000000 samples (the paper: 2000), got " + std::to_string(samples));
  require(min_active >= 1 && min_active <= max_active, "--min-active",
          "expected 1 <= min_active <= max_active, got " + std::to_string(min_active) + " and " +
              std::to_string(max_active));
  require(test_fraction >= 0 && test_fraction < 1, "--test-fraction",
          fmt::format("expected a number in [0, 1), got {}", test_fraction));
  dr.validate();
  size.validate();
}

void HumanDatasetOptions::validate() const {
  require(people >= 0, "--people", "expected a count >= 1, or 0 for the default, got " + std::to_string(people));
  require(test_people >= -1, "--test-people", "expected a count >= 0, got " + std::to_string(test_people));
  dr.validate();
  size.validate();
}

DatasetSummary build_avatar_dataset(const std::string& rig_path, const std::string& folder,
                                    const AvatarDatasetOptions& options) {
  const Stopwatch clock;
  options.validate();
  check_folder(folder, options.force);
  const Rig rig = load_rig(rig_path, options.mesh_name);
  check_mesh_size(rig.neutral, options.size, rig_path);
  check_rig_for_later_steps(rig, options.require_eyes);
  prepare_folder(folder, options.force);
  SamplingOptions sampling;
  sampling.count = options.samples;
  sampling.min_active = options.min_active;
  sampling.max_active = options.max_active;
  sampling.seed = options.seed;
  sampling.include_neutral = true;
  const Eigen::MatrixXd weights = sample_rig_weights(rig, sampling);
  const int64_t n = weights.rows(), c = weights.cols();
  const int v = rig.neutral.vertex_count();
  log::info("avatar {}: {} vertices, {} controllers, {} samples", rig.name, v, c, n);

  Dataset d;
  describe(d, folder, DatasetKind::avatar, rig.source, rig.neutral, options.dr, options.seed);
  d.name = rig.name;
  d.units = rig.units;
  d.gltf_meshes = rig.gltf_meshes;
  d.landmarks = rig.landmarks;
  d.eyes = rig.eyes;
  for (const Controller& controller : rig.controllers) d.controllers.push_back(controller.name);

  // Evaluating and featurising in blocks bounds the memory to a block of meshes, not N.
  const Stopwatch features_clock;
  const DrFeatures dr(d.rest, options.dr);
  d.features = torch::empty({n, v, kDrWidth}, torch::kFloat32);
  {
    Progress progress("avatar DR features", n, options.progress);
    constexpr int64_t kBlock = 64;
    for (int64_t begin = 0; begin < n; begin += kBlock) {
      const int64_t count = std::min(kBlock, n - begin);
      const std::vector<Positions> meshes = evaluate_samples(rig, weights.middleRows(begin, count));
      dr_batch(dr, meshes, sample_pointer(d.features, begin));
      progress.advance(count);
    }
  }
  const double features_seconds = features_clock.seconds();
  d.weights = torch::from_blob(const_cast<double*>(weights.data()), {c, n}, torch::kFloat64).t().contiguous();

  const int64_t test_count = std::llround(options.test_fraction * static_cast<double>(n));
  const Split s = split(n, std::min(test_count, n - 1), options.seed);
  d.train = s.train;
  d.test = s.test;
  d.normaliser = Normaliser::fit(d.features, d.train).with_channel_floor(kAvatarRangeFloor);
  write_dataset(d, &options);
  return summarise(d, clock, features_seconds);
}

DatasetSummary build_human_dataset(const FaceModel& model, const std::vector<ExpressionRecipe>& recipes,
                                   const std::string& recipes_source, const std::string& folder,
                                   const HumanDatasetOptions& options) {
  const Stopwatch clock;
  options.validate();
  if (!options.test_subjects.empty())
    throw Error("--test-subjects",
                "only for a face folder; a face model's people are drawn at random (use --test-people)");
  if (recipes.empty()) throw Error(recipes_source, "no expression recipes");
  check_mesh_size(model.neutral, options.size, model.source);
  for (const ExpressionRecipe& recipe : recipes)
    for (const auto& [shape, weight] : recipe.weights)
      if (model.expression_index(shape) < 0)
        throw Error(recipes_source, "recipe \"" + recipe.name + "\" uses the blendshape \"" + shape +
                                        "\", which the face model " + model.source + " does not have");
  prepare_folder(folder, options.force);

  const int64_t modes = static_cast<int64_t>(model.identities.size());
  const int64_t people = options.people > 0 ? options.people : default_people(modes, options.test_people);
  const int64_t expressions = static_cast<int64_t>(recipes.size());
  const int v = model.neutral.vertex_count();
  const int64_t test_count = default_test_people(people, options.test_people);
  require_test_split(people, test_count, "--test-people");
  if (modes == 0) log::warn("face model {} has no identity modes: every person is the neutral face", model.source);
  log::info("face model {}: {} vertices, {} identity modes; {} people x {} expressions", model.name, v, modes, people,
            expressions);
  if (people - test_count < modes + 1)
    log::warn(
        "{} training people cannot span the face model's {} identity modes: the human VAE will not see every "
        "way faces differ, and unseen people's codes will scatter by identity (leave --people out for {})",
        people - test_count, modes, default_people(modes, options.test_people));

  Dataset d;
  describe(d, folder, DatasetKind::human, model.source, model.neutral, options.dr, options.seed);
  d.name = model.name;
  d.recipes = absolute_path(recipes_source);
  if (options.own_recipes) {
    d.recipes = absolute_path((fs::path(folder) / "recipes.yaml").string());
    write_expression_recipes(d.recipes, recipes);
  }
  d.units = model.units;
  d.landmarks = model.landmarks;
  d.eyes = model.eyes;
  for (const ExpressionRecipe& recipe : recipes) d.expressions.push_back(recipe.name);
  char name[32];
  for (int64_t p = 0; p < people; ++p) {
    std::snprintf(name, sizeof name, "person%03lld", static_cast<long long>(p));
    d.subjects.push_back(name);
  }
  // Identities first, person by person, so that person p is the same for any --people >= p.
  Random random(options.seed);
  d.identity = torch::empty({people, modes}, torch::kFloat64);
  double* identity = d.identity.data_ptr<double>();
  for (int64_t i = 0; i < people * modes; ++i) identity[i] = random.normal();
  const Split s = split(people, test_count, options.seed);
  d.train_subjects = names_of(d.subjects, s.train);
  d.test_subjects = names_of(d.subjects, s.test);
  std::vector<char> is_train(people, 0);
  for (int64_t p : s.train) is_train[p] = 1;

  const Stopwatch features_clock;
  const DrFeatures dr(d.rest, options.dr);
  d.features = torch::empty({people * expressions, v, kDrWidth}, torch::kFloat32);
  std::vector<Positions> sums(expressions, Positions::Zero(v, 3));
  {
    Progress progress("human DR features", people * expressions, options.progress);
    std::vector<Positions> meshes(expressions);
    for (int64_t p = 0; p < people; ++p) {
      const Eigen::VectorXd c = Eigen::Map<const Eigen::VectorXd>(identity + p * modes, modes);
      const Positions person = model.person(c);
#pragma omp parallel for schedule(static)
      for (int64_t e = 0; e < expressions; ++e) meshes[e] = model.expression(person, recipes[e].weights);
      dr_batch(dr, meshes, sample_pointer(d.features, p * expressions));
      if (is_train[p])
        for (int64_t e = 0; e < expressions; ++e) sums[e] += meshes[e];
      progress.advance(expressions);
    }
  }
  return finish_human_dataset(d, dr, sums, s, expressions, clock, features_clock);
}

DatasetSummary build_face_folder_dataset(const std::string& face_folder, const std::string& folder,
                                         const HumanDatasetOptions& options) {
  const Stopwatch clock;
  options.validate();
  FaceFolderOptions folder_options;
  folder_options.neutral = options.neutral;
  check_folder(folder, options.force);
  const FaceFolder faces = open_face_folder(face_folder, folder_options);
  check_mesh_size(faces.topology, options.size, face_folder);
  const int64_t subjects = static_cast<int64_t>(faces.subjects.size());
  const int64_t expressions = static_cast<int64_t>(faces.expressions.size());

  // The split: named subjects, or a seeded choice.
  Split s;
  if (!options.test_subjects.empty()) {
    std::set<int64_t> test;
    for (const std::string& name : options.test_subjects) {
      const int index = faces.subject_index(name);
      if (index < 0) {
        std::string known;
        for (size_t k = 0; k < faces.subjects.size() && k < 20; ++k) known += (k ? ", " : "") + faces.subjects[k];
        throw Error("--test-subjects", "no subject \"" + name + "\" in " + face_folder + " (subjects: " + known +
                                           (faces.subjects.size() > 20 ? ", ..." : "") + ")");
      }
      test.insert(index);
    }
    require_test_split(subjects, static_cast<int64_t>(test.size()), "--test-subjects");
    for (int64_t i = 0; i < subjects; ++i) (test.count(i) ? s.test : s.train).push_back(i);
  } else {
    const int64_t test_count = default_test_people(subjects, options.test_people);
    require_test_split(subjects, test_count, "--test-people");
    s = split(subjects, test_count, options.seed);
  }

  // The rest: a given mesh, or the mean of the training subjects' neutral faces.
  Mesh rest;
  if (!options.rest_mesh.empty()) {
    rest = read_mesh(options.rest_mesh);
    require_same_topology(faces.topology, rest);
  } else {
    if (faces.neutral < 0)
      throw Error(face_folder, "no subject has a \"" + options.neutral +
                                   "\" mesh to average into the rest face; name the neutral expression (--neutral) or "
                                   "give a rest mesh (--rest)");
    Positions mean = Positions::Zero(faces.topology.vertex_count(), 3);
    for (int64_t subject : s.train) mean += faces.read(static_cast<int>(subject), faces.neutral);
    rest = with_positions(faces.topology, mean / static_cast<double>(s.train.size()));
    rest.source = "mean neutral of " + face_folder;
  }
  prepare_folder(folder, options.force);

  const int v = rest.vertex_count();
  log::info("face folder {}: {} vertices, {} subjects x {} expressions", face_folder, v, subjects, expressions);
  Dataset d;
  describe(d, folder, DatasetKind::human, face_folder, rest, options.dr, options.seed);
  d.name = fs::absolute(face_folder).lexically_normal().filename().string();
  if (d.name.empty()) d.name = fs::absolute(face_folder).lexically_normal().parent_path().filename().string();
  d.subjects = faces.subjects;
  d.expressions = faces.expressions;
  d.train_subjects = names_of(d.subjects, s.train);
  d.test_subjects = names_of(d.subjects, s.test);
  std::vector<char> is_train(subjects, 0);
  for (int64_t p : s.train) is_train[p] = 1;

  const Stopwatch features_clock;
  const DrFeatures dr(d.rest, options.dr);
  d.features = torch::empty({subjects * expressions, v, kDrWidth}, torch::kFloat32);
  std::vector<Positions> sums(expressions, Positions::Zero(v, 3));
  {
    Progress progress("human DR features", subjects * expressions, options.progress);
    std::vector<Positions> meshes(expressions);
    std::vector<std::exception_ptr> errors(expressions);
    for (int64_t p = 0; p < subjects; ++p) {
#pragma omp parallel for schedule(dynamic, 1)
      for (int64_t e = 0; e < expressions; ++e) {
        try {
          meshes[e] = faces.read(static_cast<int>(p), static_cast<int>(e));
        } catch (...) {
          errors[e] = std::current_exception();
        }
      }
      for (const std::exception_ptr& error : errors)
        if (error) std::rethrow_exception(error);
      dr_batch(dr, meshes, sample_pointer(d.features, p * expressions));
      if (is_train[p])
        for (int64_t e = 0; e < expressions; ++e) sums[e] += meshes[e];
      progress.advance(expressions);
    }
  }
  return finish_human_dataset(d, dr, sums, s, expressions, clock, features_clock);
}

// ---- Reading

namespace {

std::vector<std::string> string_list(const ConfigNode& node) { return node.as<std::vector<std::string>>(); }

// Checks a tensor's dtype and shape; names the file and the tensor.
const torch::Tensor& expect_tensor(const TensorMap& tensors, const std::string& name, const std::string& file,
                                   torch::ScalarType dtype, const std::vector<int64_t>& shape) {
  const torch::Tensor& t = tensor_named(tensors, name, file);
  if (t.scalar_type() != dtype || t.sizes() != c10::IntArrayRef(shape))
    throw Error(file, "tensor \"" + name + "\" is " + std::string(c10::toString(t.scalar_type())) + " " +
                          c10::str(t.sizes()) + " but the manifest calls for " + c10::toString(dtype) + " " +
                          c10::str(c10::IntArrayRef(shape)));
  return t;
}

// The manifest's own fields: kind, names, provenance, DR settings.
void read_manifest_fields(const ConfigNode& m, const std::string& manifest_path, Dataset& d) {
  const std::string kind = m.child("kind").as<std::string>();
  if (kind == "avatar")
    d.kind = DatasetKind::avatar;
  else if (kind == "human")
    d.kind = DatasetKind::human;
  else
    m.child("kind").fail("expected avatar or human, got \"" + kind + "\"");
  m.get_required("name", d.name);
  m.get_required("software_version", d.software_version);
  m.get("created", d.created);
  m.get("source", d.source);
  m.get("gltf_meshes", d.gltf_meshes);
  m.get("units", d.units);
  m.get("recipes", d.recipes);
  m.get_required("topology_fingerprint", d.fingerprint);
  d.seed = static_cast<uint64_t>(m.child("seed").as<int64_t>());
  const ConfigNode dr = m.child("dr");
  dr.reject_unknown_keys({"weighting", "normal_term", "normal_weight"});
  d.dr.weighting = parse_edge_weighting(dr.child("weighting").as<std::string>(), dr.child("weighting").where());
  dr.get("normal_term", d.dr.normal_term);
  dr.get("normal_weight", d.dr.normal_weight);
  if (d.software_version != RETARGET_VERSION)
    log::warn("{} was written by retarget {}; this is {}", manifest_path, d.software_version, RETARGET_VERSION);
}

// The rest mesh, checked against the manifest's vertex count and fingerprint, and the landmark
// and eye vertices on it.
void read_rest(const ConfigNode& m, const fs::path& dir, const std::string& rest_file, int vertex_count, Dataset& d) {
  d.rest = read_mesh((dir / rest_file).string());
  if (d.rest.vertex_count() != vertex_count)
    m.child("vertex_count")
        .fail(std::to_string(vertex_count) + " vertices but " + d.rest.source + " has " +
              std::to_string(d.rest.vertex_count()));
  const std::string fingerprint = topology_fingerprint(d.rest);
  if (fingerprint != d.fingerprint)
    m.child("topology_fingerprint")
        .fail(d.fingerprint + " but " + d.rest.source + " has the topology " + fingerprint +
              "; the rest mesh does not belong to this dataset");
  if (m.has("landmarks")) {
    const ConfigNode landmarks = m.child("landmarks");
    for (const auto& entry : landmarks.yaml()) {
      const std::string name = entry.first.as<std::string>();
      const int index = landmarks.child(name).as<int>();
      if (index < 0 || index >= vertex_count) landmarks.child(name).fail("vertex index out of range");
      d.landmarks[name] = index;
    }
  }
  if (m.has("eyes")) {
    const ConfigNode eyes = m.child("eyes");
    eyes.reject_unknown_keys({"left", "right"});
    d.eyes.left = eyes.child("left").as<std::vector<int>>();
    d.eyes.right = eyes.child("right").as<std::vector<int>>();
  }
}

// An avatar dataset's controllers, rig weights [N, C] and its sample split (a partition of
// 0..N-1).
void read_avatar_samples(const ConfigNode& m, const TensorMap& tensors, const std::string& features_path,
                         int64_t samples, Dataset& d) {
  const ConfigNode split_node = m.child("split");
  d.controllers = string_list(m.child("controllers"));
  const auto c = static_cast<int64_t>(d.controllers.size());
  d.weights = expect_tensor(tensors, "weights", features_path, torch::kFloat64, {samples, c});
  split_node.reject_unknown_keys({"test_fraction", "train", "test"});
  d.train = split_node.child("train").as<std::vector<int64_t>>();
  d.test = split_node.child("test").as<std::vector<int64_t>>();
  std::vector<int64_t> all = d.train;
  all.insert(all.end(), d.test.begin(), d.test.end());
  std::sort(all.begin(), all.end());
  bool partition = static_cast<int64_t>(all.size()) == samples;
  for (int64_t i = 0; partition && i < samples; ++i) partition = all[i] == i;
  if (!partition)
    split_node.fail("train and test together must list every sample 0.." + std::to_string(samples - 1) +
                    " exactly once");
}

// A human dataset's subjects x expressions, each sample's indices, the identity-averaged targets
// [E, V, 9] and the split by subject (every subject on exactly one side).
void read_human_samples(const ConfigNode& m, const TensorMap& tensors, const std::string& features_path,
                        int64_t samples, int vertex_count, Dataset& d) {
  const ConfigNode split_node = m.child("split");
  d.subjects = string_list(m.child("subjects"));
  d.expressions = string_list(m.child("expressions"));
  const auto p = static_cast<int64_t>(d.subjects.size()), e = static_cast<int64_t>(d.expressions.size());
  if (p * e != samples)
    m.child("sample_count")
        .fail(std::to_string(samples) + " samples but " + std::to_string(p) + " subjects x " + std::to_string(e) +
              " expressions");
  d.subject = expect_tensor(tensors, "subject", features_path, torch::kInt64, {samples});
  d.expression = expect_tensor(tensors, "expression", features_path, torch::kInt64, {samples});
  d.targets = expect_tensor(tensors, "targets", features_path, torch::kFloat32, {e, vertex_count, kDrWidth});
  if (tensors.count("identity")) d.identity = tensors.at("identity");
  if (samples > 0 && (d.subject.min().item<int64_t>() < 0 || d.subject.max().item<int64_t>() >= p ||
                      d.expression.min().item<int64_t>() < 0 || d.expression.max().item<int64_t>() >= e))
    throw Error(features_path, "subject or expression indices outside the manifest's lists");
  split_node.reject_unknown_keys({"train", "test"});
  d.train_subjects = string_list(split_node.child("train"));
  d.test_subjects = string_list(split_node.child("test"));
  std::vector<int> side(p, -1);  // 0 train, 1 test
  auto mark = [&](const std::vector<std::string>& names, int value, const ConfigNode& node) {
    for (const std::string& name : names) {
      const auto it = std::find(d.subjects.begin(), d.subjects.end(), name);
      if (it == d.subjects.end()) node.fail("unknown subject \"" + name + "\"");
      int& s = side[it - d.subjects.begin()];
      if (s >= 0) node.fail("subject \"" + name + "\" is listed twice in the split");
      s = value;
    }
  };
  mark(d.train_subjects, 0, split_node.child("train"));
  mark(d.test_subjects, 1, split_node.child("test"));
  const int64_t* subject = d.subject.data_ptr<int64_t>();
  for (int64_t i = 0; i < samples; ++i) {
    const int s = side[subject[i]];
    if (s < 0) split_node.fail("subject \"" + d.subjects[subject[i]] + "\" is in neither train nor test");
    (s == 0 ? d.train : d.test).push_back(i);
  }
}

// The feature normaliser, and the human targets' own (widened to the features' ranges).
void read_normalisers(const std::string& normaliser_path, int vertex_count, Dataset& d) {
  d.normaliser = Normaliser::load(normaliser_path);
  if (d.normaliser.vertex_count() != vertex_count)
    throw Error(normaliser_path, "has ranges for " + std::to_string(d.normaliser.vertex_count()) +
                                     " vertices but the dataset has " + std::to_string(vertex_count));
  d.target_normaliser = d.kind == DatasetKind::human && d.targets.defined() && d.targets.size(0) > 0
                            ? Normaliser::fit(d.targets).widened_to(d.normaliser, kTargetRangeFloor)
                            : d.normaliser;
}

// The manifest of a dataset folder; throws naming the folder when there is none.
ConfigNode open_manifest(const std::string& folder) {
  const std::string manifest_path = (fs::path(folder) / kManifest).string();
  if (!fs::is_regular_file(manifest_path))
    throw Error(folder, fs::is_directory(folder)
                            ? "not a dataset folder (no manifest.yaml); build one with `retarget dataset`"
                            : "dataset folder not found");
  return ConfigNode::load_file(manifest_path);
}

}  // namespace

std::vector<std::string> dataset_controllers(const std::string& folder) {
  const ConfigNode m = open_manifest(folder);
  return m.has("controllers") ? string_list(m.child("controllers")) : std::vector<std::string>{};
}

std::string dataset_recipes(const std::string& folder) {
  const ConfigNode m = open_manifest(folder);
  std::string recipes;
  m.get("recipes", recipes);
  return recipes;
}

Dataset load_dataset(const std::string& folder) {
  const fs::path dir(folder);
  const std::string manifest_path = (dir / kManifest).string();
  const ConfigNode m = open_manifest(folder);
  m.reject_unknown_keys({
      "format",       "kind",
      "name",         "software_version",
      "created",      "source",
      "gltf_meshes",  "units",
      "vertex_count", "topology_fingerprint",
      "dr",           "seed",
      "sample_count", "sampling",
      "controllers",  "subjects",
      "expressions",  "recipes",
      "split",        "landmarks",
      "eyes",         "files",
  });
  const int format = m.child("format").as<int>();
  if (format != kDatasetFormat)
    m.child("format").fail("dataset format " + std::to_string(format) + " but this build reads format " +
                           std::to_string(kDatasetFormat) + "; rebuild the dataset with `retarget dataset`");

  Dataset d;
  d.folder = folder;
  read_manifest_fields(m, manifest_path, d);
  const int vertex_count = m.child("vertex_count").as<int>();
  const int64_t samples = m.child("sample_count").as<int64_t>();

  std::string rest_file = kRest, features_file = kFeatures, normaliser_file = kNormaliser;
  if (m.has("files")) {
    const ConfigNode files = m.child("files");
    files.reject_unknown_keys({"rest", "features", "normaliser"});
    files.get("rest", rest_file);
    files.get("features", features_file);
    files.get("normaliser", normaliser_file);
  }
  read_rest(m, dir, rest_file, vertex_count, d);

  const std::string features_path = (dir / features_file).string();
  const TensorMap tensors = load_tensors(features_path);
  d.features = expect_tensor(tensors, "features", features_path, torch::kFloat32, {samples, vertex_count, kDrWidth});
  if (d.kind == DatasetKind::avatar)
    read_avatar_samples(m, tensors, features_path, samples, d);
  else
    read_human_samples(m, tensors, features_path, samples, vertex_count, d);
  read_normalisers((dir / normaliser_file).string(), vertex_count, d);
  return d;
}

}  // namespace retarget
