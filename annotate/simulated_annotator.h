// A simulated annotator for the tournaments: it prefers the candidate whose score (lower = more
// alike: correspond/perceived_scores.h gives each annotator's own, in mm over the face's regions)
// is smaller, through a model of a person's judgement: Gaussian perception noise that grows with
// how different the faces are (Weber) and with fatigue, a draw when the two look alike, a draw
// rate for hard comparisons and lapses (a random answer). It lets the whole pipeline run without
// people, and makes the store's behaviour testable against a known best candidate.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "annotate/annotation_store.h"
#include "core/random.h"

namespace retarget {

struct SimulatedAnnotatorOptions {
  double noise = 0.0;              // stddev of the Gaussian noise added to each score per comparison, score units; >= 0
  double weber = 0.0;              // plus this fraction of the two scores' mean (perception is relative); >= 0
  double draw_margin = 0.0;        // draw when the noisy scores differ by at most this, score units; >= 0
  double draw_rate = 0.0;          // probability of answering draw, in [0, 1]
  double lapse_rate = 0.0;         // probability of a random left/right answer (inattention), in [0, 1]
  double fatigue = 0.0;            // the noise grows by this fraction per 1,000 answers of the annotator; >= 0
  uint64_t seed = 1;               // same seed and the same comparisons in the same order -> same answers
  int annotators = 1;              // run_simulated_annotation: simulated annotators taking turns; >= 1
  std::string name = "simulated";  // their names: `name` for one, `name`-1 .. `name`-N for several
  double lease_seconds = 60;       // lease asked for each comparison; > 0

  // Throws retarget::Error naming `key_path`.<field> for a value out of range.
  void validate(const std::string& key_path = "simulated_annotator") const;
};

// Per group label (the human expression), the score of each candidate sample id; lower means
// the avatar sample looks more like the human expression.
using CandidateScores = std::map<std::string, std::map<int64_t, double>>;

class SimulatedAnnotator {
 public:
  // Throws retarget::Error if options are invalid or a score is not finite.
  SimulatedAnnotator(CandidateScores scores, const SimulatedAnnotatorOptions& options);

  // Draw with probability draw_rate; a random side with probability lapse_rate; otherwise the
  // side whose score plus N(0, sigma^2) is lower, sigma = (noise + weber * mean score) *
  // (1 + fatigue * answers / 1000), and a draw when the noisy scores differ by at most
  // draw_margin (or tie exactly). Throws retarget::Error naming the group and sample when a
  // score is missing.
  Answer judge(const Assignment& assignment);

 private:
  double score(const std::string& label, int64_t sample) const;

  CandidateScores scores_;
  SimulatedAnnotatorOptions options_;
  Random random_;
  int64_t answers_ = 0;  // judged so far (fatigue)
};

struct SimulationCounts {
  int answers = 0;        // calls to answer(), draws included
  int decided = 0;        // left/right answers
  int draws = 0;          // draw answers (requeued or settled by the tie-break)
  int tie_breaks = 0;     // comparisons settled by the tie-break
  bool finished = false;  // every group in the store has a champion afterwards

  SimulationCounts& operator+=(const SimulationCounts& other);
};

// One annotator's loop: asks for a comparison, answers it, until none is available to it.
SimulationCounts annotate_until_idle(AnnotationStore& store, const std::string& annotator, SimulatedAnnotator& judge,
                                     double lease_seconds);

// Checks that every group in the store has a score for each of its candidates, registers
// options.annotators simulated annotators and lets them take turns until no comparison is left
// for any of them; with no other annotator at work that finishes every tournament. Throws
// retarget::Error naming the group and sample of a missing score before answering anything.
SimulationCounts run_simulated_annotation(AnnotationStore& store, const CandidateScores& scores,
                                          const SimulatedAnnotatorOptions& options = {});

// The same with one score table per annotator (each judges with its own reading of the avatar):
// scores.size() must equal options.annotators; annotator i's answers are seeded with
// mix_seed(options.seed, i). max_answers > 0 stops after that many answers in all (the
// annotation budget; tournaments left unfinished keep the champions they have so far).
SimulationCounts run_simulated_annotation(AnnotationStore& store, const std::vector<CandidateScores>& scores,
                                          const SimulatedAnnotatorOptions& options, int64_t max_answers = 0);

}  // namespace retarget
