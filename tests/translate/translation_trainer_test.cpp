#include "translate/translation_trainer.h"

#include <torch/torch.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <functional>
#include <vector>

#include "annotate/annotation_store.h"
#include "child_process.h"
#include "cli/commands.h"
#include "core/error.h"
#include "correspond/annotation_project.h"
#include "correspond/correspondence.h"
#include "data/dataset.h"
#include "export/bundle_export.h"
#include "tiny_correspondence.h"
#include "tiny_data.h"
#include "tiny_vae_runs.h"
#include "train/checkpoint.h"
#include "train/vae_run.h"
#include "train/vae_trainer.h"
#include "translate/translation_data.h"
#include "translate/translation_run.h"

using namespace retarget;
using namespace retarget::test;
namespace fs = std::filesystem;

namespace {

// The tiny data of tests/tiny_correspondence.h (a human dataset of 8 people x neutral, A,
// AB, C, 36 vertices; an avatar dataset of 60 samples, 64 vertices) with a human VAE (latent 3),
// two avatar VAEs (latent 4; the correspondences use the first), correspondences with groups of
// 6, and an annotation project whose tournaments are all decided (the smaller sample id wins).
struct TranslationFixture {
  std::string human_vae, avatar_vae, correspondences, project, other_avatar_vae, human_dataset;
};

const TranslationFixture& fixture() {
  static const TranslationFixture f = [] {
    const TinyCorrespondenceData& data = tiny_correspondence_data();
    const fs::path dir = process_scratch_dir("translation_fixture");
    TranslationFixture t;
    t.human_dataset = data.human;
    const std::string avatar_dataset = data.avatar;

    t.human_vae = (dir / "human_vae").string();
    train_tiny_vae(tiny_vae_config(t.human_dataset, t.human_vae, 3, 11));
    t.avatar_vae = (dir / "avatar_vae").string();
    train_tiny_vae(tiny_vae_config(avatar_dataset, t.avatar_vae, 4, 7));
    t.other_avatar_vae = (dir / "other_avatar_vae").string();
    train_tiny_vae(tiny_vae_config(avatar_dataset, t.other_avatar_vae, 4, 12));
    CorrespondenceOptions c;
    c.group_size = 6;
    c.progress = nullptr;
    t.correspondences = (dir / "corr").string();
    build_correspondences(t.human_dataset, avatar_dataset, t.avatar_vae, t.correspondences, c);
    t.project = (dir / "project").string();
    const AnnotationProject project = init_annotation_project(t.correspondences, t.project);
    AnnotationStore store = AnnotationStore::open(project.database());
    while (auto next = store.next_comparison("tester", 300))
      store.answer(next->comparison, "tester", next->left < next->right ? Answer::left : Answer::right);
    return t;
  }();
  return f;
}

// A small, fast config: stage 1 (L_P only, 3 epochs), an empty stage 2, stage 3 (all terms, 2).
std::string config_text(const std::string& output, const std::string& codes = "subjects",
                        const std::string& stages = "") {
  const TranslationFixture& f = fixture();
  return "task: translation\n"
         "data:\n"
         "  human_vae: " +
         f.human_vae +
         "\n"
         "  avatar_vae: " +
         f.avatar_vae +
         "\n"
         "  correspondences: " +
         f.correspondences +
         "\n"
         "  triplets: " +
         f.project +
         "\n"
         "  held_out_fraction: 0.25\n"
         "  human_codes: " +
         codes +
         "\n"
         "model: {hidden: 16}\n"
         "training: {batch_size: 5, checkpoint_every: 1, seed: 3, threads: 1}\n"
         "stages:\n" +
         (stages.empty() ? "  - {name: paired, epochs: 3, lr: 1.0e-2, weights: {paired: 1, group: 0, triplet: 0}}\n"
                           "  - {name: group, epochs: 0, lr: 1.0e-3, weights: {paired: 1, group: 1, triplet: 0}}\n"
                           "  - {name: triplet, epochs: 2, lr: 5.0e-3, weights: {paired: 1, group: 0.5, triplet: 2}}\n"
                         : stages) +
         "output: " + output + "\n";
}

TranslationTrainConfig config_for(const std::string& output, const std::string& codes = "subjects",
                                  const std::string& stages = "") {
  return read_translation_train_config(ConfigNode::parse(config_text(output, codes, stages), "translation.yaml"));
}

TranslationTrainOptions quiet(RunStart start = RunStart::fresh, int stop_after = -1) {
  TranslationTrainOptions o;
  o.start = start;
  o.progress = nullptr;
  o.stop_after_epochs = stop_after;
  return o;
}

std::map<std::string, torch::Tensor> weights_of(const std::string& run, const std::string& which) {
  const TrainedTranslation t = load_trained_translation(run, which);
  std::map<std::string, torch::Tensor> out;
  for (const auto& p : t.translation->named_parameters()) out[p.key()] = p.value().clone();
  return out;
}

void check_equal_weights(const std::map<std::string, torch::Tensor>& a, const std::map<std::string, torch::Tensor>& b) {
  REQUIRE(a.size() == b.size());
  for (const auto& [name, value] : a) {
    INFO(name);
    CHECK(torch::equal(value, b.at(name)));
  }
}

int run_cli(const std::vector<std::string>& args) {
  std::vector<std::string> storage = args;
  std::vector<char*> argv;
  for (std::string& a : storage) argv.push_back(a.data());
  return cli::export_command(static_cast<int>(argv.size()), argv.data());
}

}  // namespace

TEST_CASE("translation data: codes, groups and triplets from the runs", "[translation_trainer]") {
  const TranslationFixture& f = fixture();
  TranslationDataOptions o = config_for("unused").data;
  const TranslationData d = load_translation_data(o, 3);
  const Dataset human = load_dataset(f.human_dataset);
  CHECK(d.expressions == std::vector<std::string>{"neutral", "A", "AB", "C"});
  // subjects: every training subject's sample of every expression (6 training people x 4).
  CHECK(d.inputs.sizes().vec() == std::vector<int64_t>{6 * 4, 3});
  CHECK(d.test_inputs.sizes().vec() == std::vector<int64_t>{2 * 4, 3});
  CHECK(d.y0.sizes().vec() == std::vector<int64_t>{4, 4});
  CHECK(d.group_codes.sizes().vec() == std::vector<int64_t>{4, 6, 4});
  // A full tournament of 6 candidates decides 5 comparisons per group, more with derived ones.
  CHECK(d.triplets_loaded > 4 * 5);
  CHECK(d.held_out_triplets.triplets == std::llround(0.25 * d.triplets_loaded));
  CHECK(d.train_triplets.triplets + d.held_out_triplets.triplets == d.triplets_loaded);
  // Each triplet counts once per input of its expression (6 each).
  CHECK(d.train_triplets.rows() == 6 * d.train_triplets.triplets);
  // The rows' codes are group codes of their expression.
  const Correspondences c = load_correspondences(f.correspondences);
  for (int64_t r = 0; r < d.train_triplets.rows(); r += 7) {
    const int64_t k = d.input_expression[d.train_triplets.anchor[r].item<int64_t>()].item<int64_t>();
    const torch::Tensor diff = (c.group_codes[k] - d.train_triplets.positive[r]).abs().sum(1);
    CHECK(diff.min().item<double>() == 0.0);
    // The row's unit under triplet_scale: group is 1 / its group's spread.
    CHECK(d.train_triplets.group_scale[r].item<double>() == Approx(1.0 / d.group_spread[k].item<double>()));
  }
  // Group spread: the mean squared distance of a group's codes from their centroid.
  for (int64_t k = 0; k < 4; ++k) {
    const torch::Tensor codes = c.group_codes[k].to(torch::kFloat64);
    const double spread = (codes - codes.mean(0)).pow(2).sum(1).mean().item<double>();
    CHECK(d.group_spread[k].item<double>() == Approx(std::max(spread, kMinGroupSpread)).epsilon(1e-4));
  }
  CHECK(d.held_out_triplets.group_scale.size(0) == d.held_out_triplets.rows());
  // targets: one input per expression, the code of the identity-averaged target.
  o.human_codes = HumanCodes::targets;
  const TranslationData t = load_translation_data(o, 3);
  CHECK(t.inputs.sizes().vec() == std::vector<int64_t>{4, 3});
  CHECK(torch::equal(t.input_expression, torch::arange(4, torch::kInt64)));
  TrainedVae h = load_trained_vae(f.human_vae, "best");
  const torch::Tensor expected = encoder_means(h, human.targets.index_select(0, torch::tensor({0, 1, 2, 3})));
  CHECK(torch::allclose(t.inputs, expected));
  CHECK(t.train_triplets.rows() == t.train_triplets.triplets);
}

TEST_CASE("translation data: mismatched runs and triplets fail with a message", "[translation_trainer]") {
  const TranslationFixture& f = fixture();
  TrainedVae human = load_trained_vae(f.human_vae, "best");
  TrainedVae avatar = load_trained_vae(f.avatar_vae, "best");
  const Correspondences c = load_correspondences(f.correspondences);
  std::vector<Triplet> triplets = load_project_triplets(f.project, false);
  REQUIRE(!triplets.empty());
  CHECK_NOTHROW(make_translation_data(human, avatar, c, triplets, "p.db", HumanCodes::subjects, 0.2, 1));

  // A sample outside the group, named with the triplet.
  std::vector<Triplet> bad = triplets;
  bad[1].positive = 999;
  CHECK(error_of([&] { make_translation_data(human, avatar, c, bad, "p.db", HumanCodes::subjects, 0.2, 1); })
            .find("p.db: triplet (group " + std::to_string(bad[1].group) + " \"" + bad[1].anchor +
                  "\", positive 999, negative " + std::to_string(bad[1].negative) +
                  "): avatar sample 999 is not in the group of \"" + bad[1].anchor + "\"") != std::string::npos);
  bad = triplets;
  bad[0].anchor = "frown";
  CHECK_THROWS_WITH(make_translation_data(human, avatar, c, bad, "p.db", HumanCodes::subjects, 0.2, 1),
                    Catch::Contains("p.db: triplet") && Catch::Contains("no expression \"frown\""));

  // The VAEs swapped, and an avatar VAE that did not make y0.
  CHECK_THROWS_WITH(make_translation_data(avatar, human, c, triplets, "p.db", HumanCodes::subjects, 0.2, 1),
                    Catch::Contains("data.human_vae needs a human one"));
  TrainedVae other = load_trained_vae(f.other_avatar_vae, "best");
  CHECK_THROWS_WITH(make_translation_data(human, other, c, triplets, "p.db", HumanCodes::subjects, 0.2, 1),
                    Catch::Contains(f.other_avatar_vae) && Catch::Contains("does not reproduce the codes y0") &&
                        Catch::Contains(c.avatar_vae_run));

  // Through a config: a missing project, a human run in place of the avatar run.
  TranslationDataOptions o = config_for("unused").data;
  o.triplets = (fs::path(f.project) / "nothing").string();
  CHECK_THROWS_WITH(load_translation_data(o, 1), Catch::Contains("nothing") && Catch::Contains("no such annotation"));
  o = config_for("unused").data;
  o.avatar_vae = f.human_vae;
  CHECK_THROWS(load_translation_data(o, 1));
}

TEST_CASE("translation data: F learns from another human dataset, coded by the human VAE's own encoder",
          "[translation_trainer]") {
  const TranslationFixture& f = fixture();
  TrainedVae human = load_trained_vae(f.human_vae, "best");
  TrainedVae avatar = load_trained_vae(f.avatar_vae, "best");
  const Correspondences c = load_correspondences(f.correspondences);
  const std::vector<Triplet> triplets = load_project_triplets(f.project, false);
  const TranslationData own = make_translation_data(human, avatar, c, triplets, "p.db", HumanCodes::subjects, 0.2, 1);
  // Other faces of the same people and expressions (here: the same folder's, moved further):
  // their codes are the VAE's encoder and normaliser applied to them, not the VAE's own faces'.
  Dataset faces = load_dataset(f.human_dataset);
  faces.features = faces.features * 1.5;
  const TranslationData other =
      make_translation_data(human, avatar, c, triplets, "p.db", HumanCodes::subjects, 0.2, 1, &faces);
  REQUIRE(other.inputs.sizes() == own.inputs.sizes());
  CHECK(torch::equal(other.input_expression, own.input_expression));
  CHECK_FALSE(torch::allclose(other.inputs, own.inputs));
  std::vector<int64_t> rows;
  const auto e = faces.expression.accessor<int64_t, 1>();
  for (const int64_t row : faces.train)
    if (std::find(c.expressions.begin(), c.expressions.end(), faces.expressions[static_cast<size_t>(e[row])]) !=
        c.expressions.end())
      rows.push_back(row);
  CHECK(torch::allclose(other.inputs, encoder_means(human, faces.features.index_select(0, torch::tensor(rows)))));
  // An avatar dataset, or faces of another topology, are named.
  Dataset wrong = load_dataset(avatar.dataset.folder);
  CHECK_THROWS_WITH(make_translation_data(human, avatar, c, triplets, "p.db", HumanCodes::subjects, 0.2, 1, &wrong),
                    Catch::Contains(wrong.folder) && Catch::Contains("needs a human one"));
  wrong.kind = DatasetKind::human;
  CHECK_THROWS_WITH(make_translation_data(human, avatar, c, triplets, "p.db", HumanCodes::subjects, 0.2, 1, &wrong),
                    Catch::Contains("data.human_dataset needs the VAE's topology"));
  // Through a config: data.human_dataset.
  TranslationDataOptions o = config_for("unused").data;
  o.human_dataset = avatar.dataset.folder;
  CHECK_THROWS_WITH(load_translation_data(o, 1), Catch::Contains("data.human_dataset needs a human one"));
  o.human_dataset = f.human_dataset;
  CHECK(torch::allclose(load_translation_data(o, 1).inputs, own.inputs));
}

TEST_CASE("translation training follows its stages, lowers L_P and fills its run folder", "[translation_trainer]") {
  const fs::path out = scratch_dir("translation_stages") / "run";
  const TranslationTrainConfig config = config_for(out.string());
  const TranslationTrainSummary s = train_translation(config, quiet());
  CHECK(s.finished);
  CHECK(s.epochs_done == 5);
  CHECK(s.inputs == 24);
  CHECK(s.held_out_triplets > 0);
  for (const char* file : {"config.yaml", "run.yaml", "metrics.jsonl", "metrics.csv", "checkpoints/last.pt",
                           "checkpoints/stage1.pt", "checkpoints/stage2.pt", "checkpoints/stage3.pt"})
    CHECK(fs::exists(out / file));
  CHECK_FALSE(fs::exists(out / "checkpoints" / "best.pt"));

  const auto metrics = read_metrics(out.string());
  REQUIRE(metrics.size() == 5);
  // Epochs 1-3: stage 1; the 0-epoch stage 2 is skipped; epochs 4-5: stage 3.
  const std::vector<double> stage = {1, 1, 1, 3, 3}, lr = {1e-2, 1e-2, 1e-2, 5e-3, 5e-3};
  const std::vector<double> group = {0, 0, 0, 0.5, 0.5}, triplet = {0, 0, 0, 2, 2};
  for (size_t e = 0; e < metrics.size(); ++e) {
    INFO("epoch " << e + 1);
    CHECK(metrics[e].at("epoch") == e + 1);
    CHECK(metrics[e].at("stage") == stage[e]);
    CHECK(metrics[e].at("lr") == Approx(lr[e]));
    CHECK(metrics[e].at("weight_paired") == 1);
    CHECK(metrics[e].at("weight_group") == group[e]);
    CHECK(metrics[e].at("weight_triplet") == triplet[e]);
    const auto& m = metrics[e];
    CHECK(m.at("loss") == Approx(m.at("paired") + group[e] * m.at("group") + triplet[e] * m.at("triplet")));
    for (const char* key : {"train_accuracy", "held_out_accuracy", "held_out_triplet", "test_paired"}) {
      INFO(key);
      CHECK(std::isfinite(m.at(key)));
    }
    CHECK(m.at("held_out_accuracy") >= 0);
    CHECK(m.at("held_out_accuracy") <= 1);
  }
  CHECK(metrics[2].at("paired") < metrics[0].at("paired"));
  REQUIRE(s.stages.size() == 2);  // the skipped stage is not listed
  CHECK(s.stages[0].name == "paired");
  CHECK(s.stages[0].end.epoch == 3);
  CHECK(s.stages[1].name == "triplet");
  CHECK(s.stages[1].end.epoch == 5);

  // Snapshots: stage 1 and the skipped stage 2 hold F after epoch 3, stage 3 the last weights.
  const auto stage1 = weights_of(out.string(), "stage1");
  check_equal_weights(stage1, weights_of(out.string(), "stage2"));
  check_equal_weights(weights_of(out.string(), "stage3"), weights_of(out.string(), "last"));
  CHECK(load_trained_translation(out.string(), "stage1").state.epoch == 3);
  CHECK_FALSE(torch::equal(stage1.at("g.weight"), weights_of(out.string(), "last").at("g.weight")));
  CHECK_THROWS_WITH(load_trained_translation(out.string(), "stage4"),
                    Catch::Contains("--checkpoint") && Catch::Contains("stage1 .. stage3"));
  CHECK_THROWS_WITH(load_trained_translation(out.string(), "best"), Catch::Contains("'last'"));
  CHECK_THROWS_WITH(load_trained_vae(out.string(), "best"), Catch::Contains("not a VAE run"));

  const RunStatus status = RunStatus::load(out.string());
  CHECK(status.task == "translation");
  CHECK(status.status == "finished");
  CHECK(status.fingerprints.count("human_dataset") == 1);
  CHECK(status.fingerprints.count("avatar_dataset") == 1);
  CHECK(to_yaml(read_translation_train_config(ConfigNode::load_file((out / "config.yaml").string()))) ==
        to_yaml(config));
  CHECK_THROWS_WITH(train_translation(config, quiet()), Catch::Contains("finished run") && Catch::Contains("--force"));
}

TEST_CASE("training F reduces L_P on a tiny problem", "[translation_trainer]") {
  const fs::path out = scratch_dir("translation_paired") / "run";
  const TranslationTrainConfig config =
      config_for(out.string(), "targets",
                 "  - {name: paired, epochs: 60, lr: 1.0e-2, weights: {paired: 1, group: 0, triplet: 0}}\n");
  const TranslationTrainSummary s = train_translation(config, quiet());
  CHECK(s.finished);
  CHECK(s.inputs == 4);
  CHECK(s.last.paired < 0.2 * s.first.paired);
}

TEST_CASE("a resumed translation run ends with the same weights as an uninterrupted one", "[translation_trainer]") {
  const fs::path dir = scratch_dir("translation_resume");
  const TranslationTrainConfig straight = config_for((dir / "straight").string());
  train_translation(straight, quiet());
  for (int stop : {2, 3}) {  // mid-stage, and at the stage boundary
    INFO("stopped after " << stop);
    const std::string folder = (dir / ("interrupted" + std::to_string(stop))).string();
    const TranslationTrainConfig interrupted = config_for(folder);
    const TranslationTrainSummary first = train_translation(interrupted, quiet(RunStart::fresh, stop));
    CHECK_FALSE(first.finished);
    CHECK(first.epochs_done == stop);
    // As if the process died after logging the next epoch but before its checkpoint.
    std::ofstream((fs::path(folder) / "metrics.jsonl").string(), std::ios::app)
        << "{\"epoch\": " << stop + 1 << ", \"lr\": 1}\n";
    CHECK_THROWS_WITH(train_translation(interrupted, quiet()), Catch::Contains("--resume"));
    const TranslationTrainSummary second = train_translation(interrupted, quiet(RunStart::resume));
    CHECK(second.finished);
    CHECK(second.epochs_run == 5 - stop);
    check_equal_weights(weights_of((dir / "straight").string(), "last"), weights_of(folder, "last"));
    check_equal_weights(weights_of((dir / "straight").string(), "stage1"), weights_of(folder, "stage1"));
    const auto ma = read_metrics((dir / "straight").string());
    const auto mb = read_metrics(folder);
    REQUIRE(mb.size() == ma.size());
    for (size_t i = 0; i < ma.size(); ++i) {
      CHECK(ma[i].at("loss") == mb[i].at("loss"));
      CHECK(ma[i].at("held_out_accuracy") == mb[i].at("held_out_accuracy"));
    }
  }
}

TEST_CASE("input noise: F trains on noisy codes, the same on every run and after a resume", "[translation_trainer]") {
  const fs::path dir = scratch_dir("translation_noise");
  auto noisy = [&](const std::string& name) {
    ConfigNode root = ConfigNode::parse(config_text((dir / name).string(), "subjects", ""), "translation.yaml");
    root.apply_override("training.input_noise=2");
    return read_translation_train_config(root);
  };
  train_translation(config_for((dir / "quiet").string()), quiet());
  train_translation(noisy("straight"), quiet());
  train_translation(noisy("again"), quiet());
  check_equal_weights(weights_of((dir / "straight").string(), "last"), weights_of((dir / "again").string(), "last"));
  // The noise changes what F learns...
  const auto plain = weights_of((dir / "quiet").string(), "last");
  const auto with_noise = weights_of((dir / "straight").string(), "last");
  double difference = 0;
  for (const auto& [name, value] : plain) difference += (value - with_noise.at(name)).abs().sum().item<double>();
  CHECK(difference > 1e-3);
  // ... and a run stopped mid-stage resumes to the same weights (the noise is seeded per epoch).
  const TranslationTrainConfig interrupted = noisy("interrupted");
  CHECK_FALSE(train_translation(interrupted, quiet(RunStart::fresh, 2)).finished);
  CHECK(train_translation(interrupted, quiet(RunStart::resume)).finished);
  check_equal_weights(with_noise, weights_of((dir / "interrupted").string(), "last"));
}

TEST_CASE("a translation run without triplets trains without L_T", "[translation_trainer]") {
  const fs::path out = scratch_dir("translation_no_triplets") / "run";
  ConfigNode root = ConfigNode::parse(config_text(out.string()), "t.yaml");
  root.apply_override("data.triplets=");
  const TranslationTrainConfig config = read_translation_train_config(root);
  CHECK(config.data.triplets.empty());
  const TranslationTrainSummary s = train_translation(config, quiet());
  CHECK(s.finished);
  CHECK(s.triplets == 0);
  const auto metrics = read_metrics(out.string());
  CHECK(metrics.back().at("triplet") == 0);
  CHECK(std::isnan(metrics.back().at("train_accuracy")));
  CHECK(std::isnan(metrics.back().at("held_out_accuracy")));
}

TEST_CASE("export of a translation run: the bundle equals decode(F(encode(x)))", "[translation_trainer][export]") {
  const TranslationFixture& f = fixture();
  const fs::path dir = scratch_dir("translation_export");
  train_translation(config_for((dir / "run").string()), quiet());

  for (const std::string which : {"last", "stage1"}) {
    INFO(which);
    const std::string out = (dir / ("bundle-" + which)).string();
    CHECK(run_cli({"export", (dir / "run").string(), "--checkpoint", which, "--out", out}) == 0);
    const LoadedBundle bundle = load_bundle(out);
    CHECK(bundle.metadata.human.latent == 3);
    CHECK(bundle.metadata.avatar.latent == 4);
    CHECK(bundle.metadata.translation_hidden == 16);
    // The avatar dataset's rig travels with it (retarget-infer --weights), with its mm scale.
    REQUIRE(bundle.rig.has_value());
    CHECK(bundle.rig->controller_count() == 4);
    CHECK(bundle.metadata.rig->controllers[0].name == "ctrl0");
    CHECK(bundle.metadata.rig->millimetres_per_unit > 0);

    // Real features of the human test subjects, through the framework's modules.
    TrainedVae human = load_trained_vae(f.human_vae, "best");
    TrainedVae avatar = load_trained_vae(f.avatar_vae, "best");
    TrainedTranslation t = load_trained_translation((dir / "run").string(), which);
    const Dataset& hd = human.dataset;
    const torch::Tensor x = hd.features.index_select(0, torch::tensor(hd.test)).to(torch::kFloat32);
    torch::NoGradGuard no_grad;
    const torch::Tensor code = human.vae->encode(hd.normaliser.normalise(x)).mean;
    const torch::Tensor expected =
        avatar.dataset.normaliser.denormalise(avatar.vae->decode(t.translation->forward(code)));
    torch::jit::Module module = bundle.module;
    const torch::Tensor y = module.forward({x}).toTensor();
    REQUIRE(y.sizes() == expected.sizes());
    CHECK((y - expected).abs().max().item<double>() < 1e-4);
  }
  CHECK_THROWS_WITH(
      run_cli({"export", (dir / "run").string(), "--checkpoint", "stage9", "--out", (dir / "bad").string()}),
      Catch::Contains("stage1 .. stage3"));
  // VAE runs still export through the same command.
  CHECK(run_cli({"export", f.human_vae, "--out", (dir / "vae").string()}) == 0);
  CHECK(fs::exists(dir / "vae" / "encoder.pt"));
}

TEST_CASE("translation data-parallel: two ranks end with the weights of one, also resumed from one rank",
          "[translation_trainer][parallel]") {
  const fs::path dir = scratch_dir("translation_two_ranks");
  // Batches of 5 inputs and their triplets, input noise on: both are split between the ranks.
  std::string text = config_text("unused");
  text.replace(text.find("threads: 1}"), 11, "threads: 1, input_noise: 0.5}");
  std::ofstream(dir / "f.yaml") << text;
  auto run = [&](const std::string& out, const std::vector<std::string>& extra) {
    std::vector<std::string> args{"train", (dir / "f.yaml").string(), "--out", (dir / out).string()};
    args.insert(args.end(), extra.begin(), extra.end());
    const int status = wait_for(spawn_retarget(args, dir / (out + ".log")));
    INFO(file_bytes(dir / (out + ".log")));
    REQUIRE((WIFEXITED(status) && WEXITSTATUS(status) == 0));
  };
  run("one", {});
  run("two", {"--nproc", "2"});
  auto largest_difference = [&](const std::string& x, const std::string& y) {
    const TrainedTranslation a = load_trained_translation((dir / x).string());
    const TrainedTranslation b = load_trained_translation((dir / y).string());
    double largest = 0;
    const auto pb = b.translation->named_parameters();
    for (const auto& p : a.translation->named_parameters())
      largest = std::max(largest, (p.value() - pb[p.key()]).abs().max().item<double>());
    return largest;
  };
  CHECK(largest_difference("one", "two") < 1e-5);
  // One rank for 2 epochs (mid-stage 1, stopped as if killed), then two ranks to the end.
  const TranslationTrainConfig part = read_translation_train_config(
      load_config_with_overrides((dir / "f.yaml").string(), {"output=" + (dir / "parts").string()}));
  REQUIRE(!train_translation(part, quiet(RunStart::fresh, 2)).finished);
  run("parts", {"--resume", "--nproc", "2"});
  CHECK(largest_difference("one", "parts") < 1e-5);
  CHECK(read_metrics((dir / "two").string()).size() == read_metrics((dir / "one").string()).size());
  CHECK(fs::exists(dir / "two/checkpoints/stage3.pt"));  // rank 0 wrote the stage snapshots
}
