// The recipes of `retarget pipeline` (pipeline/recipe.h): the shipped ones load and plan the
// stages scripts/demo.sh and scripts/real_data.sh ran; overrides, relative paths and bad values.
#include "pipeline/recipe.h"

#include <algorithm>
#include <catch2/catch.hpp>
#include <filesystem>
#include <string>
#include <vector>

#include "pipeline/pipeline_stages.h"
#include "scratch.h"
#include "train/run_folder.h"

using namespace retarget;
using namespace retarget::test;
namespace fs = std::filesystem;

namespace {

fs::path configs() { return fs::path(RETARGET_SOURCE_DIR) / "configs"; }
std::string demo_recipe() { return (configs() / "recipes/demo.yaml").string(); }

std::vector<std::string> keys(const std::vector<Stage>& stages) {
  std::vector<std::string> k;
  for (const Stage& s : stages) k.push_back(s.key);
  return k;
}

}  // namespace

TEST_CASE("the demo recipe plans the demo: synthetic data, VAEs, 22 rounds for 2,000 comparisons, evaluation",
          "[pipeline]") {
  const Recipe recipe = load_recipe(demo_recipe(), {});
  CHECK(recipe.human.synthetic());
  CHECK(recipe.avatar.synthetic_name() == "fox");
  CHECK(recipe.profile == (configs() / "train/quick").lexically_normal().string());
  const std::vector<Stage> stages = pipeline_stages(recipe, "/runs/demo");
  const std::vector<std::string> k = keys(stages);
  REQUIRE(k.size() == 41);
  CHECK(std::vector<std::string>(k.begin(), k.begin() + 12) ==
        std::vector<std::string>{"synth", "avatar", "datasets/avatar", "datasets/human", "pictures", "geometry",
                                 "runs/avatar_vae", "runs/human_vae", "runs/cyclegan", "proposed", "test_faces",
                                 "method/annotation-dataset"});
  CHECK(k[12] == "method/round-01");
  CHECK(k[33] == "method/round-22");
  CHECK(std::vector<std::string>(k.end() - 7, k.end()) ==
        std::vector<std::string>{"method/translation", "method/bundle", "method/rig-head", "method/inference",
                                 "method/evaluation", "method/ladder", "method/plots"});
  // Round 3 asks with the answers of rounds 1 and 2 as evidence, and is simulated with seed 3.
  const std::string round3 = stages[14].commands[0].text();
  CHECK_THAT(round3, Catch::Contains("--evidence /runs/demo/method/rounds/1/annotation --evidence "
                                     "/runs/demo/method/rounds/2/annotation --out"));
  CHECK_THAT(stages[14].commands[2].text(), Catch::Contains("annotate simulate /runs/demo/method/rounds/3/annotation "
                                                            "--table /runs/demo/synth/avatars/fox/correspondence.yaml "
                                                            "--seed 3"));
  CHECK(stages[14].after.back() == "method/round-02");
  // Another panel of people: the same readings in every round, other than the default panel's.
  const std::vector<Stage> panel =
      pipeline_stages(load_recipe(demo_recipe(), {"annotators.simulate.reading-seed=2"}), "/runs/demo");
  for (const size_t round : {12, 14}) CHECK_THAT(panel[round].commands[2].text(), Catch::Contains("--reading-seed 2"));
}

TEST_CASE("the real-data recipe plans no synthetic data, its own rig and table", "[pipeline]") {
  const Recipe recipe = load_recipe((configs() / "recipes/real.yaml").string(), {"method.budget=700"});
  const std::vector<Stage> stages = pipeline_stages(recipe, "/runs/real");
  CHECK(stages.front().key == "datasets/avatar");
  CHECK(stages.front().inputs == std::vector<std::string>{(configs() / "real/lapin").lexically_normal().string()});
  CHECK(keys(stages).back() == "method/plots");
  int rounds = 0;
  for (const Stage& s : stages) rounds += s.family == "round";
  CHECK(rounds == 8);  // 6 of references and blends (94), then 2 of references (47): 658 of 700
}

TEST_CASE("training.processes trains the VAEs and F data-parallel, the CycleGAN in one process", "[pipeline]") {
  const Recipe recipe = load_recipe(demo_recipe(), {"training.processes=2"});
  CHECK(recipe.training_processes == 2);
  for (const Stage& s : pipeline_stages(recipe, "/runs/demo")) {
    if (s.family != "train") continue;
    INFO(s.key);
    std::string command;  // the train command (F's stage exports the triplets first)
    for (const StageCommand& c : s.commands)
      if (c.text().rfind("retarget train ", 0) == 0) command = c.text();
    REQUIRE(!command.empty());
    if (s.key == "runs/cyclegan")
      CHECK_THAT(command, !Catch::Contains("--nproc"));
    else
      CHECK_THAT(command, Catch::Contains("--force --nproc 2"));
  }
  CHECK_THROWS_WITH(load_recipe(demo_recipe(), {"training.processes=0"}), Catch::Contains("training.processes"));
}

TEST_CASE("overrides read paths against the working folder, the recipe's own against the recipe", "[pipeline]") {
  const fs::path dir = scratch_dir("recipe_paths");
  fs::create_directories(dir / "sub/profile");
  for (const char* name : {"avatar_vae.yaml", "human_vae.yaml", "translation.yaml", "cyclegan.yaml"})
    write_file(dir / "sub/profile", name, "task: vae\n");
  write_file(dir / "sub", "recipes.yaml", "recipes:\n  - {name: neutral, weights: {}}\n");
  const std::string recipe_file = write_file(
      dir / "sub", "r.yaml",
      "human: {face_model: synthetic, recipes: recipes.yaml}\navatar: {rig: synthetic/fox}\nprofile: profile\n");
  const Recipe r = load_recipe(recipe_file, {});
  CHECK(r.human.recipes == (dir / "sub/recipes.yaml").string());
  CHECK(r.profile == (dir / "sub/profile").string());
  const Recipe o = load_recipe(recipe_file, {"profile=" + (dir / "sub/profile").string(), "human.people=5"});
  CHECK(o.human.people == 5);
  fs::current_path(dir);
  const Recipe relative = load_recipe(recipe_file, {"profile=sub/profile"});
  CHECK(relative.profile == (dir / "sub/profile").string());
}

TEST_CASE("a bad recipe is refused naming the file, line and key path", "[pipeline]") {
  const fs::path dir = scratch_dir("recipe_bad");
  const std::string demo = demo_recipe();
  CHECK_THAT(error_of([&] { load_recipe(demo, {"method.budget=-3"}); }),
             Catch::Contains("method.budget: expected a positive number, got -3"));
  CHECK_THAT(error_of([&] { load_recipe(demo, {"method.search=greedy"}); }),
             Catch::Contains("method.search: expected belief, champions or map, got \"greedy\""));
  CHECK_THAT(error_of([&] { load_recipe(demo, {"annotators.simulate.loudness=3"}); }), Catch::Contains("loudness"));
  CHECK_THAT(error_of([&] { load_recipe(demo, {"avatar.rig=/nowhere/rig"}); }),
             Catch::Contains("avatar.rig: rig not found: /nowhere/rig"));
  CHECK_THAT(error_of([&] { load_recipe(demo, {"training.avatar_vae=[epochs]"}); }),
             Catch::Contains("expected key.path=value"));
  const std::string typo = write_file(dir, "typo.yaml", "base: " + demo + "\nmethods:\n  budget: 10\n");
  const std::string message = error_of([&] { load_recipe(typo, {}); });
  CHECK_THAT(message, Catch::Contains("typo.yaml:2"));
  CHECK_THAT(message, Catch::Contains("methods"));
}

TEST_CASE("a training stage resumes an unfinished run, skips a finished one and starts over without one",
          "[pipeline]") {
  const fs::path dir = scratch_dir("training_stage_resume");
  const fs::path config = dir / "vae.yaml";
  write_file(dir, "vae.yaml", "task: vae\n");
  const std::string folder = (dir / "run").string();
  const Stage s = training_stage("runs/x", "x", config.string(), {"data.dataset=D"}, folder,
                                 {retarget_command({"eval", "vae", folder})});
  REQUIRE(s.commands.size() == 2);
  CHECK(s.commands[0].text() ==
        "retarget train " + config.string() + " --set data.dataset=D --out " + folder + " --force");
  CHECK(s.inputs == std::vector<std::string>{config.string()});
  CHECK_FALSE(s.resume());  // no run.yaml: killed before the run began
  fs::create_directories(folder);
  RunStatus status;
  status.task = "vae";
  status.status = "running";
  status.save(folder);
  std::optional<std::vector<StageCommand>> rest = s.resume();
  REQUIRE(rest);
  REQUIRE(rest->size() == 2);
  CHECK((*rest)[0].text() == "retarget train " + folder + " --resume");
  status.status = "finished";
  status.save(folder);
  rest = s.resume();
  REQUIRE(rest);
  REQUIRE(rest->size() == 1);
  CHECK((*rest)[0].text() == "retarget eval vae " + folder);
}

TEST_CASE("a training stage digests its config's whole chain of bases", "[pipeline]") {
  const Recipe recipe = load_recipe(demo_recipe(), {});
  const std::vector<Stage> stages = pipeline_stages(recipe, "/runs/demo");
  const auto f =
      std::find_if(stages.begin(), stages.end(), [](const Stage& s) { return s.key == "method/translation"; });
  REQUIRE(f != stages.end());
  REQUIRE(f->inputs.size() == 2);
  CHECK(f->inputs[0] == fs::weakly_canonical(configs() / "train/quick/translation.yaml").string());
  CHECK(f->inputs[1] == fs::weakly_canonical(configs() / "train/translation.yaml").string());
}

TEST_CASE("each round's annotation project queues its groups with the round's own seed", "[pipeline]") {
  const Recipe recipe = load_recipe(demo_recipe(), {});
  const std::vector<Stage> stages = pipeline_stages(recipe, "/runs/demo");
  std::vector<std::string> seeds;
  for (const Stage& s : stages) {
    if (s.family != "round") continue;
    const auto init = std::find_if(s.commands.begin(), s.commands.end(),
                                   [](const StageCommand& c) { return c.args.size() > 1 && c.args[1] == "init"; });
    REQUIRE(init != s.commands.end());
    const auto seed = std::find(init->args.begin(), init->args.end(), "--seed");
    REQUIRE(seed != init->args.end());
    REQUIRE(seed + 1 != init->args.end());
    seeds.push_back(*(seed + 1));
  }
  REQUIRE(seeds.size() >= 2);
  for (size_t r = 0; r < seeds.size(); ++r) CHECK(seeds[r] == std::to_string(r + 1));
}

TEST_CASE("a round answered by people waits instead of simulating, and a restart keeps its answers", "[pipeline]") {
  const fs::path dir = scratch_dir("people_round");
  const Recipe recipe = load_recipe(demo_recipe(), {"annotators.kind=people", "method.annotation_blends=0"});
  const std::vector<Stage> stages = pipeline_stages(recipe, dir.string());
  const auto round = std::find_if(stages.begin(), stages.end(), [](const Stage& s) { return s.family == "round"; });
  REQUIRE(round != stages.end());
  CHECK_THAT(round->title, Catch::Contains("answered by people"));
  REQUIRE(round->commands.size() == 2);  // correspond, annotate init: no simulate
  CHECK(round->commands[1].args[1] == "init");
  CHECK(round->wait);
  REQUIRE(round->resume);
  CHECK_FALSE(round->resume());  // no project yet: the round starts over
  const fs::path project = dir / "method/rounds/1/annotation";
  fs::create_directories(project);
  write_file(project, "annotations.db", "");
  const std::optional<std::vector<StageCommand>> kept = round->resume();
  REQUIRE(kept);
  CHECK(kept->empty());  // the project and its answers stay: only the wait runs again
  CHECK_THAT(error_of([&] {
               load_recipe(demo_recipe(), {"annotators.kind=people", "annotators.simulate.noise=0.1"});
             }),
             Catch::Contains("annotators.simulate: only with kind: simulated"));
}
