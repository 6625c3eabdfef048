#include "translate/translation_config.h"

#include <catch2/catch.hpp>
#include <functional>

#include "core/error.h"
#include "scratch.h"

using namespace retarget;

namespace {

using test::error_of;

const std::string kGood =
    "task: translation\n"
    "data:\n"
    "  human_vae: runs/human\n"
    "  avatar_vae: runs/avatar\n"
    "  correspondences: corr\n"
    "  triplets: project\n"
    "  held_out_fraction: 0.25\n"
    "  human_codes: targets\n"
    "model: {hidden: 16, negative_slope: 0.2}\n"
    "loss: {margin: 0.3, triplet_scale: absolute}\n"
    "training: {batch_size: 8, checkpoint_every: 2, seed: 5, threads: 1}\n"
    "stages:\n"
    "  - {name: one, epochs: 3, lr: 1.0e-2, weights: {paired: 1, group: 0, triplet: 0}}\n"
    "  - {epochs: 0, lr: 1.0e-3, weights: {paired: 1, group: 1, triplet: 0}}\n"
    "  - {name: three, epochs: 2, lr: 1.0e-3, weights: {paired: 1, group: 1, triplet: 10}}\n"
    "output: out\n";

TranslationTrainConfig parse(const std::string& text) {
  return read_translation_train_config(ConfigNode::parse(text, "c.yaml"));
}

std::string replaced(const std::string& from, const std::string& to) {
  std::string text = kGood;
  const size_t at = text.find(from);
  REQUIRE(at != std::string::npos);
  return text.replace(at, from.size(), to);
}

}  // namespace

TEST_CASE("translation config: keys map one to one and read back from its YAML", "[translation_config]") {
  const TranslationTrainConfig c = parse(kGood);
  CHECK(c.data.human_vae == "runs/human");
  CHECK(c.data.human_checkpoint == "best");
  CHECK(c.data.triplets == "project");
  CHECK(c.data.include_derived);
  CHECK(c.data.held_out_fraction == 0.25);
  CHECK(c.data.human_codes == HumanCodes::targets);
  CHECK(c.model.hidden() == 16);
  CHECK(c.model.negative_slope() == 0.2);
  CHECK(c.margin == 0.3);
  CHECK(c.triplet_scale == TripletScale::absolute);
  CHECK(c.training.batch_size == 8);
  CHECK(c.training.seed == 5);
  REQUIRE(c.stages.size() == 3);
  CHECK(c.stages[0].name == "one");
  CHECK(c.stages[1].name == "stage2");  // the default name
  CHECK(c.stages[2].weights.triplet == 10);
  CHECK(c.total_epochs() == 5);
  // Epochs 0-2 are stage 1, the empty stage 2 is skipped, 3-4 are stage 3.
  CHECK(c.stage_of(0) == 0);
  CHECK(c.stage_of(2) == 0);
  CHECK(c.stage_of(3) == 2);
  CHECK(c.stage_of(4) == 2);
  CHECK(c.stage_end(0) == 3);
  CHECK(c.stage_end(1) == 3);
  CHECK(c.stage_end(2) == 5);
  CHECK(c.training.input_noise == 0);  // the paper: none
  const TranslationTrainConfig noisy = parse(replaced("threads: 1}", "threads: 1, input_noise: 4}"));
  CHECK(noisy.training.input_noise == 4);
  CHECK(read_translation_train_config(ConfigNode::parse(to_yaml(noisy), "again.yaml")).training.input_noise == 4);
  CHECK(to_yaml(read_translation_train_config(ConfigNode::parse(to_yaml(c), "again.yaml"))) == to_yaml(c));
}

TEST_CASE("translation config: defaults are the paper's progressive schedule", "[translation_config]") {
  const TranslationTrainConfig c =
      parse("task: translation\ndata: {human_vae: h, avatar_vae: a, correspondences: c}\noutput: o\n");
  CHECK(c.data.triplets.empty());
  CHECK(c.data.human_codes == HumanCodes::subjects);
  CHECK(c.data.held_out_fraction == 0.2);
  CHECK(c.margin == 0.2);
  CHECK(c.triplet_scale == TripletScale::group);  // not the paper's: see translation_config.h
  CHECK(c.model.hidden() == 100);
  CHECK(c.model.negative_slope() == 0.1);
  REQUIRE(c.stages.size() == 3);
  CHECK(c.stages[0].lr == 1e-4);
  CHECK(c.stages[0].weights.paired == 1);
  CHECK(c.stages[0].weights.group == 1e-4);
  CHECK(c.stages[0].weights.triplet == 1e-4);
  CHECK(c.stages[1].lr == 1e-5);
  CHECK(c.stages[1].weights.group == 1);
  CHECK(c.stages[1].weights.triplet == 1e-4);
  CHECK(c.stages[2].lr == 1e-6);
  CHECK(c.stages[2].weights.paired == 1);
  CHECK(c.stages[2].weights.group == 1);
  CHECK(c.stages[2].weights.triplet == 10);
  // An empty triplets key means none.
  CHECK(parse(replaced("  triplets: project\n", "  triplets:\n")).data.triplets.empty());
}

TEST_CASE("translation config: bad values fail naming file, line and key path", "[translation_config]") {
  CHECK(error_of([] { parse(replaced("human_codes: targets", "human_code: targets")); }) ==
        "c.yaml:8: data.human_code: unknown key (did you mean 'human_codes'?)");
  CHECK(error_of([] { parse(replaced("human_codes: targets", "human_codes: people")); }) ==
        "c.yaml:8: data.human_codes: expected 'subjects' or 'targets', got 'people'");
  CHECK(error_of([] { parse(replaced("name: three, epochs: 2, lr: 1.0e-3", "name: three, epochs: 2, lr: -1")); }) ==
        "c.yaml:15: stages[2].lr: expected a positive number, got -1");
  CHECK_THROWS_WITH(parse(replaced("{name: one, epochs: 3", "{name: one, epochs: -3")),
                    Catch::Contains("c.yaml:13: stages[0].epochs") && Catch::Contains("-3"));
  CHECK_THROWS_WITH(parse(replaced("triplet: 10}", "triplet: -10}")),
                    Catch::Contains("stages[2].weights.triplet: expected a number >= 0"));
  CHECK_THROWS_WITH(parse(replaced("weights: {paired: 1, group: 0, triplet: 0}", "weights: {paired: 1, group: 0}")),
                    Catch::Contains("stages[0].weights.triplet: missing required key"));
  CHECK(error_of([] { parse(replaced("weights: {paired: 1, group: 0,", "weights: {paired: 1, grup: 0,")); }) ==
        "c.yaml:13: stages[0].weights.grup: unknown key (did you mean 'group'?)");
  CHECK_THROWS_WITH(parse(replaced("epochs: 3,", "epochs: 3, decay: 0.5,")),
                    Catch::Contains("stages[0].decay: unknown key"));
  CHECK_THROWS_WITH(parse(replaced("held_out_fraction: 0.25", "held_out_fraction: 1")),
                    Catch::Contains("data.held_out_fraction") && Catch::Contains("[0, 1)"));
  CHECK_THROWS_WITH(parse(replaced("margin: 0.3", "margin: -0.3")), Catch::Contains("loss.margin"));
  CHECK(error_of([] { parse(replaced("triplet_scale: absolute", "triplet_scale: relative")); }) ==
        "c.yaml:10: loss.triplet_scale: expected 'group' or 'absolute', got 'relative'");
  CHECK_THROWS_WITH(parse(replaced("batch_size: 8", "batch_size: 0")), Catch::Contains("training.batch_size"));
  CHECK(error_of([] { parse(replaced("threads: 1}", "threads: 1, input_noise: -1}")); }) ==
        "c.yaml:11: training.input_noise: expected a finite number >= 0 (a multiple of the codes' spread), got -1");
  CHECK_THROWS_WITH(parse(replaced("hidden: 16", "hidden: 0")), Catch::Contains("model.hidden"));
  CHECK(error_of([] { parse(replaced("  avatar_vae: runs/avatar\n", "")); }) ==
        "c.yaml: data.avatar_vae: missing: the run folder of the avatar VAE the correspondences were built with; "
        "give it with --set data.avatar_vae=PATH (the profiles under configs/train name no run's files)");
  CHECK_THROWS_WITH(
      parse(replaced("  human_vae: runs/human\n", "  human_vae: runs/human\n  human_checkpoint: first\n")),
      Catch::Contains("data.human_checkpoint") && Catch::Contains("'best' or 'last'"));
  CHECK_THROWS_WITH(parse(replaced("task: translation", "task: vae")),
                    Catch::Contains("task") && Catch::Contains("expected 'translation'"));
  CHECK_THROWS_WITH(parse(replaced("task: translation", "task: gan")),
                    Catch::Contains("unknown task 'gan'") && Catch::Contains("translation"));
  CHECK_THROWS_WITH(parse(replaced("stages:\n", "stage:\n")), Catch::Contains("did you mean 'stages'"));
  // Every stage empty: nothing to train.
  std::string none = replaced("epochs: 3,", "epochs: 0,");
  none.replace(none.find("epochs: 2,"), 10, "epochs: 0,");
  CHECK_THROWS_WITH(parse(none), Catch::Contains("stages: expected at least one epoch"));

  // --set overrides reach the keys.
  ConfigNode root = ConfigNode::parse(kGood, "c.yaml");
  root.apply_override("training.seed=9");
  root.apply_override("data.human_codes=subjects");
  const TranslationTrainConfig overridden = read_translation_train_config(root);
  CHECK(overridden.training.seed == 9);
  CHECK(overridden.data.human_codes == HumanCodes::subjects);
}
