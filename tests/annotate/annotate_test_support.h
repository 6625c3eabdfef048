// Helpers for the annotate tests: a scratch folder (tests/test_support.h would pull in geometry),
// a controllable clock, and groups whose true best candidate is known.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "annotate/annotation_store.h"
#include "annotate/simulated_annotator.h"

namespace retarget::test {

// A fresh, empty scratch folder below the build tree, unique per name.
inline std::filesystem::path scratch_dir(const std::string& name) {
  std::filesystem::path dir = std::filesystem::path(RETARGET_TEST_TMP) / "annotate" / name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

// A clock the test moves by hand; copies share the time.
struct ManualClock {
  std::shared_ptr<double> seconds = std::make_shared<double>(1000.0);
  void advance(double s) const { *seconds += s; }
  std::function<double()> function() const {
    auto t = seconds;
    return [t] { return *t; };
  }
};

// Candidates of a test group: sample ids base, base + 1, ...; candidate i's score (lower = more
// alike) is (37 i + 11) mod 101: distinct for up to 101 candidates (101 is prime) and scrambled,
// so the best one is not simply the first.
struct TestGroup {
  std::string label;
  std::vector<int64_t> samples;
  std::vector<double> scores;     // true dissimilarity, the oracle
  std::vector<double> distances;  // to y0: equal to the scores unless a test says otherwise

  int64_t best() const {
    size_t b = 0;
    for (size_t i = 1; i < scores.size(); ++i) {
      if (scores[i] < scores[b]) b = i;
    }
    return samples[b];
  }
  double score_of(int64_t sample) const {
    for (size_t i = 0; i < samples.size(); ++i) {
      if (samples[i] == sample) return scores[i];
    }
    return 1e300;
  }
};

inline TestGroup make_test_group(const std::string& label, int count, int64_t base = 100) {
  TestGroup g;
  g.label = label;
  for (int i = 0; i < count; ++i) {
    g.samples.push_back(base + i);
    g.scores.push_back(static_cast<double>((i * 37 + 11) % 101));
  }
  g.distances = g.scores;
  return g;
}

inline CandidateScores scores_of(const std::vector<TestGroup>& groups) {
  CandidateScores scores;
  for (const TestGroup& g : groups) {
    for (size_t i = 0; i < g.samples.size(); ++i) scores[g.label][g.samples[i]] = g.scores[i];
  }
  return scores;
}

// The consistent oracle: the candidate with the lower true score wins.
inline Answer oracle(const TestGroup& g, const Assignment& a) {
  return g.score_of(a.left) < g.score_of(a.right) ? Answer::left : Answer::right;
}

}  // namespace retarget::test
