#include "correspond/correspondence.h"

#include <fmt/format.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <functional>
#include <set>
#include <sstream>

#include "annotate/annotation_store.h"
#include "core/error.h"
#include "core/tensor_io.h"
#include "correspond/annotation_project.h"
#include "correspond/rig_head.h"
#include "geometry/controller_correspondence.h"
#include "geometry/controller_map.h"
#include "geometry/dr_features.h"
#include "geometry/face_model.h"
#include "geometry/mesh_io.h"
#include "geometry/metrics.h"
#include "geometry/rig.h"
#include "tiny_correspondence.h"
#include "train/vae_run.h"

// The rounds' starts come from the orchestration of rounds, above this room (pipeline/round_starts.h).
#include "pipeline/round_starts.h"

using namespace retarget;
using namespace retarget::test;
namespace fs = std::filesystem;

namespace {

CorrespondenceOptions quiet(int group_size = 8) {
  CorrespondenceOptions o;
  o.group_size = group_size;
  o.progress = nullptr;
  return o;
}

// One build shared by the tests that only read it.
const Correspondences& built() {
  static const Correspondences c = [] {
    const auto& d = tiny_correspondence_data();
    CorrespondenceOptions o = quiet();
    o.initial = "dt";  // the paper's path; the rig projection has a test of its own
    return build_correspondences(d.human, d.avatar, d.run, (process_scratch_dir("correspondence_built") / "c").string(),
                                 o);
  }();
  return c;
}

std::string read_text(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace

TEST_CASE("correspondences: groups are the exact nearest avatar samples, nearest first", "[correspondence]") {
  const auto& d = tiny_correspondence_data();
  const Correspondences& c = built();
  const Dataset avatar = load_dataset(d.avatar);
  REQUIRE(c.expressions == std::vector<std::string>{"neutral", "A", "AB", "C"});
  REQUIRE(c.groups.sizes() == c10::IntArrayRef({4, 8}));
  REQUIRE(c.dt_features.sizes() == c10::IntArrayRef({4, avatar.vertex_count(), 9}));
  const int64_t n = avatar.sample_count();
  for (int64_t k = 0; k < 4; ++k) {
    INFO(c.expressions[k]);
    // Brute force: every sample's distance, one by one, in double.
    std::vector<std::pair<double, int64_t>> all;
    const torch::Tensor query = c.dt_features[k].to(torch::kFloat64);
    for (int64_t s = 0; s < n; ++s)
      all.emplace_back((avatar.features[s].to(torch::kFloat64) - query).pow(2).sum().sqrt().item<double>(), s);
    std::sort(all.begin(), all.end());
    for (int64_t p = 0; p < 8; ++p) {
      CHECK(c.groups[k][p].item<int64_t>() == all[p].second);
      CHECK(c.distances[k][p].item<double>() == Approx(all[p].first).epsilon(1e-6));
      if (p > 0) CHECK(c.distances[k][p].item<float>() >= c.distances[k][p - 1].item<float>());
    }
  }
}

TEST_CASE("correspondences: y0 and the group codes are encoder means of what was written", "[correspondence]") {
  const auto& d = tiny_correspondence_data();
  const Correspondences& c = built();
  TrainedVae trained = load_trained_vae(d.run, "best");
  torch::NoGradGuard no_grad;
  const DrFeatures dr(trained.dataset.rest, trained.dataset.dr);
  for (int64_t k = 0; k < c.expression_count(); ++k) {
    INFO(c.expressions[k]);
    const Mesh dt = read_mesh((fs::path(c.folder) / "dt" / (c.expressions[k] + ".obj")).string());
    REQUIRE(dt.vertex_count() == trained.dataset.vertex_count());
    const DrFeatureMatrix f = dr.compute(dt.vertices);
    const torch::Tensor features =
        torch::from_blob(const_cast<float*>(f.data()), {1, f.rows(), 9}, torch::kFloat32).clone();
    CHECK(torch::allclose(features[0], c.dt_features[k], 1e-5, 1e-6));
    // Normalised within the training range before encoding (train/vae_run.h encoder_means).
    const torch::Tensor normalised = trained.dataset.normaliser.normalise_within_range(features);
    const torch::Tensor mean = trained.vae->encode(normalised).mean[0];
    CHECK(torch::allclose(mean, c.y0[k], 1e-4, 1e-5));
    const Mesh reference = read_mesh((fs::path(c.folder) / "reference" / (c.expressions[k] + ".obj")).string());
    CHECK(reference.vertex_count() == load_dataset(d.human).vertex_count());
  }
  const torch::Tensor samples = trained.dataset.features.index_select(0, c.groups.flatten());
  const torch::Tensor codes = trained.vae->encode(trained.dataset.normaliser.normalise_within_range(samples)).mean;
  CHECK(torch::allclose(codes.reshape(c.group_codes.sizes()), c.group_codes, 1e-4, 1e-5));
}

TEST_CASE("correspondences: the neutral reference lands near the avatar rest", "[correspondence]") {
  const auto& d = tiny_correspondence_data();
  const Correspondences& c = built();
  const Dataset avatar = load_dataset(d.avatar);
  const Mesh neutral = read_mesh((fs::path(c.folder) / "dt" / "neutral.obj").string());
  const Mesh smile = read_mesh((fs::path(c.folder) / "dt" / "A.obj").string());
  const double diagonal = bounding_box_diagonal(avatar.rest.vertices);
  const double neutral_max = (neutral.vertices - avatar.rest.vertices).rowwise().norm().maxCoeff();
  const double a_max = (smile.vertices - avatar.rest.vertices).rowwise().norm().maxCoeff();
  CHECK(neutral_max < 0.02 * diagonal);
  CHECK(a_max > 5 * neutral_max);  // a real expression moves much more
  // Its group is led by samples that barely move (the rest pose is sample 0).
  CHECK(c.distances[0][0].item<double>() < 0.5 * c.distances[1][0].item<double>());
}

TEST_CASE("correspondences: the folder reads back as written", "[correspondence]") {
  const auto& d = tiny_correspondence_data();
  const Correspondences& c = built();
  const Correspondences r = load_correspondences(c.folder);
  CHECK(r.folder == c.folder);
  CHECK(r.created == c.created);
  CHECK(r.group_size == 8);
  CHECK(r.expressions == c.expressions);
  CHECK(r.human_dataset == fs::absolute(d.human).lexically_normal().string());
  CHECK(r.avatar_dataset == c.avatar_dataset);
  CHECK(r.avatar_vae_run == c.avatar_vae_run);
  CHECK(r.avatar_vae_checkpoint == "best");
  CHECK(r.human_fingerprint == c.human_fingerprint);
  CHECK(r.avatar_fingerprint == c.avatar_fingerprint);
  CHECK(r.human_name == "tiny");
  CHECK(r.avatar_name == "blob");
  CHECK(torch::equal(r.y0, c.y0));
  CHECK(torch::equal(r.dt_features, c.dt_features));
  CHECK(torch::equal(r.groups, c.groups));
  CHECK(torch::equal(r.distances, c.distances));
  CHECK(torch::equal(r.group_codes, c.group_codes));
  CHECK(r.expression_index("AB") == 2);
  CHECK_THROWS_WITH(r.expression_index("nope"), Catch::Contains("nope") && Catch::Contains("neutral, A, AB, C"));
  const std::string manifest = read_text(fs::path(c.folder) / "correspondences.yaml");
  CHECK(manifest.find("corner11: [35, 63]") != std::string::npos);
  // The landmark pairs the transfer used read back, in order.
  REQUIRE(c.landmarks.size() == 4);
  REQUIRE(r.landmarks.size() == 4);
  for (size_t i = 0; i < 4; ++i) {
    CHECK(r.landmarks[i].source == c.landmarks[i].source);
    CHECK(r.landmarks[i].target == c.landmarks[i].target);
  }
  CHECK(std::any_of(r.landmarks.begin(), r.landmarks.end(),
                    [](const LandmarkPair& p) { return p.source == 35 && p.target == 63; }));
  CHECK(manifest.find("format: retarget-correspondences") != std::string::npos);
  // The tensors are one plain dict.
  const TensorMap t = load_tensors((fs::path(c.folder) / "correspondences.pt").string());
  CHECK(t.size() == 5);

  const Dataset human = load_dataset(d.human), avatar = load_dataset(d.avatar);
  check_correspondences(r, human, avatar);
  const Dataset other = load_dataset(d.other_avatar);
  CHECK_THROWS_WITH(check_correspondences(r, human, other),
                    Catch::Contains(other.fingerprint) && Catch::Contains(avatar.fingerprint));
  CHECK_THROWS_WITH(check_correspondences(r, avatar, avatar), Catch::Contains(human.fingerprint));
}

TEST_CASE("correspondences: a chosen subset of expressions keeps its order", "[correspondence]") {
  const auto& d = tiny_correspondence_data();
  CorrespondenceOptions o = quiet(4);
  o.initial = "dt";  // as built()
  o.expressions = {"C", "A"};
  const Correspondences c =
      build_correspondences(d.human, d.avatar, d.run, (scratch_dir("correspondence_subset") / "c").string(), o);
  CHECK(c.expressions == std::vector<std::string>{"C", "A"});
  CHECK(c.groups.sizes() == c10::IntArrayRef({2, 4}));
  CHECK(torch::allclose(c.y0[1], built().y0[1]));
  CHECK(torch::equal(c.groups[1], built().groups[1].slice(0, 0, 4)));
  CHECK(fs::exists(fs::path(c.folder) / "dt" / "C.obj"));
  CHECK_FALSE(fs::exists(fs::path(c.folder) / "dt" / "neutral.obj"));
}

TEST_CASE("correspondences: mismatched inputs and bad options are refused", "[correspondence]") {
  const auto& d = tiny_correspondence_data();
  const fs::path dir = scratch_dir("correspondence_build_errors");
  const std::string out = (dir / "c").string();
  const Dataset avatar = load_dataset(d.avatar), other = load_dataset(d.other_avatar);

  // The VAE was trained on another topology.
  CHECK_THROWS_WITH(build_correspondences(d.human, d.other_avatar, d.run, out, quiet(4)),
                    Catch::Contains(avatar.fingerprint) && Catch::Contains(other.fingerprint));
  CHECK_THROWS_WITH(build_correspondences(d.avatar, d.avatar, d.run, out, quiet()),
                    Catch::Contains("is an avatar dataset"));

  CorrespondenceOptions o = quiet(1);
  CHECK_THROWS_WITH(build_correspondences(d.human, d.avatar, d.run, out, o), Catch::Contains("correspond.group_size"));
  o = quiet(61);
  CHECK_THROWS_WITH(build_correspondences(d.human, d.avatar, d.run, out, o),
                    Catch::Contains("correspond.group_size") && Catch::Contains("only 60 samples"));
  o = quiet();
  o.expressions = {"A", "smile"};
  CHECK_THROWS_WITH(build_correspondences(d.human, d.avatar, d.run, out, o),
                    Catch::Contains("unknown expression \"smile\"") && Catch::Contains("neutral, A, AB, C"));
  o.expressions = {"A", "A"};
  CHECK_THROWS_WITH(build_correspondences(d.human, d.avatar, d.run, out, o), Catch::Contains("named twice"));
  o = quiet();
  o.checkpoint = "middle";
  CHECK_THROWS_WITH(build_correspondences(d.human, d.avatar, d.run, out, o), Catch::Contains("correspond.checkpoint"));

  // Two landmark pairs are not enough.
  const std::string two = (dir / "two.yaml").string();
  std::ofstream(two) << "pairs: [[0, 0], [5, 7]]\n";
  o = quiet();
  o.landmarks_file = two;
  CHECK_THROWS_WITH(build_correspondences(d.human, d.avatar, d.run, out, o),
                    Catch::Contains(two) && Catch::Contains("at least 3"));
  // A landmark file of three pairs works and names what it matches.
  const std::string three = (dir / "three.yaml").string();
  std::ofstream(three) << "pairs: [[0, 0], [5, 7], [35, 63]]\n";
  o.landmarks_file = three;
  o.group_size = 2;
  o.expressions = {"A"};
  build_correspondences(d.human, d.avatar, d.run, out, o);
  const std::string manifest = read_text(fs::path(out) / "correspondences.yaml");
  CHECK(manifest.find("corner10: [5, 7]") != std::string::npos);

  // A folder with files in it needs force.
  CHECK_THROWS_WITH(build_correspondences(d.human, d.avatar, d.run, out, o), Catch::Contains("--force"));
  o.force = true;
  o.expressions = {"C"};
  build_correspondences(d.human, d.avatar, d.run, out, o);
  CHECK_FALSE(fs::exists(fs::path(out) / "dt" / "A.obj"));  // the old set's files are gone
  CHECK(fs::exists(fs::path(out) / "dt" / "C.obj"));
}

TEST_CASE("correspondences: damaged folders are refused naming the file", "[correspondence]") {
  const fs::path dir = scratch_dir("correspondence_damaged");
  CHECK_THROWS_WITH(load_correspondences((dir / "none").string()), Catch::Contains("not found"));
  CHECK_THROWS_WITH(load_correspondences(dir.string()), Catch::Contains("no correspondences.yaml"));

  const fs::path copy = dir / "copy";
  fs::copy(built().folder, copy, fs::copy_options::recursive);
  // Tensors that do not fit the manifest.
  TensorMap t = load_tensors((copy / "correspondences.pt").string());
  t["groups"] = t["groups"].slice(1, 0, 4).contiguous();
  save_tensors((copy / "correspondences.pt").string(), t);
  CHECK_THROWS_WITH(load_correspondences(copy.string()),
                    Catch::Contains("correspondences.pt") && Catch::Contains("\"groups\""));
  t["groups"] = built().groups.clone();
  t["groups"][0][0] = 60;
  save_tensors((copy / "correspondences.pt").string(), t);
  CHECK_THROWS_WITH(load_correspondences(copy.string()), Catch::Contains("outside 0..59"));

  // A landmark pair outside the avatar mesh.
  t["groups"] = built().groups.clone();
  save_tensors((copy / "correspondences.pt").string(), t);
  std::string manifest = read_text(copy / "correspondences.yaml");
  const std::string good = manifest;
  const size_t mark = manifest.find("corner11: [35, 63]");
  REQUIRE(mark != std::string::npos);
  manifest.replace(mark, 18, "corner11: [35, 64]");
  std::ofstream(copy / "correspondences.yaml") << manifest;
  CHECK_THROWS_WITH(load_correspondences(copy.string()),
                    Catch::Contains("landmarks.corner11") && Catch::Contains("0..63"));
  manifest = good;

  // Another format version.
  const size_t at = manifest.find("format_version: 1");
  REQUIRE(at != std::string::npos);
  manifest.replace(at, 17, "format_version: 7");
  std::ofstream(copy / "correspondences.yaml") << manifest;
  CHECK_THROWS_WITH(load_correspondences(copy.string()),
                    Catch::Contains("correspondences.yaml") && Catch::Contains("format version 7"));
}

TEST_CASE("correspondences: projected onto the rig, y0 and the groups come from a rig expression", "[correspondence]") {
  const auto& d = tiny_correspondence_data();
  CorrespondenceOptions o = quiet();
  REQUIRE(o.initial == "rig");  // the default
  const std::string folder = (scratch_dir("correspondence_rig") / "c").string();
  const Correspondences c = build_correspondences(d.human, d.avatar, d.run, folder, o);
  const Dataset avatar = load_dataset(d.avatar);
  const Rig rig = load_rig(avatar.source);
  TrainedVae trained = load_trained_vae(d.run, "best");
  REQUIRE(c.initial == "rig");
  REQUIRE(c.initial_weights.sizes() == c10::IntArrayRef({4, rig.controller_count()}));
  const DrFeatures dr(avatar.rest, avatar.dr);
  torch::NoGradGuard no_grad;
  for (int64_t k = 0; k < c.expression_count(); ++k) {
    INFO(c.expressions[k]);
    Eigen::VectorXd w(rig.controller_count());
    for (int j = 0; j < rig.controller_count(); ++j) {
      w(j) = c.initial_weights[k][j].item<double>();
      CHECK(w(j) >= rig.controllers[j].min);
      CHECK(w(j) <= rig.controllers[j].max);
    }
    // The weights are the best the rig can do for the DT result: no single controller's nudge helps.
    const Mesh dt = read_mesh((fs::path(folder) / "dt" / (c.expressions[k] + ".obj")).string());
    const auto misfit = [&](const Eigen::VectorXd& x) { return (rig.evaluate(x) - dt.vertices).squaredNorm(); };
    for (int j = 0; j < rig.controller_count(); ++j)
      for (double step : {-0.02, 0.02}) {
        Eigen::VectorXd nudged = w;
        nudged(j) = std::clamp(w(j) + step, rig.controllers[j].min, rig.controllers[j].max);
        CHECK(misfit(nudged) >= misfit(w) - 1e-12);
      }
    // dt_rig/<expression>.obj is the rig at those weights, and its features are what was encoded.
    const Mesh projected = read_mesh((fs::path(folder) / "dt_rig" / (c.expressions[k] + ".obj")).string());
    CHECK((projected.vertices - rig.evaluate(w)).cwiseAbs().maxCoeff() < 1e-6);
    const DrFeatureMatrix f = dr.compute(rig.evaluate(w));
    const torch::Tensor features =
        torch::from_blob(const_cast<float*>(f.data()), {1, f.rows(), 9}, torch::kFloat32).clone();
    CHECK(torch::allclose(features[0], c.initial_features[k], 1e-5, 1e-6));
    const torch::Tensor mean = trained.vae->encode(trained.dataset.normaliser.normalise_within_range(features)).mean[0];
    CHECK(torch::allclose(mean, c.y0[k], 1e-4, 1e-5));
    // The group is the exact nearest samples to the projection.
    const torch::Tensor all =
        (avatar.features.to(torch::kFloat64) - c.initial_features[k].to(torch::kFloat64)).pow(2).sum({1, 2}).sqrt();
    CHECK(c.distances[k][0].item<double>() == Approx(all.min().item<double>()).epsilon(1e-6));
  }
  // The projection of the neutral reference is (nearly) the rest pose: no controller to speak of.
  CHECK(c.initial_weights[0].abs().max().item<double>() < 0.1);
  // It reads back.
  const Correspondences r = load_correspondences(folder);
  CHECK(r.initial == "rig");
  CHECK(torch::equal(r.initial_weights, c.initial_weights));
  CHECK(torch::equal(r.initial_features, c.initial_features));
  // A bad choice is named.
  o.initial = "mesh";
  CHECK_THROWS_WITH(build_correspondences(d.human, d.avatar, d.run, folder + "2", o),
                    Catch::Contains("correspond.initial") && Catch::Contains("'rig', 'dt', 'champions' or 'table'"));
}

TEST_CASE("correspondences: spread members are varied rig expressions, the rest the nearest", "[correspondence]") {
  const auto& d = tiny_correspondence_data();
  const Dataset avatar = load_dataset(d.avatar);
  CorrespondenceOptions o = quiet();
  o.spread = 3;
  const fs::path dir = scratch_dir("correspondence_spread");
  const std::string folder = (dir / "c").string();
  const Correspondences c = build_correspondences(d.human, d.avatar, d.run, folder, o);
  CorrespondenceOptions plain = quiet(5);
  const Correspondences near = build_correspondences(d.human, d.avatar, d.run, (dir / "near").string(), plain);
  REQUIRE(c.groups.sizes() == c10::IntArrayRef({4, 8}));
  CHECK(c.spread == 3);
  const torch::Tensor w = avatar.weights.to(torch::kFloat64);
  const torch::Tensor unit = w / w.norm(2, 1, true).clamp_min(1e-12);
  for (int64_t k = 0; k < c.expression_count(); ++k) {
    INFO(c.expressions[k]);
    // The first 5 are the 5 nearest, exactly as a group of 5 would be.
    CHECK(torch::equal(c.groups[k].slice(0, 0, 5), near.groups[k]));
    std::set<int64_t> members;
    for (int64_t j = 0; j < 8; ++j) members.insert(c.groups[k][j].item<int64_t>());
    CHECK(members.size() == 8);  // no sample twice
    for (int64_t j = 5; j < 8; ++j) {
      const int64_t s = c.groups[k][j].item<int64_t>();
      // Each moves a controller past half its range, and its distance is its raw-DR distance.
      CHECK(w[s].abs().max().item<double>() >= 0.5);
      const double distance =
          (avatar.features[s].to(torch::kFloat64) - c.initial_features[k].to(torch::kFloat64)).norm().item<double>();
      CHECK(c.distances[k][j].item<double>() == Approx(distance).epsilon(1e-5));
      // Farthest-point: no eligible sample outside the group is further (in direction) from
      // the members chosen before it.
      const auto gap = [&](int64_t sample) {
        double g = 2;
        for (int64_t i = 0; i < j; ++i) {
          const int64_t m = c.groups[k][i].item<int64_t>();
          if (w[m].abs().max().item<double>() >= 0.5) g = std::min(g, 1 - unit[sample].dot(unit[m]).item<double>());
        }
        return g;
      };
      const double chosen = gap(s);
      for (int64_t other = 0; other < avatar.sample_count(); ++other) {
        bool earlier = false;
        for (int64_t i = 0; i < j; ++i) earlier = earlier || c.groups[k][i].item<int64_t>() == other;
        if (earlier || w[other].abs().max().item<double>() < 0.5) continue;
        CHECK(gap(other) <= chosen + 1e-9);
      }
    }
  }
  CHECK(load_correspondences(folder).spread == 3);
  o.spread = 8;
  CHECK_THROWS_WITH(build_correspondences(d.human, d.avatar, d.run, folder + "2", o),
                    Catch::Contains("correspond.spread") && Catch::Contains("0 to 7"));
}

TEST_CASE("correspondences: a later round starts from the champions of finished tournaments", "[correspondence]") {
  const auto& d = tiny_correspondence_data();
  const fs::path dir = scratch_dir("correspondence_rounds");
  CorrespondenceOptions o = quiet();
  o.spread = 2;
  const Correspondences first = build_correspondences(d.human, d.avatar, d.run, (dir / "c1").string(), o);
  const AnnotationProject project = init_annotation_project(first.folder, (dir / "p1").string());

  CorrespondenceOptions again = quiet();
  again.initial = "champions";
  again.around = project.folder;
  again.round_starts = champions_of(project.folder);
  // Unfinished tournaments are refused, naming the expression.
  CHECK_THROWS_WITH(build_correspondences(d.human, d.avatar, d.run, (dir / "c2").string(), again),
                    Catch::Contains("p1") && Catch::Contains("is not finished"));
  {
    AnnotationStore store = AnnotationStore::open(project.database());
    const Dataset human = load_dataset(d.human), avatar = load_dataset(d.avatar);
    run_simulated_annotation(
        store, ground_truth_scores(first, human, avatar, load_controller_correspondence(d.table), d.table).scores);
  }
  const Correspondences second = build_correspondences(d.human, d.avatar, d.run, (dir / "c2").string(), again);
  CHECK(second.initial == "champions");
  CHECK(second.around == fs::absolute(project.folder).lexically_normal().string());
  const Dataset avatar = load_dataset(d.avatar);
  TrainedVae trained = load_trained_vae(d.run, "best");
  AnnotationStore store = AnnotationStore::open(project.database());
  torch::NoGradGuard no_grad;
  for (const GroupProgress& g : store.progress().groups) {
    INFO(g.label);
    REQUIRE(g.champion.has_value());
    const int64_t k = second.expression_index(g.label);
    // The champion is where the round starts: its features, its weights, its code, and it heads its own group.
    CHECK(torch::equal(second.initial_features[k], avatar.features[*g.champion]));
    CHECK(torch::allclose(second.initial_weights[k], avatar.weights[*g.champion].to(torch::kFloat64)));
    CHECK(second.groups[k][0].item<int64_t>() == *g.champion);
    CHECK(second.distances[k][0].item<double>() == Approx(0).margin(1e-6));
    const torch::Tensor mean =
        trained.vae
            ->encode(trained.dataset.normaliser.normalise_within_range(avatar.features[*g.champion].unsqueeze(0)))
            .mean[0];
    CHECK(torch::allclose(mean, second.y0[k], 1e-4, 1e-5));
  }
  const Correspondences read = load_correspondences(second.folder);
  CHECK(read.initial == "champions");
  CHECK(read.around == second.around);
  CHECK(torch::equal(read.initial_features, second.initial_features));
  // The options must agree, and the project must be over the same avatar.
  again.around.clear();
  CHECK_THROWS_WITH(build_correspondences(d.human, d.avatar, d.run, (dir / "c3").string(), again),
                    Catch::Contains("correspond.around"));
}

TEST_CASE("correspondences: rig proposals around the champions, numbered after the dataset", "[correspondence]") {
  const auto& d = tiny_correspondence_data();
  const fs::path dir = scratch_dir("correspondence_proposals");
  const Dataset human = load_dataset(d.human), avatar = load_dataset(d.avatar);
  const ControllerCorrespondence table = load_controller_correspondence(d.table);
  const auto finish = [&](const Correspondences& c, const std::string& folder) {
    const AnnotationProject project = init_annotation_project(c.folder, folder);
    AnnotationStore store = AnnotationStore::open(project.database());
    run_simulated_annotation(store, ground_truth_scores(c, human, avatar, table, d.table).scores);
    return project;
  };
  const Correspondences first = build_correspondences(d.human, d.avatar, d.run, (dir / "c1").string(), quiet());
  const AnnotationProject p1 = finish(first, (dir / "p1").string());

  CorrespondenceOptions o = quiet();
  o.initial = "champions";
  o.around = p1.folder;
  o.round_starts = champions_of(p1.folder);
  o.proposals.count = 5;
  const Correspondences second = build_correspondences(d.human, d.avatar, d.run, (dir / "c2").string(), o);
  const int64_t n = avatar.sample_count(), k = second.expression_count();
  REQUIRE(second.avatar_samples == n);
  REQUIRE(second.proposals.count == 5);
  REQUIRE(second.candidate_count() == n + k * 5);
  REQUIRE(second.proposal_weights.sizes() == c10::IntArrayRef({k, 5, second.initial_weights.size(1)}));
  const Rig rig = load_rig(avatar.source);
  const DrFeatures dr(avatar.rest, avatar.dr);
  TrainedVae trained = load_trained_vae(d.run, "best");
  torch::NoGradGuard no_grad;
  for (int64_t e = 0; e < k; ++e) {
    INFO(second.expressions[e]);
    // Three nearest dataset samples, then the five proposals, the champion (the start) first.
    for (int64_t j = 0; j < 3; ++j) CHECK(second.groups[e][j].item<int64_t>() < n);
    for (int64_t j = 0; j < 5; ++j) CHECK(second.groups[e][3 + j].item<int64_t>() == n + e * 5 + j);
    CHECK(torch::equal(second.proposal_weights[e][0], second.initial_weights[e]));
    CHECK(second.distances[e][3].item<double>() == Approx(0).margin(1e-5));
    for (int64_t j = 0; j < 5; ++j) {
      const int64_t id = n + e * 5 + j;
      // A proposal is the rig at its weights: its features, its code, its distance to the start.
      const torch::Tensor w = second.proposal_weights[e][j].contiguous();
      const DrFeatureMatrix f =
          dr.compute(rig.evaluate(Eigen::Map<const Eigen::VectorXd>(w.data_ptr<double>(), w.numel())));
      const torch::Tensor features =
          torch::from_blob(const_cast<float*>(f.data()), {f.rows(), 9}, torch::kFloat32).clone();
      CHECK(torch::allclose(second.candidate_features(avatar, id), features, 1e-5, 1e-6));
      CHECK(torch::equal(second.candidate_weights(avatar, id), second.proposal_weights[e][j]));
      const torch::Tensor mean =
          trained.vae->encode(trained.dataset.normaliser.normalise_within_range(features.unsqueeze(0))).mean[0];
      CHECK(torch::allclose(mean, second.group_codes[e][3 + j], 1e-4, 1e-5));
      const double distance =
          (features.to(torch::kFloat64) - second.initial_features[e].to(torch::kFloat64)).norm().item<double>();
      CHECK(second.distances[e][3 + j].item<double>() == Approx(distance).epsilon(1e-5).margin(1e-6));
    }
  }
  // Dataset ids still resolve to the dataset; ids past the proposals are named.
  CHECK(torch::equal(second.candidate_features(avatar, 2), avatar.features[2]));
  CHECK_THROWS_WITH(second.candidate_features(avatar, n + k * 5), Catch::Contains("has no candidate"));

  // It reads back, and the annotation project scores and renders proposals like samples.
  const Correspondences read = load_correspondences(second.folder);
  CHECK(read.proposals.count == 5);
  CHECK(read.proposals.sigma == second.proposals.sigma);
  CHECK(torch::equal(read.proposal_weights, second.proposal_weights));
  CHECK(torch::equal(read.proposal_features, second.proposal_features));
  const GroundTruth truth = ground_truth_scores(read, human, avatar, table, d.table);
  const std::string label = read.expressions[1];
  const std::vector<double>& target = truth.controller_weights.at(label);
  const int64_t proposal = n + 5 + 2;
  double sum = 0;
  for (size_t j = 0; j < target.size(); ++j)
    sum += std::pow(read.proposal_weights[1][2][static_cast<int64_t>(j)].item<double>() - target[j], 2);
  CHECK(truth.scores.at(label).at(proposal) == Approx(std::sqrt(sum)));
  const AnnotationProject p2 = finish(read, (dir / "p2").string());
  AnnotationRenders renders(p2, 64);
  CHECK(fs::file_size(renders.candidate(proposal)) > 100);

  // A third round starts from the second's champions, proposals among them.
  o.around = p2.folder;
  o.round_starts = champions_of(p2.folder);
  o.proposals.seed = 3;
  const Correspondences third = build_correspondences(d.human, d.avatar, d.run, (dir / "c3").string(), o);
  AnnotationStore store = AnnotationStore::open(p2.database());
  for (const GroupProgress& g : store.progress().groups) {
    INFO(g.label);
    const int64_t e = third.expression_index(g.label);
    CHECK(torch::equal(third.initial_weights[e], read.candidate_weights(avatar, *g.champion)));
    CHECK(torch::equal(third.initial_features[e], read.candidate_features(avatar, *g.champion)));
  }

  // Options that cannot hold are named.
  CorrespondenceOptions bad = quiet();
  bad.initial = "dt";
  bad.proposals.count = 2;
  CHECK_THROWS_WITH(build_correspondences(d.human, d.avatar, d.run, (dir / "bad").string(), bad),
                    Catch::Contains("correspond.proposals") && Catch::Contains("initial 'rig' or 'champions'"));
  bad.initial = "rig";
  bad.spread = 3;
  bad.proposals.count = 5;
  CHECK_THROWS_WITH(build_correspondences(d.human, d.avatar, d.run, (dir / "bad").string(), bad),
                    Catch::Contains("correspond.proposals") && Catch::Contains("do not fit groups of 8"));
  // A whole group of proposals is allowed without spread.
  bad.spread = 0;
  bad.proposals.count = 8;
  const Correspondences all = build_correspondences(d.human, d.avatar, d.run, (dir / "all").string(), bad);
  CHECK(all.groups.min().item<int64_t>() == n);
}

TEST_CASE("correspondences: round 1 starts from the rig at a controller table's reading of each recipe",
          "[correspondence]") {
  const auto& d = tiny_correspondence_data();
  CorrespondenceOptions o = quiet();
  o.initial = "table";
  o.start_table = d.table;
  o.proposals.count = 3;  // the start itself first, then rig proposals around it
  const std::string folder = (scratch_dir("correspondence_table") / "c").string();
  const Correspondences c = build_correspondences(d.human, d.avatar, d.run, folder, o);
  const Dataset human = load_dataset(d.human), avatar = load_dataset(d.avatar);
  const Rig rig = load_rig(avatar.source);
  const ControllerCorrespondence table = load_controller_correspondence(d.table);
  const std::vector<ExpressionRecipe> recipes = load_expression_recipes(human.recipes);
  REQUIRE(c.initial == "table");
  CHECK(c.start_table == fs::absolute(d.table).lexically_normal().string());
  for (int64_t k = 0; k < c.expression_count(); ++k) {
    INFO(c.expressions[k]);
    const auto recipe = std::find_if(recipes.begin(), recipes.end(),
                                     [&](const ExpressionRecipe& r) { return r.name == c.expressions[k]; });
    REQUIRE(recipe != recipes.end());
    const Eigen::VectorXd want = rig_weights_from_human(table, rig, recipe->weights);
    for (int j = 0; j < rig.controller_count(); ++j) CHECK(c.initial_weights[k][j].item<double>() == Approx(want(j)));
    // The first proposal is the start itself, so the tournament can keep it.
    const torch::Tensor first = c.candidate_weights(avatar, c.groups[k][c.group_size - 3].item<int64_t>());
    CHECK(torch::allclose(first.to(torch::kFloat64), c.initial_weights[k], 1e-6, 1e-9));
  }
  const Correspondences r = load_correspondences(folder);
  CHECK(r.initial == "table");
  CHECK(r.start_table == c.start_table);
  CHECK(torch::equal(r.initial_weights, c.initial_weights));
  // A controller map (the rig head of earlier rounds) starts the same way; the map read from this
  // table gives the table's own starts.
  std::vector<std::string> controllers;
  for (const Controller& ctrl : rig.controllers) controllers.push_back(ctrl.name);
  const std::string map_path = (scratch_dir("correspondence_table_map") / "map.yaml").string();
  write_controller_map(map_path, controller_map_from_table(table, controllers, {"a", "b", "c"}));
  o.start_table = map_path;
  const Correspondences from_map = build_correspondences(d.human, d.avatar, d.run, folder + "-map", o);
  CHECK(torch::allclose(from_map.initial_weights, c.initial_weights, 1e-6, 1e-9));
  // A table without initial 'table', and the other way round, are named.
  o.initial = "rig";
  CHECK_THROWS_WITH(build_correspondences(d.human, d.avatar, d.run, folder + "2", o),
                    Catch::Contains("correspond.start_table"));
  o.initial = "table";
  o.start_table.clear();
  CHECK_THROWS_WITH(build_correspondences(d.human, d.avatar, d.run, folder + "2", o),
                    Catch::Contains("needs the controller table"));
}

TEST_CASE("correspondences: the belief search asks one informative pair per expression and learns from its rounds",
          "[correspondence][belief]") {
  const auto& d = tiny_correspondence_data();
  const fs::path dir = scratch_dir("correspondence_belief");
  // The prior reads the recipes wrongly: shape a drives ctrl1 and b ctrl0 (the truth: a -> ctrl0, b -> ctrl1).
  const std::string wrong = (dir / "wrong.yaml").string();
  write_controller_correspondence(
      wrong, {{"ctrl0", {{"b", 1.0}}}, {"ctrl1", {{"a", 1.0}}}, {"ctrl2", {{"c", 1.0}}}, {"ctrl3", {}}}, "blob");
  const Dataset human = load_dataset(d.human), avatar = load_dataset(d.avatar);
  const Rig rig = load_rig(avatar.source);
  const ControllerCorrespondence truth_table = load_controller_correspondence(d.table);
  const std::vector<ExpressionRecipe> recipes = load_expression_recipes(human.recipes);
  CorrespondenceOptions o = quiet(2);
  o.initial = "table";
  o.start_table = wrong;
  o.informative = true;
  // The annotator below judges exactly; the belief may assume so.
  BeliefSearchOptions belief;
  belief.weber = 0.02;
  belief.lapse = 0;
  belief.reading_sd = 0;
  // Mean distance of each round's starts' faces to the truth's (avatar units, Frobenius).
  const auto error_of = [&](const Correspondences& c) {
    double sum = 0;
    for (int64_t k = 0; k < c.expression_count(); ++k) {
      const auto recipe = std::find_if(recipes.begin(), recipes.end(),
                                       [&](const ExpressionRecipe& r) { return r.name == c.expressions[k]; });
      const torch::Tensor w = c.initial_weights[k].contiguous();
      sum += (rig.evaluate(Eigen::Map<const Eigen::VectorXd>(w.data_ptr<double>(), w.numel())) -
              rig.evaluate(rig_weights_from_human(truth_table, rig, recipe->weights)))
                 .norm();
    }
    return sum / static_cast<double>(c.expression_count());
  };
  // An annotator who judges faces: each candidate's score is its face's distance to the truth's.
  const auto face_scores = [&](const Correspondences& c) {
    CandidateScores scores;
    for (int64_t k = 0; k < c.expression_count(); ++k) {
      const auto recipe = std::find_if(recipes.begin(), recipes.end(),
                                       [&](const ExpressionRecipe& r) { return r.name == c.expressions[k]; });
      const Positions want = rig.evaluate(rig_weights_from_human(truth_table, rig, recipe->weights));
      for (int64_t p = 0; p < c.group_size; ++p) {
        const int64_t id = c.groups[k][p].item<int64_t>();
        const torch::Tensor w = c.candidate_weights(avatar, id).to(torch::kFloat64).contiguous();
        scores[c.expressions[k]][id] =
            (rig.evaluate(Eigen::Map<const Eigen::VectorXd>(w.data_ptr<double>(), w.numel())) - want).norm();
      }
    }
    return scores;
  };
  std::vector<double> errors;
  for (int round = 1; round <= 12; ++round) {
    const fs::path c_folder = dir / fmt::format("c{}", round), p_folder = dir / fmt::format("p{}", round);
    o.round_starts = belief_search_round(wrong, o.evidence, belief);
    const Correspondences c = build_correspondences(d.human, d.avatar, d.run, c_folder.string(), o);
    REQUIRE(c.informative);
    REQUIRE(c.group_size == 2);
    REQUIRE(c.proposals.count == 2);
    CHECK(c.evidence.size() == static_cast<size_t>(round - 1));
    if (round == 1) {
      // Round 1 bets on the prior, and each group is two new rig expressions inside the ranges.
      for (int64_t k = 0; k < c.expression_count(); ++k) {
        const auto recipe = std::find_if(recipes.begin(), recipes.end(),
                                         [&](const ExpressionRecipe& r) { return r.name == c.expressions[k]; });
        const Eigen::VectorXd prior =
            rig_weights_from_human(load_controller_correspondence(wrong), rig, recipe->weights);
        for (int j = 0; j < rig.controller_count(); ++j)
          CHECK(c.initial_weights[k][j].item<double>() == Approx(prior(j)));
        CHECK(c.groups[k][0].item<int64_t>() == avatar.sample_count() + 2 * k);
        CHECK(c.groups[k][1].item<int64_t>() == avatar.sample_count() + 2 * k + 1);
        const torch::Tensor a = c.candidate_weights(avatar, c.groups[k][0].item<int64_t>());
        const torch::Tensor b = c.candidate_weights(avatar, c.groups[k][1].item<int64_t>());
        CHECK((a >= 0).all().item<bool>());
        CHECK((b <= 1).all().item<bool>());
        if (c.expressions[k] != "neutral") CHECK(!torch::allclose(a, b));  // a neutral recipe has nothing to ask
      }
    } else {
      CHECK(c.evidence_comparisons > 0);
    }
    errors.push_back(error_of(c));
    const AnnotationProject project = init_annotation_project(c.folder, p_folder.string());
    AnnotationStore store = AnnotationStore::open(project.database());
    const CandidateScores sc = face_scores(c);
    run_simulated_annotation(store, sc);
    o.evidence.push_back(p_folder.string());
  }
  std::string trace;
  for (const double e : errors) trace += fmt::format(" {:.3f}", e);
  INFO("face error of the starts by round:" << trace);
  CHECK(errors.back() < 0.5 * errors.front());
  // The belief's most likely map, as `rig-map fit --belief` writes it, reads A's face nearer the truth than the prior
  // does.
  RigHeadFitOptions head;
  head.correspondences = (dir / "c1").string();
  head.annotations = o.evidence;
  head.prior = wrong;
  head.belief = true;
  head.belief_search = belief;
  const ControllerMap learnt = fit_rig_head(head);
  CHECK(learnt.pairs > 0);
  const Eigen::VectorXd a_truth = rig_weights_from_human(truth_table, rig, {{"a", 1.0}});
  const Eigen::VectorXd a_prior = rig_weights_from_human(load_controller_correspondence(wrong), rig, {{"a", 1.0}});
  const auto face_gap = [&](const Eigen::VectorXd& w) { return (rig.evaluate(w) - rig.evaluate(a_truth)).norm(); };
  CHECK(face_gap(learnt.on_rig({{"a", 1.0}}, rig)) < 0.6 * face_gap(a_prior));
  // The folder reads back with its rounds; the options are checked.
  const Correspondences read = load_correspondences((dir / "c12").string());
  CHECK(read.informative);
  CHECK(read.evidence.size() == 11);
  CHECK(read.evidence_comparisons > 0);
  o.group_size = 4;
  CHECK_THROWS_WITH(build_correspondences(d.human, d.avatar, d.run, (dir / "bad").string(), o),
                    Catch::Contains("correspond.informative") && Catch::Contains("groups of 2"));
  o.group_size = 2;
  o.informative = false;
  CHECK_THROWS_WITH(build_correspondences(d.human, d.avatar, d.run, (dir / "bad").string(), o),
                    Catch::Contains("correspond.evidence"));
}
