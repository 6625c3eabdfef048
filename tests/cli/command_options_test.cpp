#include "cli/command_options.h"

#include <catch2/catch.hpp>
#include <cxxopts.hpp>
#include <functional>
#include <string>
#include <vector>

#include "cli/commands.h"
#include "run_command.h"

using namespace retarget;
using Catch::Contains;

namespace {

struct Parsed {
  bool ran = false;  // false: --help was given
  int count = 0;
  std::string printed;
};

// A command with one option in the default group and one in "more", parsed by parse_options.
Parsed parse_demo(std::vector<std::string> args, std::vector<std::string> groups = {}, bool own_help = false) {
  Parsed out;
  const auto command = [&](int argc, char** argv) {
    cxxopts::Options options("retarget demo", "A demo command.");
    options.add_options()("count", "how many", cxxopts::value<int>()->default_value("3"));
    if (own_help) options.add_options()("h,help", "show this help");
    options.add_options()("late", "added after the command's own -h");
    options.add_options("more")("extra", "an option of another group");
    const std::optional<cxxopts::ParseResult> parsed = cli::parse_options(options, argc, argv, groups);
    if (!parsed) return 0;
    out.ran = true;
    out.count = (*parsed)["count"].as<int>();
    return 0;
  };
  static std::function<int(int, char**)> current;
  current = command;
  const int code = test::run_command([](int argc, char** argv) { return current(argc, argv); }, "demo", std::move(args),
                                     &out.printed);
  REQUIRE(code == 0);
  return out;
}

}  // namespace

TEST_CASE("parse_options parses the command line and leaves stdout alone", "[cli]") {
  const Parsed p = parse_demo({"--count", "7"});
  CHECK(p.ran);
  CHECK(p.count == 7);
  CHECK(p.printed.empty());
}

TEST_CASE("parse_options prints the help for --help and -h, -h last in the default group", "[cli]") {
  for (const char* flag : {"--help", "-h"}) {
    const Parsed p = parse_demo({flag});
    CHECK_FALSE(p.ran);
    CHECK_THAT(p.printed, Contains("A demo command.") && Contains("--count") && Contains("--extra"));
    const size_t help = p.printed.find("-h, --help"), late = p.printed.find("--late");
    REQUIRE(help != std::string::npos);
    CHECK(late < help);
  }
}

TEST_CASE("parse_options keeps a command's own -h where the command placed it", "[cli]") {
  const Parsed p = parse_demo({"--help"}, {}, true);
  CHECK_FALSE(p.ran);
  const size_t help = p.printed.find("-h, --help"), late = p.printed.find("--late");
  REQUIRE(help != std::string::npos);
  CHECK(help < late);
  CHECK(p.printed.find("-h, --help", help + 1) == std::string::npos);
}

TEST_CASE("parse_options prints only the groups asked for", "[cli]") {
  const Parsed p = parse_demo({"--help"}, {""});
  CHECK_THAT(p.printed, Contains("--count"));
  CHECK(p.printed.find("--extra") == std::string::npos);
}

TEST_CASE("parse_options throws for an unknown option, as cxxopts does", "[cli]") {
  CHECK_THROWS_AS(parse_demo({"--no-such-option"}), cxxopts::exceptions::exception);
}

TEST_CASE("every command's --help prints its usage and exits 0", "[cli]") {
  struct Command {
    int (*run)(int, char**);
    const char* name;
    const char* usage;  // in its help
  };
  const Command commands[] = {
      {cli::render_command, "render", "retarget render"},
      {cli::synth_command, "synth", "retarget synth"},
      {cli::dataset_command, "dataset", "retarget dataset"},
      {cli::train_command, "train", "retarget train"},
      {cli::export_command, "export", "retarget export"},
      {cli::correspond_command, "correspond", "retarget correspond"},
      {cli::annotate_serve, "serve", "retarget annotate serve"},
      {cli::faces_command, "faces", "retarget faces"},
      {cli::eval_ladder, "ladder", "retarget eval ladder"},
      {cli::avatar_meaning, "meaning", "retarget avatar meaning"},
      {cli::avatar_landmarks, "landmarks", "retarget avatar landmarks"},
  };
  for (const Command& c : commands) {
    INFO(c.name);
    std::string printed;
    CHECK(test::run_command(c.run, c.name, {"--help"}, &printed) == 0);
    CHECK_THAT(printed, Contains(c.usage) && Contains("-h, --help"));
  }
}
