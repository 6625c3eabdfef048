#include "annotate/simulated_annotator.h"

#include <fmt/format.h>

#include <cmath>
#include <functional>
#include <utility>
#include <vector>

#include "core/config.h"
#include "core/error.h"
#include "core/random.h"

namespace retarget {

void SimulatedAnnotatorOptions::validate(const std::string& key_path) const {
  require(std::isfinite(noise) && noise >= 0, key_path + ".noise",
          fmt::format("expected a number >= 0 (score units), got {}", noise));
  require(std::isfinite(draw_rate) && draw_rate >= 0 && draw_rate <= 1, key_path + ".draw_rate",
          fmt::format("expected a probability in [0, 1], got {}", draw_rate));
  require(std::isfinite(weber) && weber >= 0, key_path + ".weber",
          fmt::format("expected a fraction >= 0, got {}", weber));
  require(std::isfinite(draw_margin) && draw_margin >= 0, key_path + ".draw_margin",
          fmt::format("expected a number >= 0 (score units), got {}", draw_margin));
  require(std::isfinite(lapse_rate) && lapse_rate >= 0 && lapse_rate <= 1, key_path + ".lapse_rate",
          fmt::format("expected a probability in [0, 1], got {}", lapse_rate));
  require(std::isfinite(fatigue) && fatigue >= 0, key_path + ".fatigue",
          fmt::format("expected a number >= 0 (noise growth per 1,000 answers), got {}", fatigue));
  require(annotators >= 1, key_path + ".annotators", fmt::format("expected at least 1, got {}", annotators));
  require(!name.empty(), key_path + ".name", "expected a non-empty annotator name");
  require(std::isfinite(lease_seconds) && lease_seconds > 0, key_path + ".lease_seconds",
          fmt::format("expected a positive number of seconds, got {}", lease_seconds));
}

SimulationCounts& SimulationCounts::operator+=(const SimulationCounts& other) {
  answers += other.answers;
  decided += other.decided;
  draws += other.draws;
  tie_breaks += other.tie_breaks;
  return *this;
}

SimulatedAnnotator::SimulatedAnnotator(CandidateScores scores, const SimulatedAnnotatorOptions& options)
    : scores_(std::move(scores)), options_(options), random_(options.seed) {
  options_.validate();
  for (const auto& [label, samples] : scores_) {
    for (const auto& [sample, value] : samples) {
      if (!std::isfinite(value)) {
        throw Error("simulated annotator",
                    fmt::format("group '{}': the score of sample {} is {}", label, sample, value));
      }
    }
  }
}

double SimulatedAnnotator::score(const std::string& label, int64_t sample) const {
  const auto group = scores_.find(label);
  if (group == scores_.end()) throw Error("simulated annotator", fmt::format("no scores for group '{}'", label));
  const auto value = group->second.find(sample);
  if (value == group->second.end()) {
    throw Error("simulated annotator", fmt::format("group '{}': no score for sample {}", label, sample));
  }
  return value->second;
}

Answer SimulatedAnnotator::judge(const Assignment& a) {
  double left = score(a.label, a.left), right = score(a.label, a.right);
  const double tiredness = 1 + options_.fatigue * static_cast<double>(answers_++) / 1000.0;
  if (options_.draw_rate > 0 && random_.unit() <= options_.draw_rate) return Answer::draw;
  if (options_.lapse_rate > 0 && random_.unit() <= options_.lapse_rate)
    return random_.below(2) == 0 ? Answer::left : Answer::right;
  const double sigma = (options_.noise + options_.weber * 0.5 * (std::abs(left) + std::abs(right))) * tiredness;
  if (sigma > 0) {
    left += sigma * random_.normal();
    right += sigma * random_.normal();
  }
  if (std::abs(left - right) <= options_.draw_margin) return Answer::draw;
  return left < right ? Answer::left : Answer::right;
}

namespace {

void answer_one(AnnotationStore& store, const std::string& annotator, SimulatedAnnotator& judge,
                const Assignment& assignment, SimulationCounts& counts) {
  const Answer answer = judge.judge(assignment);
  const AnswerResult result = store.answer(assignment.comparison, annotator, answer);
  ++counts.answers;
  if (answer == Answer::draw) {
    ++counts.draws;
  } else {
    ++counts.decided;
  }
  if (result.status == AnswerStatus::tie_break) ++counts.tie_breaks;
}

}  // namespace

SimulationCounts annotate_until_idle(AnnotationStore& store, const std::string& annotator, SimulatedAnnotator& judge,
                                     double lease_seconds) {
  SimulationCounts counts;
  while (std::optional<Assignment> a = store.next_comparison(annotator, lease_seconds)) {
    answer_one(store, annotator, judge, *a, counts);
  }
  return counts;
}

namespace {

void check_scores(AnnotationStore& store, const CandidateScores& scores) {
  for (const GroupInfo& g : store.groups()) {
    const auto group = scores.find(g.label);
    if (group == scores.end()) {
      throw Error("simulated annotator",
                  fmt::format("no scores for group '{}' (group {} of {})", g.label, g.id, store.path()));
    }
    for (int64_t sample : g.candidates) {
      if (!group->second.count(sample)) {
        throw Error("simulated annotator",
                    fmt::format("group '{}': no score for candidate sample {}", g.label, sample));
      }
    }
  }
}

std::vector<std::string> annotator_names(const SimulatedAnnotatorOptions& options) {
  std::vector<std::string> names;
  for (int i = 1; i <= options.annotators; ++i)
    names.push_back(options.annotators == 1 ? options.name : fmt::format("{}-{}", options.name, i));
  return names;
}

// The annotators take turns asking for a comparison and answering it with judge_of(their index)
// until none is left for any of them, or max_answers (> 0) answers are given.
SimulationCounts take_turns(AnnotationStore& store, const std::vector<std::string>& names,
                            const std::function<SimulatedAnnotator&(size_t)>& judge_of, double lease_seconds,
                            int64_t max_answers) {
  SimulationCounts counts;
  const auto spent = [&] { return max_answers > 0 && counts.answers >= max_answers; };
  for (bool any = true; any && !spent();) {
    any = false;
    for (size_t i = 0; i < names.size() && !spent(); ++i) {
      std::optional<Assignment> a = store.next_comparison(names[i], lease_seconds);
      if (!a) continue;
      any = true;
      answer_one(store, names[i], judge_of(i), *a, counts);
    }
  }
  counts.finished = store.finished();
  return counts;
}

}  // namespace

SimulationCounts run_simulated_annotation(AnnotationStore& store, const CandidateScores& scores,
                                          const SimulatedAnnotatorOptions& options) {
  options.validate();
  check_scores(store, scores);
  const std::vector<std::string> names = annotator_names(options);
  // Register everyone first so a draw waits for the others instead of coming straight back.
  for (const std::string& name : names) store.register_annotator(name);

  SimulatedAnnotator judge(scores, options);  // one judge, one stream of answers, for everyone
  return take_turns(
      store, names, [&](size_t) -> SimulatedAnnotator& { return judge; }, options.lease_seconds, 0);
}

SimulationCounts run_simulated_annotation(AnnotationStore& store, const std::vector<CandidateScores>& scores,
                                          const SimulatedAnnotatorOptions& options, int64_t max_answers) {
  options.validate();
  if (static_cast<int>(scores.size()) != options.annotators)
    throw Error("simulated annotator",
                fmt::format("{} score tables for {} annotators", scores.size(), options.annotators));
  if (max_answers < 0) throw Error("simulated annotator", fmt::format("a budget of {} answers", max_answers));
  for (const CandidateScores& s : scores) check_scores(store, s);
  std::vector<std::string> names = annotator_names(options);
  for (const std::string& name : names) store.register_annotator(name);

  std::vector<SimulatedAnnotator> judges;
  for (int i = 0; i < options.annotators; ++i) {
    SimulatedAnnotatorOptions own = options;
    own.seed = mix_seed(options.seed, static_cast<uint64_t>(i));
    judges.emplace_back(scores[static_cast<size_t>(i)], own);
  }
  return take_turns(
      store, names, [&](size_t i) -> SimulatedAnnotator& { return judges[i]; }, options.lease_seconds, max_answers);
}

}  // namespace retarget
