#include "cli/belief_options.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <charconv>
#include <string>
#include <system_error>
#include <vector>

#include "core/error.h"

namespace retarget::cli {

namespace {

// "2,3.5" -> {2, 3.5}; "" -> {}. Throws retarget::Error naming `flag` and the item that is not a number.
std::vector<double> number_list(const std::string& text, const std::string& flag) {
  std::vector<double> values;
  size_t begin = 0;
  while (begin < text.size()) {
    const size_t end = std::min(text.find(',', begin), text.size());
    const std::string item = text.substr(begin, end - begin);
    double value = 0;
    const auto [last, error] = std::from_chars(item.data(), item.data() + item.size(), value);
    if (item.empty() || error != std::errc() || last != item.data() + item.size())
      throw Error(flag, fmt::format("expected numbers separated by commas, got '{}' in '{}'", item, text));
    values.push_back(value);
    begin = end + 1;
  }
  return values;
}

}  // namespace

void add_belief_options(cxxopts::Options& options, const BeliefSearchOptions& d) {
  const auto number = [](double v) { return cxxopts::value<double>()->default_value(fmt::format("{}", v)); };
  options.add_options("belief search")(
      "belief-prior-sd", "prior spread of each map entry, a fraction of its controller's range", number(d.prior_sd))(
      "belief-off-table", "prior spread of each map entry the prior leaves at 0, a fraction of --belief-prior-sd",
      number(d.off_table))("belief-weber", "assumed perception noise, a fraction of a judged distance",
                           number(d.weber))(
      "belief-reading-sd", "assumed spread of annotators' readings, a fraction of each range", number(d.reading_sd))(
      "belief-lapse", "assumed probability of a random answer", number(d.lapse))(
      "belief-step", "half the gap between a pair, in the belief's standard deviations", number(d.step))(
      "belief-sparsity", "the map's pull of each entry towards the prior's (Laplace, per range unit)",
      number(d.sparsity))("belief-passes",
                          "passes of expectation propagation over the answers before the map is read (0: one pass, "
                          "in the answers' order)",
                          cxxopts::value<int>()->default_value(std::to_string(d.refine_passes)))(
      "belief-annotator-sd",
      "the map's reading: each annotator's own reading of the map about the one they share, a fraction of each "
      "range (0: every answer pooled)",
      number(d.annotator_sd))(
      "belief-leave-one-out",
      "the map's reading: each entry moves from the prior's only as far as it does without any one annotator's "
      "answers (true/false)",
      cxxopts::value<bool>()->default_value(d.leave_one_out ? "true" : "false"))(
      "belief-jackknife",
      "the map's reading: each entry's move from the prior's shrinks by its jackknife spread over annotators, "
      "x max(0, 1 - z^2 var / move^2) (z: this value; 0: off)",
      number(d.jackknife_z))(
      "belief-jackknife-if-it-predicts",
      "the map's reading: the jackknifed map only if, made without each annotator in turn, it agrees with more "
      "of their answers than the pooled map does (true/false)",
      cxxopts::value<bool>()->default_value(d.jackknife_if_it_predicts ? "true" : "false"))(
      "belief-jackknife-also",
      "the map's reading, with --belief-jackknife-if-it-predicts: further strengths z tried, comma-separated; the "
      "reading (pooled, or jackknifed at any z) that agrees with the most held-out answers wins",
      cxxopts::value<std::string>()->default_value(fmt::format("{}", fmt::join(d.jackknife_alternatives, ","))));
}

BeliefSearchOptions belief_options(const cxxopts::ParseResult& args) {
  BeliefSearchOptions o;
  o.prior_sd = args["belief-prior-sd"].as<double>();
  o.off_table = args["belief-off-table"].as<double>();
  o.weber = args["belief-weber"].as<double>();
  o.reading_sd = args["belief-reading-sd"].as<double>();
  o.lapse = args["belief-lapse"].as<double>();
  o.step = args["belief-step"].as<double>();
  o.sparsity = args["belief-sparsity"].as<double>();
  o.refine_passes = args["belief-passes"].as<int>();
  o.annotator_sd = args["belief-annotator-sd"].as<double>();
  o.leave_one_out = args["belief-leave-one-out"].as<bool>();
  o.jackknife_z = args["belief-jackknife"].as<double>();
  o.jackknife_if_it_predicts = args["belief-jackknife-if-it-predicts"].as<bool>();
  o.jackknife_alternatives = number_list(args["belief-jackknife-also"].as<std::string>(), "--belief-jackknife-also");
  o.validate("--belief");
  return o;
}

}  // namespace retarget::cli
