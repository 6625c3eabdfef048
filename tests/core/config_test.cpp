#include "core/config.h"

#include <catch2/catch.hpp>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "core/error.h"
#include "scratch.h"

namespace retarget {
namespace {

using test::scratch_dir;

// The pattern every options struct follows: defaults in the struct, a loader that maps keys
// one to one, validate() naming the key path.
struct StageOptions {
  double lr = 1e-3;  // learning rate, > 0
  int epochs = 10;   // passes over the data, >= 1

  void validate(const std::string& path) const {
    require_positive(lr, key_path(path, "lr"));
    require(epochs >= 1, key_path(path, "epochs"), "expected at least 1 epoch, got " + std::to_string(epochs));
  }
};

struct TranslationOptions {
  int latent_size = 25;                   // size of x and y; required
  std::string loss = "l2";                // "l1" or "l2"
  bool shuffle = true;                    // reshuffle samples every epoch
  std::vector<double> weights{1.0, 0.5};  // L_P and L_G weights
  double dropout = 0.0;                   // in [0, 1)
  std::vector<StageOptions> stages;       // one per training stage

  void validate(const std::string& path) const {
    require_positive(latent_size, key_path(path, "latent_size"));
    require(loss == "l1" || loss == "l2", key_path(path, "loss"), "expected l1 or l2, got \"" + loss + "\"");
    require_in_range(dropout, 0.0, 0.99, key_path(path, "dropout"));
    for (size_t i = 0; i < stages.size(); ++i) stages[i].validate(path + ".stages[" + std::to_string(i) + "]");
  }
};

StageOptions read_stage(const ConfigNode& node) {
  node.reject_unknown_keys({"lr", "epochs"});
  StageOptions options;
  node.get("lr", options.lr);
  node.get("epochs", options.epochs);
  return options;
}

TranslationOptions read_translation(const ConfigNode& node) {
  node.reject_unknown_keys({"latent_size", "loss", "shuffle", "weights", "dropout", "stages"});
  TranslationOptions options;
  node.get_required("latent_size", options.latent_size);
  node.get("loss", options.loss);
  node.get("shuffle", options.shuffle);
  node.get("weights", options.weights);
  node.get("dropout", options.dropout);
  if (node.has("stages"))
    for (size_t i = 0; i < node.child("stages").size(); ++i)
      options.stages.push_back(read_stage(node.child("stages").at(i)));
  options.validate(node.path());
  return options;
}

const char* const kTranslationYaml = R"(# a training run
translation:
  latent_size: 25
  loss: l1
  weights: [2.0, 0.25]
  stages:
    - lr: 1.0e-3
      epochs: 20
    - lr: 5e-4
    - epochs: 3
      lr: 1e-4
)";

}  // namespace

TEST_CASE("an options struct loads from YAML, keeping defaults for absent keys", "[config]") {
  const ConfigNode root = ConfigNode::parse(kTranslationYaml, "run.yaml");
  const TranslationOptions options = read_translation(root.child("translation"));
  CHECK(options.latent_size == 25);
  CHECK(options.loss == "l1");
  CHECK(options.shuffle == true);  // default kept
  CHECK(options.weights == std::vector<double>{2.0, 0.25});
  REQUIRE(options.stages.size() == 3);
  CHECK(options.stages[0].lr == 1e-3);
  CHECK(options.stages[0].epochs == 20);
  CHECK(options.stages[1].epochs == 10);  // default kept
  CHECK(options.stages[2].lr == 1e-4);
  CHECK(root.child("translation").child("stages").at(2).child("lr").path() == "translation.stages[2].lr");
}

TEST_CASE("options errors name the file, line and key path", "[config]") {
  const std::string prefix = "translation:\n  latent_size: 25\n  stages:\n    - lr: 1e-3\n    - {}\n";
  auto load = [&](const std::string& tail) {
    read_translation(ConfigNode::parse(prefix + tail, "run.yaml").child("translation"));
  };

  // The example from the design guide.
  CHECK_THROWS_WITH(load("    - lr: fast\n"), "run.yaml:6: translation.stages[2].lr: expected a number, got \"fast\"");
  // validate() knows the key path but not the line.
  CHECK_THROWS_WITH(load("    - lr: -0.5\n"), "translation.stages[2].lr: expected a positive number, got -0.5");
  CHECK_THROWS_WITH(load("    - epochs: 0\n"), "translation.stages[2].epochs: expected at least 1 epoch, got 0");
  CHECK_THROWS_WITH(load("    - epoch: 5\n"),
                    "run.yaml:6: translation.stages[2].epoch: unknown key (did you mean 'epochs'?)");
  CHECK_THROWS_WITH(load("  dropout: 1.5\n"), "translation.dropout: expected a number in [0, 0.99], got 1.5");
  CHECK_THROWS_WITH(load("  loss: huber\n"), "translation.loss: expected l1 or l2, got \"huber\"");
  CHECK_THROWS_WITH(read_translation(ConfigNode::parse("translation:\n  loss: l1\n", "run.yaml").child("translation")),
                    "run.yaml: translation.latent_size: missing required key");
}

TEST_CASE("typed getters read every supported type", "[config]") {
  const ConfigNode n = ConfigNode::parse(R"(
d: [1e-3, .5, -2, +3, 7.25, .inf, -.inf, 1E2]
i: [42, +7, -3, 1e3, 3.0, 2147483647, -2147483648]
big: 9223372036854775807
f: 0.1
b: [true, false]
s: hello world
quoted: "12"
nested: [[1, 2], [3]]
empty: []
)",
                                         "t.yaml");
  const auto d = n.child("d").as<std::vector<double>>();
  CHECK(d == std::vector<double>{1e-3, 0.5, -2, 3, 7.25, INFINITY, -INFINITY, 100});
  CHECK(n.child("i").as<std::vector<int>>() == std::vector<int>{42, 7, -3, 1000, 3, 2147483647, -2147483647 - 1});
  CHECK(n.child("big").as<int64_t>() == INT64_MAX);
  CHECK(n.child("f").as<float>() == 0.1f);
  CHECK(n.child("b").as<std::vector<bool>>() == std::vector<bool>{true, false});
  CHECK(n.child("s").as<std::string>() == "hello world");
  CHECK(n.child("quoted").as<int>() == 12);
  CHECK(n.child("quoted").as<std::string>() == "12");
  CHECK(n.child("i").at(0).as<std::string>() == "42");
  CHECK(n.child("nested").as<std::vector<std::vector<int>>>() == std::vector<std::vector<int>>{{1, 2}, {3}});
  CHECK(n.child("empty").as<std::vector<double>>().empty());
  CHECK(std::isnan(ConfigNode::parse("x: .nan", "t.yaml").child("x").as<double>()));
}

TEST_CASE("wrong types and out-of-range values are reported with line and key path", "[config]") {
  struct Case {
    const char* yaml;
    std::string (*read)(const ConfigNode&);
    const char* message;
  };
  auto as_double = [](const ConfigNode& n) { return std::to_string(n.child("v").as<double>()); };
  auto as_float = [](const ConfigNode& n) { return std::to_string(n.child("v").as<float>()); };
  auto as_int = [](const ConfigNode& n) { return std::to_string(n.child("v").as<int>()); };
  auto as_int64 = [](const ConfigNode& n) { return std::to_string(n.child("v").as<int64_t>()); };
  auto as_bool = [](const ConfigNode& n) { return std::to_string(n.child("v").as<bool>()); };
  auto as_string = [](const ConfigNode& n) { return n.child("v").as<std::string>(); };
  auto as_doubles = [](const ConfigNode& n) { return std::to_string(n.child("v").as<std::vector<double>>().size()); };
  const Case cases[] = {
      {"v: fast", as_double, "t.yaml:1: v: expected a number, got \"fast\""},
      {"v: inf", as_double, "t.yaml:1: v: expected a number, got \"inf\""},
      {"v: 0x10", as_double, "t.yaml:1: v: expected a number, got \"0x10\""},
      {"v: \"\"", as_double, "t.yaml:1: v: expected a number, got \"\""},
      {"v:", as_double, "t.yaml:1: v: expected a number, got nothing"},
      {"v: [1]", as_double, "t.yaml:1: v: expected a number, got a list"},
      {"v: {a: 1}", as_double, "t.yaml:1: v: expected a number, got a map"},
      {"v: 1e999", as_double, "t.yaml:1: v: expected a number within the range of a double, got 1e999"},
      {"v: 1e39", as_float,
       "t.yaml:1: v: expected a number between -3.4028234663852886e+38 and 3.4028234663852886e+38, got 1e39"},
      {"v: 2.5", as_int, "t.yaml:1: v: expected an integer, got 2.5"},
      {"v: ten", as_int, "t.yaml:1: v: expected an integer, got \"ten\""},
      {"v: .nan", as_int, "t.yaml:1: v: expected an integer, got .nan"},
      {"v: 3000000000", as_int, "t.yaml:1: v: expected an integer between -2147483648 and 2147483647, got 3000000000"},
      {"v: -2147483649", as_int,
       "t.yaml:1: v: expected an integer between -2147483648 and 2147483647, got -2147483649"},
      {"v: 99999999999999999999", as_int64,
       "t.yaml:1: v: expected an integer between -9223372036854775808 and 9223372036854775807, got "
       "99999999999999999999"},
      {"v: 1e30", as_int64,
       "t.yaml:1: v: expected an integer between -9223372036854775808 and 9223372036854775807, got 1e30"},
      {"v: yes", as_bool, "t.yaml:1: v: expected true or false, got \"yes\""},
      {"v: 1", as_bool, "t.yaml:1: v: expected true or false, got 1"},
      {"v: True", as_bool, "t.yaml:1: v: expected true or false, got \"True\""},
      {"v: {a: 1}", as_string, "t.yaml:1: v: expected a string, got a map"},
      {"v: ~", as_string, "t.yaml:1: v: expected a string, got nothing"},
      {"v: 3", as_doubles, "t.yaml:1: v: expected a list, got 3"},
      {"\n\nv: [1, 2,\n    oops]", as_doubles, "t.yaml:4: v[2]: expected a number, got \"oops\""},
  };
  for (const Case& c : cases) {
    INFO(c.yaml);
    CHECK_THROWS_WITH(c.read(ConfigNode::parse(c.yaml, "t.yaml")), c.message);
  }
}

TEST_CASE("an error keeps where and what apart", "[config]") {
  try {
    ConfigNode::parse("a:\n  b: x\n", "t.yaml").child("a").child("b").as<double>();
    FAIL("no exception");
  } catch (const Error& e) {
    CHECK(e.where() == "t.yaml:2: a.b");
    CHECK(e.detail() == "expected a number, got \"x\"");
  }
}

TEST_CASE("get() leaves the default when the key is absent and reads it when present", "[config]") {
  const ConfigNode n = ConfigNode::parse("a: 3\n", "t.yaml");
  int a = 1, b = 2;
  n.get("a", a);
  n.get("b", b);
  CHECK(a == 3);
  CHECK(b == 2);
  CHECK_THROWS_WITH(n.get_required("b", b), "t.yaml: b: missing required key");
  CHECK_THROWS_WITH(n.child("nested").child("x"), "t.yaml: nested: missing required key");
}

TEST_CASE("an empty document or an empty section reads as an empty map", "[config]") {
  for (const char* text : {"", "# only a comment\n"}) {
    const ConfigNode root = ConfigNode::parse(text, "t.yaml");
    CHECK(root.is_null());
    CHECK_FALSE(root.has("anything"));
    CHECK(root.size() == 0);
    CHECK_NOTHROW(root.reject_unknown_keys({"a"}));
  }
  const ConfigNode section = ConfigNode::parse("model:\n", "t.yaml").child("model");
  int latent = 25;
  section.get("latent_size", latent);
  CHECK(latent == 25);
}

TEST_CASE("node shape queries", "[config]") {
  const ConfigNode n = ConfigNode::parse("m: {a: 1, b: 2}\nl: [1, 2, 3]\ns: x\n", "t.yaml");
  CHECK(n.is_map());
  CHECK(n.child("m").is_map());
  CHECK(n.child("m").size() == 2);
  CHECK(n.child("l").is_sequence());
  CHECK(n.child("l").size() == 3);
  CHECK_FALSE(n.child("s").is_null());
  CHECK(n.path().empty());
  CHECK(n.file() == "t.yaml");
  CHECK(n.child("l").at(1).path() == "l[1]");
  CHECK(ConfigNode::parse("[[1], [2]]", "t.yaml").at(1).at(0).path() == "[1][0]");
}

TEST_CASE("using a node as the wrong shape is reported", "[config]") {
  const ConfigNode n = ConfigNode::parse("m: {a: 1}\nl: [1, 2]\ns: x\n", "t.yaml");
  CHECK_THROWS_WITH(n.child("s").child("a"), "t.yaml:3: s: expected a map of keys, got \"x\"");
  CHECK_THROWS_WITH(n.child("l").has("a"), "t.yaml:2: l: expected a map of keys, got a list");
  CHECK_THROWS_WITH(n.child("m").at(0), "t.yaml:1: m: expected a list, got a map");
  CHECK_THROWS_WITH(n.child("l").at(2), "t.yaml:2: l: expected at least 3 items, got 2");
  CHECK_THROWS_WITH(n.child("s").size(), "t.yaml:3: s: expected a list or a map, got \"x\"");
  CHECK_THROWS_WITH(n.child("s").reject_unknown_keys({"a"}), "t.yaml:3: s: expected a map of keys, got \"x\"");
  CHECK_THROWS_WITH(n.child("m").fail("needs at least two entries"), "t.yaml:1: m: needs at least two entries");
}

TEST_CASE("unknown keys are rejected with the closest known key suggested", "[config]") {
  const std::string text = "model:\n  latent_size: 25\n  laten_size: 30\n";
  const ConfigNode model = ConfigNode::parse(text, "config.yaml").child("model");
  CHECK_THROWS_WITH(model.reject_unknown_keys({"latent_size", "layers"}),
                    "config.yaml:3: model.laten_size: unknown key (did you mean 'latent_size'?)");
  // Case is ignored when looking for the near miss.
  CHECK_THROWS_WITH(ConfigNode::parse("Latent_Size: 1", "c.yaml").reject_unknown_keys({"latent_size"}),
                    "c.yaml:1: Latent_Size: unknown key (did you mean 'latent_size'?)");
  // No near miss: list what the section takes instead of guessing.
  CHECK_THROWS_WITH(ConfigNode::parse("colour: red", "c.yaml").reject_unknown_keys({"latent_size", "layers"}),
                    "c.yaml:1: colour: unknown key (known keys: latent_size, layers)");
  CHECK_THROWS_WITH(ConfigNode::parse("a: 1", "c.yaml").reject_unknown_keys(std::vector<std::string>{}),
                    "c.yaml:1: a: unknown key (this section takes no keys)");
  CHECK_NOTHROW(ConfigNode::parse("a: 1\nb: 2", "c.yaml").reject_unknown_keys(std::vector<std::string>{"a", "b"}));
}

TEST_CASE("YAML syntax errors and duplicate keys name the file, line and column", "[config]") {
  try {
    ConfigNode::parse("a: 1\nb: [1, 2\nc: 3\n", "bad.yaml");
    FAIL("no exception");
  } catch (const Error& e) {
    INFO(e.what());
    CHECK_THAT(e.where(), Catch::Matchers::Matches(R"(bad\.yaml:\d+:\d+)"));
    CHECK_THAT(e.detail(), Catch::Matchers::StartsWith("invalid YAML: "));
  }
  CHECK_THROWS_WITH(ConfigNode::parse("a: 1\nb:\n  x: [\n", "bad.yaml"),
                    Catch::Matchers::StartsWith("bad.yaml:") && Catch::Matchers::Contains("invalid YAML"));
  CHECK_THROWS_WITH(ConfigNode::parse("model:\n  lr: 1\n  depth: 3\n  lr: 2\n", "dup.yaml"),
                    "dup.yaml:4: model.lr: duplicate key (first given on line 2)");
  CHECK_THROWS_WITH(ConfigNode::parse("stages:\n  - {a: 1, a: 2}\n", "dup.yaml"),
                    "dup.yaml:2: stages[0].a: duplicate key (first given on line 2)");
  CHECK_THROWS_WITH(ConfigNode::parse("? [1, 2]\n: x\n", "key.yaml"),
                    "key.yaml:1: keys must be plain names, not lists or maps");
}

TEST_CASE("aliases are checked once: cycles and billions of alias paths parse at once", "[config]") {
  // Nine levels of ten aliases each: 10^9 paths through the document, 10 lists.
  std::string laughs = "l0: &l0 [x, x, x, x, x, x, x, x, x, x]\n";
  for (int level = 1; level < 10; ++level) {
    laughs += "l" + std::to_string(level) + ": &l" + std::to_string(level) + " [";
    for (int k = 0; k < 10; ++k) laughs += (k ? ", *l" : "*l") + std::to_string(level - 1);
    laughs += "]\n";
  }
  const ConfigNode root = ConfigNode::parse(laughs, "laughs.yaml");
  CHECK(root.child("l9").size() == 10);
  CHECK_THROWS_WITH(root.child("l9").as<std::vector<double>>(),
                    Catch::Contains("l9[0]") && Catch::Contains("expected a number"));
  // An alias inside its own anchor, where yaml-cpp accepts it, must not recurse forever.
  try {
    const ConfigNode cycle = ConfigNode::parse("a: &a [1, *a]\n", "cycle.yaml");
    CHECK(cycle.child("a").size() == 2);
  } catch (const Error& e) {
    CHECK_THAT(e.what(), Catch::StartsWith("cycle.yaml"));
  }
  // A duplicate key inside an aliased map is still found.
  CHECK_THROWS_WITH(ConfigNode::parse("m: &m {a: 1, a: 2}\nn: *m\n", "dup.yaml"),
                    Catch::Contains("dup.yaml:1: m.a: duplicate key"));
}

TEST_CASE("load_file reads a file and names it in every error", "[config]") {
  const auto dir = scratch_dir("config_load_file");
  const std::string good = (dir / "good.yaml").string();
  std::ofstream(good) << "translation:\n  latent_size: 16\n  stages:\n    - lr: 2e-3\n";
  const ConfigNode root = ConfigNode::load_file(good);
  CHECK(root.file() == good);
  CHECK(read_translation(root.child("translation")).latent_size == 16);

  const std::string bad_value = (dir / "bad_value.yaml").string();
  std::ofstream(bad_value) << "translation:\n  latent_size: 16\n  stages:\n    - lr: fast\n";
  CHECK_THROWS_WITH(read_translation(ConfigNode::load_file(bad_value).child("translation")),
                    bad_value + ":4: translation.stages[0].lr: expected a number, got \"fast\"");

  const std::string bad_syntax = (dir / "bad_syntax.yaml").string();
  std::ofstream(bad_syntax) << "a: 1\nb: [\n";
  CHECK_THROWS_WITH(ConfigNode::load_file(bad_syntax),
                    Catch::Matchers::StartsWith(bad_syntax + ":") && Catch::Matchers::Contains("invalid YAML"));

  const std::string missing = (dir / "missing.yaml").string();
  CHECK_THROWS_WITH(ConfigNode::load_file(missing), missing + ": cannot read config file: No such file or directory");
  CHECK_THROWS_WITH(ConfigNode::load_file(dir.string()), dir.string() + ": is a folder, not a config file");
}

using retarget::test::error_of;

TEST_CASE("configs over 1 MiB and nesting too deep are refused before any work, saying so", "[config]") {
  const auto dir = scratch_dir("config_limits");
  const std::string big = (dir / "big.yaml").string();
  {
    std::ofstream out(big);
    out << "task: vae\nnotes: [";
    for (int i = 0; i < 200000; ++i) out << "1234567, ";
    out << "0]\n";
  }
  const auto bytes = std::filesystem::file_size(big);
  CHECK(error_of([&] { ConfigNode::load_file(big); }) ==
        big + ": " + std::to_string(bytes) + " bytes; a config is at most 1048576 bytes (is this a config file?)");
  CHECK_THAT(error_of([&] { ConfigNode::parse(std::string(ConfigNode::kMaxBytes + 1, '#'), "t.yaml"); }),
             Catch::StartsWith("t.yaml: 1048577 bytes of YAML; a config is at most 1048576 bytes"));
  // Flow and block nesting past yaml-cpp's depth guard: a clear message with the place.
  const std::string flow = "a: " + std::string(5000, '[') + std::string(5000, ']') + "\n";
  CHECK_THAT(error_of([&] { ConfigNode::parse(flow, "deep.yaml"); }),
             Catch::Matches(R"(deep\.yaml:1:\d+: invalid YAML: nested too deeply for the YAML reader .*)"));
  CHECK(error_of([&] { ConfigNode::parse(std::string("a: 1\nb: \x89PNG\0\n", 14), "bin.yaml"); }) ==
        "bin.yaml: line 2, column 4: byte 0x89 is not text; a config is YAML text (is this a binary file?)");
  std::string block;
  for (int i = 0; i < 1000; ++i) block += std::string(static_cast<size_t>(i), ' ') + "k" + std::to_string(i) + ":\n";
  CHECK_THAT(error_of([&] { ConfigNode::parse(block + std::string(1000, ' ') + "x: 1\n", "deep.yaml"); }),
             Catch::Contains("nested too deeply for the YAML reader"));
}

TEST_CASE("values given with --set are blamed on the --set, not on a line of the file", "[config]") {
  ConfigNode root = ConfigNode::parse("model:\n  latent: 16\n  channels: [9, 8]\ntraining: {epochs: 3}\n", "c.yaml");
  root.apply_override("model.latent=fast");
  root.apply_override("model.channels=[9, x]");
  root.apply_override("training.bogus=1");
  CHECK(error_of([&] { root.child("model").child("latent").as<int>(); }) ==
        "--set model.latent=fast: model.latent: expected an integer, got \"fast\"");
  CHECK(error_of([&] { root.child("model").child("channels").as<std::vector<int>>(); }) ==
        "--set model.channels=[9, x]: model.channels[1]: expected an integer, got \"x\"");
  CHECK_THAT(error_of([&] { root.child("training").reject_unknown_keys({"epochs"}); }),
             Catch::StartsWith("--set training.bogus=1: training.bogus: unknown key"));
  CHECK(root.child("training").child("epochs").as<int>() == 3);  // the file's own values read as before
  ConfigNode file = ConfigNode::parse("model:\n  latent: 16\n  width: fast\n", "c.yaml");
  file.apply_override("model.latent=4");
  CHECK(error_of([&] { file.child("model").child("width").as<int>(); }) ==
        "c.yaml:3: model.width: expected an integer, got \"fast\"");
}

TEST_CASE("override_string sets a value as it is, and a later override is blamed for what it replaced", "[config]") {
  ConfigNode root = ConfigNode::parse("output: a\nmodel: {x: 1, y: 2}\n", "c.yaml");
  root.override_string("output", "runs/[x]: #1", "--out runs/[x]: #1");
  CHECK(root.child("output").as<std::string>() == "runs/[x]: #1");  // not read as YAML
  CHECK(root.source("output") == "--out runs/[x]: #1");
  CHECK(error_of([&] { root.child("output").as<int>(); }) ==
        "--out runs/[x]: #1: output: expected an integer, got \"runs/[x]: #1\"");
  CHECK(error_of([&] { root.override_string("output.x", "v", "--out v"); }) ==
        "--out v: 'output' is not a map of keys");
  root.override_string("run.folder", "r", "--run r");  // missing maps are made, as with --set
  CHECK(root.child("run").child("folder").as<std::string>() == "r");
  CHECK(root.source("model.y") == "c.yaml");
  // A --set of a whole map replaces earlier --set values inside it, and takes the blame for them.
  root.apply_override("model.x=fast");
  root.apply_override("model={x: slow}");
  CHECK(error_of([&] { root.child("model").child("x").as<int>(); }) ==
        "--set model={x: slow}: model.x: expected an integer, got \"slow\"");
  root.apply_override("model.x=quick");
  CHECK(root.source("model.x") == "--set model.x=quick");
}

TEST_CASE("validate() helpers name the key path", "[config]") {
  CHECK_NOTHROW(require_positive(0.1, "a.lr"));
  CHECK_THROWS_WITH(require_positive(0, "a.lr"), "a.lr: expected a positive number, got 0");
  CHECK_THROWS_WITH(require_positive(NAN, "a.lr"), "a.lr: expected a positive number, got nan");
  CHECK_NOTHROW(require_non_negative(0, "a.decay"));
  CHECK_THROWS_WITH(require_non_negative(-1, "a.decay"), "a.decay: expected a number >= 0, got -1");
  CHECK_NOTHROW(require_in_range(1, 0, 1, "a.p"));
  CHECK_THROWS_WITH(require_in_range(1.25, 0, 1, "a.p"), "a.p: expected a number in [0, 1], got 1.25");
  CHECK_NOTHROW(require(true, "a", "unused"));
  CHECK_THROWS_WITH(require(false, "a.mode", "expected fast or exact"), "a.mode: expected fast or exact");
  CHECK(key_path("", "lr") == "lr");
  CHECK(key_path("a.stages[1]", "lr") == "a.stages[1].lr");
}

}  // namespace retarget
