#include "infer/weights_output.h"

// LibTorch before Catch: glog (through c10) defines CHECK, and the last definition wins.
#include <torch/torch.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "bundle/bundle_format.h"
#include "core/error.h"
#include "geometry/dr_features.h"
#include "infer/retargeter.h"
#include "tests/infer/infer_test_support.h"

namespace retarget {
namespace {

namespace fs = std::filesystem;

Eigen::VectorXd random_weights(const Rig& rig, std::mt19937& random) {
  Eigen::VectorXd w(rig.controller_count());
  for (int k = 0; k < rig.controller_count(); ++k)
    w(k) = std::uniform_real_distribution<double>(rig.controllers[k].min, rig.controllers[k].max)(random);
  return w;
}

// The avatar mesh the runtime makes of the rig's own expression: its DR features (against the
// bundle's avatar rest, with the bundle's avatar DR options) through Retargeter::reconstruct.
Positions through_runtime(const Retargeter& retargeter, const Rig& rig, const Eigen::VectorXd& w) {
  const LoadedBundle& bundle = retargeter.bundle();
  const DrFeatures dr(bundle.avatar_rest, bundle.metadata.avatar.dr);
  DrFeatureMatrix features = dr.compute(rig.evaluate(w));
  const torch::Tensor y = torch::from_blob(features.data(), {1, features.rows(), kDrWidth}, torch::kFloat32).clone();
  return retargeter.reconstruct(y).front();
}

TEST_CASE("WeightsOutput recovers a rig's own expressions through the runtime's reconstruction", "[weights_output]") {
  const fs::path dir = test::process_scratch_dir("weights_output_recover");
  const LoadedBundle loaded = load_bundle(test::tiny_rig_bundle(dir / "bundle"));
  REQUIRE(loaded.rig.has_value());
  const Retargeter retargeter(loaded);
  const Rig& rig = *retargeter.bundle().rig;
  WeightsOutput output(rig, retargeter.bundle().metadata.rig->millimetres_per_unit, dir.string());
  CHECK(output.residual_unit() == "mm");
  std::mt19937 random(11);
  double error = 0;
  constexpr int kFrames = 10;
  for (int f = 0; f < kFrames; ++f) {
    const Eigen::VectorXd truth = random_weights(rig, random);
    const FrameWeights w = output.add("frame_" + std::to_string(f), through_runtime(retargeter, rig, truth));
    for (int k = 0; k < rig.controller_count(); ++k) {
      CHECK(w.weights(k) >= rig.controllers[k].min);
      CHECK(w.weights(k) <= rig.controllers[k].max);
    }
    error += (w.weights - truth).cwiseAbs().mean() / kFrames;
    CHECK(w.residual < 0.5);  // mm, on a ball of 30 mm
  }
  INFO("mean absolute error " << error);
  CHECK(error <= 0.02);  // measured: 0.008
  output.finish();
  CHECK(output.frames() == kFrames);
  CHECK(output.residual_max() >= output.residual_mean());
  CHECK(test::lines_of(dir / "weights.csv").size() == kFrames + 1);
  CHECK(test::lines_of(dir / "weights.jsonl").size() == kFrames);
}

TEST_CASE("WeightsOutput writes weights.csv and weights.jsonl, appending and then renaming", "[weights_output]") {
  const fs::path dir = test::process_scratch_dir("weights_output_files");
  BundleRig part = test::ball_rig();
  Rig& rig = part.rig;
  rig.controllers[1].name = "brow, \"left\"";  // a name CSV must quote
  std::mt19937 random(12);
  const Eigen::VectorXd a = random_weights(rig, random), b = random_weights(rig, random);
  {
    WeightsOutput output(rig, 10, dir.string());
    output.add("frame_1", rig.evaluate(a));
    // Appended under a temporary name: the final files appear only at finish().
    CHECK_FALSE(fs::exists(dir / "weights.csv"));
    CHECK_FALSE(fs::exists(dir / "weights.jsonl"));
    output.add("take 2, final", rig.evaluate(b));
    output.finish();
    CHECK(output.files() == std::vector<std::string>{(dir / "weights.csv").string(), (dir / "weights.jsonl").string()});
  }
  for (const auto& entry : fs::directory_iterator(dir))
    CHECK(entry.path().filename().string().find(".tmp") == std::string::npos);

  const std::vector<std::string> csv = test::lines_of(dir / "weights.csv");
  REQUIRE(csv.size() == 3);
  CHECK(csv[0] == "frame,bump0,\"brow, \"\"left\"\"\",bump2,bump3,bump4,shear,residual_mm");
  CHECK(csv[1].rfind("frame_1,", 0) == 0);
  CHECK(csv[2].rfind("\"take 2, final\",", 0) == 0);

  const std::vector<std::string> jsonl = test::lines_of(dir / "weights.jsonl");
  REQUIRE(jsonl.size() == 2);
  for (int f = 0; f < 2; ++f) {
    const nlohmann::json line = nlohmann::json::parse(jsonl[f]);
    CHECK(line.at("frame") == (f == 0 ? "frame_1" : "take 2, final"));
    CHECK(line.at("weights").size() == 6);
    const Eigen::VectorXd& truth = f == 0 ? a : b;
    for (int k = 0; k < rig.controller_count(); ++k)
      CHECK(line.at("weights").at(rig.controllers[k].name).get<double>() ==
            Approx(truth(k)).margin(0.01));  // the ridge
    CHECK(line.at("residual_mm").get<double>() < 0.01);
  }
  // Keys in the rig's order, not sorted.
  CHECK(jsonl[0].find("\"bump0\"") < jsonl[0].find("\"brow, \\\"left\\\"\""));

  // One format only; an output not finished leaves nothing behind.
  const fs::path only = test::process_scratch_dir("weights_output_csv_only");
  WeightsOutputOptions csv_only;
  csv_only.jsonl = false;
  {
    WeightsOutput output(rig, 0, only.string(), csv_only);
    CHECK(output.residual_unit() == "cm");
    output.add("x", rig.neutral.vertices);
    output.finish();
  }
  CHECK(fs::exists(only / "weights.csv"));
  CHECK_FALSE(fs::exists(only / "weights.jsonl"));
  const fs::path unfinished = test::process_scratch_dir("weights_output_unfinished");
  {
    WeightsOutput output(rig, 0, unfinished.string());
    output.add("x", rig.neutral.vertices);
  }
  CHECK(fs::is_empty(unfinished));
}

TEST_CASE("WeightsOutput: the smoothness term carries the previous frame's weights", "[weights_output]") {
  const BundleRig part = test::ball_rig();
  const Rig& rig = part.rig;
  std::mt19937 random(13);
  const Eigen::VectorXd a = random_weights(rig, random), b = random_weights(rig, random);
  WeightsOutputOptions sticky;
  sticky.smoothness = 1000;
  WeightsOutput smooth(rig, 10, test::process_scratch_dir("weights_output_smooth").string(), sticky);
  WeightsOutput plain(rig, 10, test::process_scratch_dir("weights_output_plain").string());
  const FrameWeights first = smooth.add("a", rig.evaluate(a));
  CHECK((first.weights - plain.add("a", rig.evaluate(a)).weights).cwiseAbs().maxCoeff() < 1e-9);  // no previous
  const FrameWeights held = smooth.add("b", rig.evaluate(b));
  CHECK((held.weights - first.weights).cwiseAbs().maxCoeff() < 0.01);
  CHECK((plain.add("b", rig.evaluate(b)).weights - b).cwiseAbs().mean() < 0.02);
  CHECK(held.residual > 0.1);  // mm: the mesh moved on, the weights did not
}

TEST_CASE("WeightsOutput refuses bad options, naming them", "[weights_output]") {
  const BundleRig part = test::ball_rig();
  const std::string dir = test::process_scratch_dir("weights_output_options").string();
  WeightsOutputOptions o;
  o.ridge = -0.5;
  CHECK_THROWS_WITH(WeightsOutput(part.rig, 10, dir, o), Catch::Contains("--weights-ridge") && Catch::Contains("-0.5"));
  o = {};
  o.smoothness = NAN;
  CHECK_THROWS_WITH(WeightsOutput(part.rig, 10, dir, o),
                    Catch::Contains("--weights-smoothness") && Catch::Contains("finite number >= 0"));
  o = {};
  o.csv = o.jsonl = false;
  CHECK_THROWS_WITH(WeightsOutput(part.rig, 10, dir, o), Catch::Contains("--weights-format"));
  CHECK(fs::is_empty(dir));
}

}  // namespace
}  // namespace retarget
