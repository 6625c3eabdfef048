#include "data/dataset.h"

#include <catch2/catch.hpp>
#include <fstream>
#include <set>

#include "core/error.h"
#include "core/log.h"
#include "geometry/expression_sampling.h"
#include "geometry/face_folder.h"
#include "geometry/mesh_io.h"
#include "geometry/rig.h"
#include "geometry/topology_fingerprint.h"
#include "test_support.h"
#include "tiny_data.h"

using namespace retarget;
namespace fs = std::filesystem;

using namespace retarget::test;

namespace {

AvatarDatasetOptions avatar_options() {
  AvatarDatasetOptions o;
  o.samples = 30;
  o.test_fraction = 0.2;
  o.seed = 3;
  o.progress = nullptr;
  return o;
}

HumanDatasetOptions human_options() {
  HumanDatasetOptions o;
  o.people = 6;
  o.test_people = 2;
  o.seed = 5;
  o.progress = nullptr;
  return o;
}

double max_difference(const torch::Tensor& a, const torch::Tensor& b) {
  return (a.to(torch::kFloat64) - b.to(torch::kFloat64)).abs().max().item<double>();
}

torch::Tensor dr_tensor(const DrFeatures& dr, const Positions& p) {
  const DrFeatureMatrix f = dr.compute(p);
  return torch::from_blob(const_cast<float*>(f.data()), {f.rows(), kDrWidth}, torch::kFloat32).clone();
}

void check_normalised_train(const Dataset& d) {
  const torch::Tensor y = d.normaliser.normalise(d.features.index_select(0, torch::tensor(d.train)));
  CHECK(y.min().item<double>() >= -0.9 - 1e-5);
  CHECK(y.max().item<double>() <= 0.9 + 1e-5);
  CHECK((d.normaliser.max - d.normaliser.min).min().item<double>() >= 1e-5 * (1 - 1e-3));
}

void replace_in_file(const fs::path& path, const std::string& from, const std::string& to) {
  std::ifstream in(path);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  in.close();
  const size_t at = text.find(from);
  REQUIRE(at != std::string::npos);
  text.replace(at, from.size(), to);
  std::ofstream(path) << text;
}

}  // namespace

TEST_CASE("an avatar dataset holds the rig's samples, their DR features and a split", "[dataset]") {
  const auto dir = test::scratch_dir("dataset_avatar");
  const Rig rig = tiny_rig();
  write_rig_folder((dir / "rig").string(), rig);
  const std::string out = (dir / "ds").string();
  const DatasetSummary s = build_avatar_dataset((dir / "rig").string(), out, avatar_options());
  CHECK(s.samples == 30);
  CHECK(s.train == 24);
  CHECK(s.test == 6);
  CHECK(s.controllers == 4);
  CHECK(s.test_min <= s.test_max);
  CHECK((s.test_outside >= 0 && s.test_outside <= 1));
  for (const char* file : {"manifest.yaml", "rest.obj", "features.pt", "normaliser.pt"})
    CHECK(s.file_bytes.at(file) > 0);

  const Dataset d = load_dataset(out);
  CHECK(d.kind == DatasetKind::avatar);
  CHECK(d.name == "blob");
  CHECK(d.units == "cm");
  CHECK(d.software_version == RETARGET_VERSION);
  CHECK(d.fingerprint == topology_fingerprint(rig.neutral));
  CHECK(d.seed == 3);
  CHECK(d.dr.weighting == EdgeWeighting::cotangent);
  CHECK(d.controllers == std::vector<std::string>{"ctrl0", "ctrl1", "ctrl2", "ctrl3"});
  CHECK(d.landmarks == rig.landmarks);
  CHECK(d.eyes.right == rig.eyes.right);
  CHECK((d.rest.vertices - rig.neutral.vertices).cwiseAbs().maxCoeff() == 0);
  REQUIRE(d.features.sizes() == c10::IntArrayRef({30, 36, 9}));
  REQUIRE(d.weights.sizes() == c10::IntArrayRef({30, 4}));

  // The weights are the sampler's, the features those of the evaluated rig.
  SamplingOptions sampling;
  sampling.count = 30;
  sampling.seed = 3;
  const Eigen::MatrixXd w = sample_rig_weights(rig, sampling);
  const DrFeatures dr(rig.neutral);
  for (int i = 0; i < 30; ++i) {
    for (int c = 0; c < 4; ++c) CHECK(d.weights[i][c].item<double>() == w(i, c));
    CHECK(max_difference(d.features[i], dr_tensor(dr, rig.evaluate(w.row(i).transpose()))) < 1e-6);
  }
  CHECK(d.features[0].abs().max().item<double>() < 1e-5);  // the rest pose comes first

  // The split is a partition; the normaliser is the training rows', each range floored at
  // kAvatarRangeFloor x its channel's largest.
  std::set<int64_t> all(d.train.begin(), d.train.end());
  all.insert(d.test.begin(), d.test.end());
  CHECK(all.size() == 30);
  CHECK(d.test.size() == 6);
  const Normaliser fitted = Normaliser::fit(d.features, d.train);
  const Normaliser expected = fitted.with_channel_floor(kAvatarRangeFloor);
  const torch::Tensor range = d.normaliser.max - d.normaliser.min;
  const torch::Tensor channel_max = std::get<0>((fitted.max - fitted.min).max(0, true));
  CHECK((range >= kAvatarRangeFloor * channel_max * (1 - 1e-5)).all().item<bool>());
  CHECK((range > (fitted.max - fitted.min) + 1e-7).any().item<bool>());  // the floor did widen some
  CHECK(torch::equal(d.normaliser.min, expected.min));
  CHECK(torch::equal(d.normaliser.max, expected.max));
  CHECK(s.widened == (d.normaliser.max - d.normaliser.min <= 1e-5 * (1 + 1e-3)).sum().item<int64_t>());
  check_normalised_train(d);
}

TEST_CASE("an avatar dataset names the controllers that move no vertex in a warning", "[dataset]") {
  const auto dir = test::scratch_dir("dataset_still_controller");
  Rig rig = tiny_rig();
  rig.controllers[2].offset.setZero();
  write_rig_folder((dir / "rig").string(), rig);
  std::vector<std::string> warnings;
  const log::Sink previous = log::set_sink([&](log::Level level, const std::string& m) {
    if (level == log::Level::warn) warnings.push_back(m);
  });
  const DatasetSummary s = build_avatar_dataset((dir / "rig").string(), (dir / "ds").string(), avatar_options());
  log::set_sink(previous);
  CHECK(s.controllers == 4);  // kept: the weights' order holds
  int named = 0;
  for (const std::string& w : warnings)
    named += w.find("1 of 4 controllers move no vertex (target = neutral): ctrl2;") != std::string::npos &&
             w.find("rig.yaml") != std::string::npos;
  CHECK(named == 1);
}

TEST_CASE("a dataset is reproducible for a seed", "[dataset]") {
  const auto dir = test::scratch_dir("dataset_seed");
  write_rig_folder((dir / "rig").string(), tiny_rig());
  build_avatar_dataset((dir / "rig").string(), (dir / "a").string(), avatar_options());
  build_avatar_dataset((dir / "rig").string(), (dir / "b").string(), avatar_options());
  AvatarDatasetOptions other = avatar_options();
  other.seed = 4;
  build_avatar_dataset((dir / "rig").string(), (dir / "c").string(), other);
  const Dataset a = load_dataset((dir / "a").string()), b = load_dataset((dir / "b").string()),
                c = load_dataset((dir / "c").string());
  CHECK(torch::equal(a.features, b.features));
  CHECK(torch::equal(a.weights, b.weights));
  CHECK(a.test == b.test);
  CHECK(!torch::equal(a.weights, c.weights));

  const FaceModel model = tiny_face_model();
  build_human_dataset(model, tiny_recipes(), "recipes.yaml", (dir / "h1").string(), human_options());
  build_human_dataset(model, tiny_recipes(), "recipes.yaml", (dir / "h2").string(), human_options());
  const Dataset h1 = load_dataset((dir / "h1").string()), h2 = load_dataset((dir / "h2").string());
  CHECK(torch::equal(h1.identity, h2.identity));
  CHECK(torch::equal(h1.features, h2.features));
  CHECK(h1.test_subjects == h2.test_subjects);
}

TEST_CASE("building into a folder that is not empty needs force", "[dataset]") {
  const auto dir = test::scratch_dir("dataset_force");
  write_rig_folder((dir / "rig").string(), tiny_rig());
  const std::string out = (dir / "ds").string();
  build_avatar_dataset((dir / "rig").string(), out, avatar_options());
  CHECK_THROWS_WITH(build_avatar_dataset((dir / "rig").string(), out, avatar_options()),
                    Catch::Contains(out) && Catch::Contains("not empty") && Catch::Contains("--force"));
  AvatarDatasetOptions forced = avatar_options();
  forced.force = true;
  forced.samples = 12;
  // What a kill during an earlier write of features.pt left (its process has ended: no pid
  // reaches 999999999): removed by the next write, not kept beside the new files.
  const fs::path stale = fs::path(out) / "features.pt.tmp.999999999.2";
  std::ofstream(stale) << "half a tensor file";
  build_avatar_dataset((dir / "rig").string(), out, forced);
  CHECK(load_dataset(out).sample_count() == 12);
  CHECK_FALSE(fs::exists(stale));

  fs::create_directories(dir / "other");
  std::ofstream(dir / "other" / "notes.txt") << "mine";
  CHECK_THROWS_WITH(
      build_human_dataset(tiny_face_model(), tiny_recipes(), "r.yaml", (dir / "other").string(), human_options()),
      Catch::Contains("--force"));
  std::ofstream(dir / "file") << "x";
  CHECK_THROWS_WITH(build_avatar_dataset((dir / "rig").string(), (dir / "file").string(), avatar_options()),
                    Catch::Contains("not a folder"));
  // A sample count beyond any use is refused at once, not allocated.
  AvatarDatasetOptions huge = avatar_options();
  huge.samples = 2000000000;
  CHECK_THROWS_WITH(build_avatar_dataset((dir / "rig").string(), (dir / "huge").string(), huge),
                    "--samples: expected 2 to 1000000 samples (the paper: 2000), got 2000000000");
}

TEST_CASE("a human dataset from a face model is split by subject with identity-averaged targets", "[dataset]") {
  const auto dir = test::scratch_dir("dataset_human_model");
  const FaceModel model = tiny_face_model();
  const auto recipes = tiny_recipes();
  const std::string out = (dir / "ds").string();
  const DatasetSummary s = build_human_dataset(model, recipes, "recipes.yaml", out, human_options());
  CHECK(s.samples == 24);
  CHECK(s.train == 16);
  CHECK(s.test == 8);
  CHECK(s.subjects == 6);
  CHECK(s.expressions == 4);

  const Dataset d = load_dataset(out);
  CHECK(d.kind == DatasetKind::human);
  CHECK(d.name == "tiny");
  CHECK(d.expressions == std::vector<std::string>{"neutral", "A", "AB", "C"});
  REQUIRE(d.subjects.size() == 6);
  CHECK(d.subjects[5] == "person005");
  REQUIRE(d.identity.sizes() == c10::IntArrayRef({6, 3}));
  REQUIRE(d.targets.sizes() == c10::IntArrayRef({4, 36, 9}));
  CHECK((d.rest.vertices - model.neutral.vertices).cwiseAbs().maxCoeff() == 0);

  // Split by subject: every subject on one side, two held out.
  CHECK(d.test_subjects.size() == 2);
  CHECK(d.train_subjects.size() == 4);
  std::set<std::string> subjects(d.train_subjects.begin(), d.train_subjects.end());
  for (const std::string& t : d.test_subjects) CHECK(subjects.insert(t).second);
  CHECK(subjects.size() == 6);
  std::set<int64_t> train_ids, test_ids;
  for (int64_t i : d.train) train_ids.insert(d.subject[i].item<int64_t>());
  for (int64_t i : d.test) test_ids.insert(d.subject[i].item<int64_t>());
  for (int64_t p : test_ids) CHECK(train_ids.count(p) == 0);
  CHECK(train_ids.size() == 4);
  CHECK(test_ids.size() == 2);

  // Independently: every mesh from the stored identity coefficients, its DR features against
  // the neutral, and the target as the DR features of the training subjects' mean mesh.
  const DrFeatures dr(model.neutral);
  auto mesh = [&](int p, int e) {
    Positions m = model.neutral.vertices;
    for (int k = 0; k < 3; ++k) m += d.identity[p][k].item<double>() * model.identities[k].offset;
    for (const auto& [name, w] : recipes[e].weights) m += w * model.expressions[name[0] - 'a'].offset;
    return m;
  };
  for (int p = 0; p < 6; ++p)
    for (int e = 0; e < 4; ++e) {
      const int64_t i = p * 4 + e;
      CHECK(d.subject[i].item<int64_t>() == p);
      CHECK(d.expression[i].item<int64_t>() == e);
      CHECK(max_difference(d.features[i], dr_tensor(dr, mesh(p, e))) < 1e-5);
    }
  for (int e = 0; e < 4; ++e) {
    Positions mean = Positions::Zero(36, 3);
    for (int64_t p : train_ids) mean += mesh(static_cast<int>(p), e);
    mean /= static_cast<double>(train_ids.size());
    CHECK(max_difference(d.targets[e], dr_tensor(dr, mean)) < 1e-5);
    // Not the average of the features: the target averages meshes, then takes features.
    CHECK(d.targets[e].abs().max().item<double>() > 0);
  }
  // The ranges cover the training subjects' features and the targets (made from them only).
  check_normalised_train(d);
  const Normaliser expected =
      Normaliser::fit(torch::cat({d.features.index_select(0, torch::tensor(d.train)), d.targets}));
  CHECK(torch::equal(d.normaliser.min, expected.min));
  CHECK(torch::equal(d.normaliser.max, expected.max));
  CHECK(d.normaliser.normalise(d.targets).abs().max().item<double>() <= 0.9 + 1e-5);
  CHECK((s.targets_min >= -0.9 - 1e-5 && s.targets_max <= 0.9 + 1e-5));
}

TEST_CASE("human datasets refuse bad recipes and splits", "[dataset]") {
  const auto dir = test::scratch_dir("dataset_human_errors");
  const FaceModel model = tiny_face_model();
  auto recipes = tiny_recipes();
  recipes.push_back({"frown", {{"mouthFrown_L", 1.0}}});
  CHECK_THROWS_WITH(build_human_dataset(model, recipes, "recipes.yaml", (dir / "a").string(), human_options()),
                    Catch::Contains("recipes.yaml") && Catch::Contains("recipe \"frown\"") &&
                        Catch::Contains("\"mouthFrown_L\"") && Catch::Contains("tiny face model"));
  CHECK(!fs::exists(dir / "a"));  // checked before anything is written
  HumanDatasetOptions all_test = human_options();
  all_test.test_people = 6;
  CHECK_THROWS_WITH(build_human_dataset(model, tiny_recipes(), "r.yaml", (dir / "b").string(), all_test),
                    Catch::Contains("--test-people") && Catch::Contains("none to train on"));
  HumanDatasetOptions named = human_options();
  named.test_subjects = {"person001"};
  CHECK_THROWS_WITH(build_human_dataset(model, tiny_recipes(), "r.yaml", (dir / "c").string(), named),
                    Catch::Contains("--test-subjects") && Catch::Contains("face folder"));
  HumanDatasetOptions none = human_options();
  none.people = -1;
  CHECK_THROWS_WITH(build_human_dataset(model, tiny_recipes(), "r.yaml", (dir / "d").string(), none),
                    Catch::Contains("--people") && Catch::Contains("got -1"));
  // The default holds out 20% of the subjects, at least one.
  HumanDatasetOptions defaults = human_options();
  defaults.test_people = -1;
  defaults.people = 3;
  CHECK(build_human_dataset(model, tiny_recipes(), "r.yaml", (dir / "e").string(), defaults).test == 4);
}

TEST_CASE("a face model's default people are enough to span its identity modes", "[dataset]") {
  // A few modes: the floor. 20% held out by default: 24 people -> 5 test, 19 training.
  CHECK(default_people(0, -1) == kDefaultPeople);
  CHECK(default_people(10, -1) == kDefaultPeople);
  // The synthetic face model's 29 modes need 29 + 10 + 1 training people: 50 with 10 held out.
  CHECK(default_people(29, -1) == 50);
  CHECK(default_people(100, -1) == 169);  // 34 held out, 135 training
  CHECK(default_people(29, 2) == 42);     // a fixed test count
  // The fewest people that leave modes + ceil(modes / 3) + 1 training (or the floor).
  const auto training = [](int64_t people) {
    return people - std::max<int64_t>(1, std::llround(0.2 * static_cast<double>(people)));
  };
  for (int64_t modes : {5, 17, 29, 53}) {
    const int64_t people = default_people(modes, -1), needed = modes + (modes + 2) / 3 + 1;
    CHECK(training(people) >= needed);
    CHECK((people == kDefaultPeople || training(people - 1) < needed));
  }

  // people 0 builds that many from the model (the tiny model has 3 modes: the floor).
  const auto dir = test::scratch_dir("dataset_default_people");
  HumanDatasetOptions defaults = human_options();
  defaults.people = 0;
  const DatasetSummary s =
      build_human_dataset(tiny_face_model(), tiny_recipes(), "r.yaml", (dir / "a").string(), defaults);
  CHECK(s.train + s.test == kDefaultPeople * static_cast<int64_t>(tiny_recipes().size()));

  // Fewer training people than modes + 1 (human_options: 6 people, 2 held out; 3 modes) is a
  // warning naming both counts and the default; enough is none.
  const auto warnings_of = [&](const HumanDatasetOptions& o, const std::string& name) {
    std::vector<std::string> warnings;
    const log::Sink previous = log::set_sink([&](log::Level level, const std::string& m) {
      if (level == log::Level::warn) warnings.push_back(m);
    });
    build_human_dataset(tiny_face_model(), tiny_recipes(), "r.yaml", (dir / name).string(), o);
    log::set_sink(previous);
    return warnings;
  };
  HumanDatasetOptions few = human_options();
  few.people = 3;
  few.test_people = 1;
  const std::vector<std::string> warned = warnings_of(few, "b");
  REQUIRE(warned.size() == 1);
  CHECK_THAT(warned[0], Catch::Contains("2 training people cannot span the face model's 3 identity modes") &&
                            Catch::Contains("leave --people out for 24"));
  CHECK(warnings_of(human_options(), "c").empty());
}

TEST_CASE("a human dataset from a face folder averages the training neutrals into the rest", "[dataset]") {
  const auto dir = test::scratch_dir("dataset_face_folder");
  const FaceModel model = tiny_face_model();
  const std::vector<std::string> subjects = {"ann", "ben", "cat", "dan"};
  const std::vector<std::pair<std::string, std::map<std::string, double>>> poses = {
      {"neutral", {}}, {"smile", {{"a", 1.0}}}, {"frown", {{"b", 0.7}, {"c", 0.3}}}};
  std::map<std::string, std::map<std::string, Positions>> meshes;
  for (size_t s = 0; s < subjects.size(); ++s) {
    Eigen::VectorXd c(3);
    c << 0.3 * s - 0.5, std::sin(s), 0.2;
    const Positions person = model.person(c);
    for (const auto& [name, weights] : poses) {
      meshes[subjects[s]][name] = model.expression(person, weights);
      write_mesh((dir / "faces" / subjects[s] / (name + ".obj")).string(),
                 with_positions(model.neutral, meshes[subjects[s]][name]));
    }
  }
  HumanDatasetOptions o = human_options();
  o.test_subjects = {"cat"};
  const std::string out = (dir / "ds").string();
  const DatasetSummary s = build_face_folder_dataset((dir / "faces").string(), out, o);
  CHECK(s.samples == 12);
  CHECK(s.test == 3);

  const Dataset d = load_dataset(out);
  CHECK(d.name == "faces");
  CHECK(d.subjects == subjects);
  CHECK(d.expressions == std::vector<std::string>{"neutral", "frown", "smile"});
  CHECK(d.test_subjects == std::vector<std::string>{"cat"});
  CHECK(d.train_subjects == std::vector<std::string>{"ann", "ben", "dan"});
  CHECK(d.test == std::vector<int64_t>{6, 7, 8});
  CHECK(!d.identity.defined());
  const std::vector<std::string> train = {"ann", "ben", "dan"};
  Positions rest = Positions::Zero(36, 3);
  for (const std::string& t : train) rest += meshes[t]["neutral"];
  rest /= 3.0;
  CHECK((d.rest.vertices - rest).cwiseAbs().maxCoeff() < 1e-12);
  const DrFeatures dr(d.rest);
  for (size_t e = 0; e < 3; ++e) {
    Positions mean = Positions::Zero(36, 3);
    for (const std::string& t : train) mean += meshes[t][d.expressions[e]];
    CHECK(max_difference(d.targets[e], dr_tensor(dr, mean / 3.0)) < 1e-5);
  }
  CHECK(d.targets[0].abs().max().item<double>() < 1e-5);  // the mean neutral is the rest
  CHECK(max_difference(d.features[3 * 3 + 2], dr_tensor(dr, meshes["dan"]["smile"])) < 1e-5);
  check_normalised_train(d);

  // A given rest mesh; a seeded split when no subjects are named.
  HumanDatasetOptions given = human_options();
  given.test_people = -1;
  given.rest_mesh = (dir / "faces" / "ann" / "neutral.obj").string();
  build_face_folder_dataset((dir / "faces").string(), (dir / "given").string(), given);
  const Dataset g = load_dataset((dir / "given").string());
  CHECK((g.rest.vertices - meshes["ann"]["neutral"]).cwiseAbs().maxCoeff() < 1e-12);
  CHECK(g.test_subjects.size() == 1);

  HumanDatasetOptions unknown = human_options();
  unknown.test_subjects = {"eve"};
  CHECK_THROWS_WITH(build_face_folder_dataset((dir / "faces").string(), (dir / "x").string(), unknown),
                    Catch::Contains("--test-subjects") && Catch::Contains("no subject \"eve\"") &&
                        Catch::Contains("ann, ben, cat, dan"));
  HumanDatasetOptions no_neutral = human_options();
  no_neutral.neutral = "rest";
  CHECK_THROWS_WITH(build_face_folder_dataset((dir / "faces").string(), (dir / "y").string(), no_neutral),
                    Catch::Contains("\"rest\"") && Catch::Contains("--neutral") && Catch::Contains("--rest"));
  CHECK(!fs::exists(dir / "y"));  // nothing written for a failed build
  HumanDatasetOptions bad_rest = human_options();
  bad_rest.rest_mesh = (dir / "grid.obj").string();
  write_mesh(bad_rest.rest_mesh, test::quad_grid(2, 2, 1.0, 1.0));
  CHECK_THROWS_WITH(build_face_folder_dataset((dir / "faces").string(), (dir / "z").string(), bad_rest),
                    Catch::Contains("grid.obj") && Catch::Contains("9 vertices"));
}

TEST_CASE("load_dataset checks the manifest against the files", "[dataset]") {
  const auto dir = test::scratch_dir("dataset_load_errors");
  write_rig_folder((dir / "rig").string(), tiny_rig());
  const fs::path out = dir / "ds";
  build_avatar_dataset((dir / "rig").string(), out.string(), avatar_options());
  CHECK_NOTHROW(load_dataset(out.string()));

  CHECK_THROWS_WITH(load_dataset((dir / "nowhere").string()),
                    Catch::Contains("nowhere") && Catch::Contains("not found"));
  CHECK_THROWS_WITH(load_dataset((dir / "rig").string()), Catch::Contains("no manifest.yaml"));

  // Another topology with the same vertex count.
  fs::copy_file(out / "rest.obj", dir / "rest.obj");
  write_mesh((out / "rest.obj").string(), test::quad_grid(8, 3, 1.0, 1.0));  // 36 vertices
  CHECK_THROWS_WITH(load_dataset(out.string()),
                    Catch::Contains("topology_fingerprint") && Catch::Contains("does not belong to this dataset"));
  write_mesh((out / "rest.obj").string(), test::quad_grid(2, 2, 1.0, 1.0));
  CHECK_THROWS_WITH(load_dataset(out.string()), Catch::Contains("vertex_count") && Catch::Contains("9"));
  fs::copy_file(dir / "rest.obj", out / "rest.obj", fs::copy_options::overwrite_existing);

  replace_in_file(out / "manifest.yaml", "sample_count: 30", "sample_count: 31");
  CHECK_THROWS_WITH(load_dataset(out.string()), Catch::Contains("features.pt") && Catch::Contains("\"features\""));
  replace_in_file(out / "manifest.yaml", "sample_count: 31", "sample_count: 30");
  replace_in_file(out / "manifest.yaml", "format: 1", "format: 7");
  CHECK_THROWS_WITH(load_dataset(out.string()),
                    Catch::Contains("manifest.yaml") && Catch::Contains("format 7") && Catch::Contains("rebuild"));
  replace_in_file(out / "manifest.yaml", "format: 7", "format: 1");
  replace_in_file(out / "manifest.yaml", "kind: avatar", "kind: robot");
  CHECK_THROWS_WITH(load_dataset(out.string()), Catch::Contains("kind") && Catch::Contains("robot"));
  replace_in_file(out / "manifest.yaml", "kind: robot", "kind: avatar");
  CHECK_NOTHROW(load_dataset(out.string()));
}
