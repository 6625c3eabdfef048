#include "core/config_base.h"

#include <catch2/catch.hpp>
#include <filesystem>
#include <string>
#include <vector>

#include "core/config.h"
#include "core/error.h"
#include "scratch.h"

namespace retarget {
namespace {

namespace fs = std::filesystem;
using Catch::Contains;
using test::error_of;
using test::scratch_dir;
using test::write_file;

// The paper-like base, a quick overlay on it and a good overlay on the quick one, in
// dir/{paper.yaml, quick/quick.yaml, good/good.yaml}.
void write_chain(const fs::path& dir) {
  fs::create_directories(dir / "quick");
  fs::create_directories(dir / "good");
  write_file(dir, "paper.yaml",
             "task: vae\n"
             "data:\n"
             "  validation_fraction: 0.1\n"
             "model:\n"
             "  channels: [9, 128, 64, 1]\n"
             "  hidden: 300\n"
             "optimiser: {lr: 1.0e-4, betas: [0.9, 0.999]}\n"
             "schedule: {decay: 0.6, every: 10}\n"
             "training:\n"
             "  epochs: 100\n"
             "  batch_size: 30\n");
  write_file(dir / "quick", "quick.yaml",
             "# the quick one\n"
             "base: ../paper.yaml\n"
             "model:\n"
             "  channels: [9, 32, 1]\n"
             "  latent: auto\n"
             "schedule:\n"
             "  every: 3\n"
             "training:\n"
             "  epochs: 10\n");
  write_file(dir / "good", "good.yaml",
             "base: ../quick/quick.yaml\n"
             "training: {epochs: 24}\n"
             "optimiser:\n"
             "  lr: fast\n");
}

TEST_CASE("a config with a base: maps merge key by key, lists and scalars are replaced whole", "[config]") {
  const fs::path dir = scratch_dir("config_base_merge");
  write_chain(dir);
  const ConfigNode quick = load_config_with_bases((dir / "quick" / "quick.yaml").string());
  CHECK(quick.file() == (dir / "quick" / "quick.yaml").string());
  CHECK_FALSE(quick.has("base"));  // the key is the loader's, no reader sees it
  CHECK(quick.child("task").as<std::string>() == "vae");
  // A nested key overridden; its siblings kept from the base.
  CHECK(quick.child("schedule").child("every").as<int>() == 3);
  CHECK(quick.child("schedule").child("decay").as<double>() == 0.6);
  CHECK(quick.child("model").child("hidden").as<int>() == 300);
  CHECK(quick.child("model").child("latent").as<std::string>() == "auto");  // a key the base lacks
  // A list is replaced, not merged item by item: the base's [9, 128, 64, 1] is gone.
  CHECK(quick.child("model").child("channels").as<std::vector<int>>() == std::vector<int>{9, 32, 1});
  CHECK(quick.child("optimiser").child("betas").as<std::vector<double>>() == std::vector<double>{0.9, 0.999});
  CHECK(quick.child("training").child("epochs").as<int>() == 10);
  CHECK(quick.child("training").child("batch_size").as<int>() == 30);
  CHECK(quick.child("data").child("validation_fraction").as<double>() == 0.1);
}

TEST_CASE("bases chain, and each value is blamed on the file and line it came from", "[config]") {
  const fs::path dir = scratch_dir("config_base_chain");
  write_chain(dir);
  const std::string good_file = (dir / "good" / "good.yaml").string();
  const std::string quick_file = (dir / "quick" / "quick.yaml").string();
  const std::string paper_file = (dir / "paper.yaml").string();
  const ConfigNode good = load_config_with_bases(good_file);
  // The files it is made of, itself first (a pipeline stage digests them all).
  CHECK(config_chain_files(good_file) == std::vector<std::string>{fs::weakly_canonical(good_file).string(),
                                                                  fs::weakly_canonical(quick_file).string(),
                                                                  fs::weakly_canonical(paper_file).string()});
  CHECK(good.child("training").child("epochs").as<int>() == 24);      // good's own
  CHECK(good.child("training").child("batch_size").as<int>() == 30);  // the paper's, through quick
  CHECK(good.child("schedule").child("every").as<int>() == 3);        // quick's
  CHECK(good.child("model").child("channels").as<std::vector<int>>() == std::vector<int>{9, 32, 1});
  CHECK(good.child("optimiser").child("betas").size() == 2);

  CHECK(good.source("training.epochs") == good_file);
  CHECK(good.source("training.batch_size") == paper_file);
  CHECK(good.source("schedule.every") == quick_file);
  CHECK(good.source("schedule.decay") == paper_file);
  CHECK(good.source("model.channels[1]") == quick_file);
  CHECK(good.source("model.hidden") == paper_file);
  CHECK(good.source("task") == paper_file);
  // Messages name the file and its own line, wherever the value came from.
  CHECK(error_of([&] { good.child("optimiser").child("lr").as<double>(); }) ==
        good_file + ":4: optimiser.lr: expected a number, got \"fast\"");
  CHECK(error_of([&] { good.child("model").child("hidden").as<bool>(); }) ==
        paper_file + ":6: model.hidden: expected true or false, got 300");
  CHECK(error_of([&] { good.child("schedule").child("every").as<bool>(); }) ==
        quick_file + ":7: schedule.every: expected true or false, got 3");
  CHECK(error_of([&] { good.child("optimiser").child("betas").at(1).as<bool>(); }) ==
        paper_file + ":7: optimiser.betas[1]: expected true or false, got 0.999");
  CHECK_THAT(error_of([&] {
               good.child("model").reject_unknown_keys({"channels", "hidden"});
             }),
             Contains(quick_file + ":5: model.latent: unknown key"));
  // --set overrides apply after the merge and are blamed on themselves.
  ConfigNode overridden = load_config_with_bases(good_file);
  overridden.apply_override("model.hidden=wide");
  overridden.apply_override("schedule={decay: 0.5}");
  CHECK(error_of([&] { overridden.child("model").child("hidden").as<int>(); }) ==
        "--set model.hidden=wide: model.hidden: expected an integer, got \"wide\"");
  CHECK_FALSE(overridden.child("schedule").has("every"));  // a --set map replaces the merged map whole
  CHECK(overridden.source("schedule.decay") == "--set schedule={decay: 0.5}");
  CHECK(overridden.child("model").child("channels").as<std::vector<int>>() == std::vector<int>{9, 32, 1});
}

TEST_CASE("a section left empty in an overlay keeps the base's, a null scalar replaces it", "[config]") {
  const fs::path dir = scratch_dir("config_base_null");
  write_file(dir, "base.yaml", "model: {hidden: 300, order: 2}\ndata: {triplets: runs/a, fraction: 0.2}\n");
  write_file(dir, "overlay.yaml",
             "base: base.yaml\n"
             "model:\n"
             "  # hidden: 100   (commented out: the section keeps the base's keys)\n"
             "data:\n"
             "  triplets:\n");
  const ConfigNode merged = load_config_with_bases((dir / "overlay.yaml").string());
  CHECK(merged.child("model").child("hidden").as<int>() == 300);
  CHECK(merged.child("model").child("order").as<int>() == 2);
  CHECK(merged.child("data").child("triplets").is_null());
  CHECK(merged.child("data").child("fraction").as<double>() == 0.2);
}

TEST_CASE("a file without base: loads as it is", "[config]") {
  const fs::path dir = scratch_dir("config_base_none");
  const std::string file = write_file(dir, "plain.yaml", "a: 1\nb: [2, 3]\n");
  const ConfigNode plain = load_config_with_bases(file);
  CHECK(plain.child("a").as<int>() == 1);
  CHECK(plain.source("b[1]") == file);
  CHECK(load_config_with_bases(write_file(dir, "empty.yaml", "# nothing\n")).size() == 0);
}

TEST_CASE("a missing base, a cycle of bases and a base that is not a map name the file and the chain", "[config]") {
  const fs::path dir = scratch_dir("config_base_errors");
  fs::create_directories(dir / "sub");
  const std::string a = (dir / "a.yaml").string(), b = (dir / "sub" / "b.yaml").string();

  // Missing: named as written and as resolved, with the chain that led there.
  write_file(dir, "a.yaml", "task: vae\nbase: sub/b.yaml\n");
  write_file(dir / "sub", "b.yaml", "base: ../missing.yaml\n");
  CHECK(error_of([&] { load_config_with_bases(a); }) == b + ":1: base: ../missing.yaml: no such file (" +
                                                            (dir / "missing.yaml").string() + "); chain: " + a +
                                                            " -> " + b + " -> " + (dir / "missing.yaml").string());

  // A cycle, through a path spelled differently.
  write_file(dir / "sub", "b.yaml", "base: ../sub/../a.yaml\n");
  CHECK(error_of([&] { load_config_with_bases(a); }) ==
        b + ":1: base: ../sub/../a.yaml: a cycle of bases: " + a + " -> " + b + " -> " + a);
  CHECK_THAT(error_of([&] { config_chain_files(a); }), Contains("a cycle of bases"));
  write_file(dir, "self.yaml", "base: self.yaml\n");
  CHECK_THAT(error_of([&] { load_config_with_bases((dir / "self.yaml").string()); }),
             Contains("self.yaml:1: base: self.yaml: a cycle of bases"));

  // A base whose document is a list, a single value or nothing.
  for (const auto& [text, shape] : {std::pair<const char*, const char*>{"- 1\n- 2\n", "a list"},
                                    {"just text\n", "a single value"},
                                    {"# nothing\n", "empty"}}) {
    write_file(dir / "sub", "b.yaml", text);
    CHECK(error_of([&] { load_config_with_bases(a); }) ==
          b + ": a base config must be a map of keys, and this document is " + shape + "; chain: " + a + " -> " + b);
  }

  // The base: key itself: a path, not a list, a map, nothing or "".
  for (const char* value : {"[a.yaml]", "{file: a.yaml}", "", "\"\""}) {
    write_file(dir, "a.yaml", std::string("base: ") + value + "\n");
    CHECK_THAT(error_of([&] { load_config_with_bases(a); }),
               Contains(a + ":1: base: expected the path of a config file (relative to this one)"));
  }
  write_file(dir, "a.yaml", "base: sub\n");
  CHECK_THAT(error_of([&] { load_config_with_bases(a); }), Contains(a + ":1: base: sub: not a file"));

  // A base's own errors name the base.
  write_file(dir, "a.yaml", "base: sub/b.yaml\n");
  write_file(dir / "sub", "b.yaml", "x: 1\nx: 2\n");
  CHECK_THAT(error_of([&] { load_config_with_bases(a); }), Contains(b + ":2") && Contains("duplicate key"));
}

}  // namespace
}  // namespace retarget
