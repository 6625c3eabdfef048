// The paper's tournament over one group of avatar candidates (pure logic, no I/O): candidates
// are paired at random, each comparison's winner advances, and the last one standing - the
// champion - is the avatar expression that looks most like the human reference. 16 candidates
// take 8 + 4 + 2 + 1 = 15 comparisons; any P >= 2 takes P - 1, with byes in the first round
// when P is not a power of two.
//
// The bracket has B = 2^ceil(log2 P) first-round slots. Round r (1-based) has B >> r matches;
// match (r, p) is fed by matches (r - 1, 2p) (left) and (r - 1, 2p + 1) (right). In round 1,
// B - P matches are byes: their one candidate advances without a comparison.
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

namespace retarget {

// Candidates are indices 0..P-1 into the group's candidate list.
struct Match {
  static constexpr int kNone = -1;

  int round = 0;       // 1..round_count()
  int position = 0;    // 0..matches_in_round(round) - 1
  int left = kNone;    // candidate index; kNone until the feeding match has a winner
  int right = kNone;   // candidate index; kNone until known, and for a bye
  int winner = kNone;  // candidate index once decided (a bye's winner is its one candidate)
  bool bye = false;    // a round-1 match with one candidate: no comparison needed

  bool decided() const { return winner != kNone; }
  // Both candidates known, not a bye, no winner yet: ready to be shown to an annotator.
  bool ready() const { return !bye && left != kNone && right != kNone && winner == kNone; }
  // The candidate that lost; kNone unless decided and not a bye.
  int loser() const { return decided() && !bye ? (winner == left ? right : left) : kNone; }
};

class Tournament {
 public:
  // A bracket for `candidate_count` (>= 2) candidates, paired by Random(seed).permutation
  // (core/random.h): the same seed gives the same bracket on every machine and standard
  // library. Throws retarget::Error for fewer than 2 candidates.
  Tournament(int candidate_count, uint64_t seed);

  int candidate_count() const { return candidate_count_; }
  uint64_t seed() const { return seed_; }
  int round_count() const { return round_count_; }
  int bracket_size() const { return 1 << round_count_; }
  int matches_in_round(int round) const { return bracket_size() >> round; }
  // Comparisons needed to find the champion: candidate_count() - 1.
  int comparison_count() const { return candidate_count_ - 1; }
  // The shuffled first-round slots, bracket_size() entries: slot 2p and 2p + 1 meet in match
  // (1, p); Match::kNone marks a bye. Byes sit in the last B - P first-round matches.
  const std::vector<int>& slots() const { return slots_; }

  // The match at (round, position), with whatever is known of it. Throws retarget::Error
  // ("tournament: round 5 does not exist (4 rounds)") for a position outside the bracket.
  Match match(int round, int position) const;
  // Every match that can be compared now, by round then position.
  std::vector<Match> ready() const;
  // Every decided comparison (byes excluded), by round then position.
  std::vector<Match> decided() const;
  int decided_count() const;

  // Records the winner (a candidate index, left or right) of a ready match. Throws
  // retarget::Error if the match is a bye, not ready, already decided, or `winner` is not one
  // of its two candidates.
  void decide(int round, int position, int winner);
  // Takes a decision back. Throws retarget::Error if the match is not decided or the match
  // its winner advanced to is already decided (that result depends on it).
  void undo(int round, int position);
  // The match that (round, position)'s winner advances to; nullopt for the final.
  std::optional<Match> next_match(int round, int position) const;

  // The overall winner once the final is decided.
  std::optional<int> champion() const;
  bool finished() const { return champion().has_value(); }

 private:
  void check(int round, int position) const;
  int& winner_at(int round, int position) { return winners_[static_cast<size_t>(offset(round) + position)]; }
  int winner_at(int round, int position) const { return winners_[static_cast<size_t>(offset(round) + position)]; }
  int offset(int round) const { return bracket_size() - (bracket_size() >> (round - 1)); }
  // Round 0 is the slots themselves.
  int entrant(int round, int position) const;

  int candidate_count_ = 0;
  uint64_t seed_ = 0;
  int round_count_ = 0;
  std::vector<int> slots_;
  std::vector<int> winners_;  // winners of rounds 1..R, round r at offset(r); kNone when open
};

// One decided comparison of a group: `winner` looked more like the human expression than
// `loser`. Ids are any candidate identifiers (indices or avatar sample ids).
struct MatchResult {
  int64_t winner = 0;
  int64_t loser = 0;
  bool tie_break = false;  // settled by the geometric tie-break after draws, not by a person
};

// An ordered pair for a triplet (anchor, positive, negative) of the same group.
struct Ordering {
  int64_t positive = 0;
  int64_t negative = 0;
  bool derived = false;    // inferred by transitivity, not compared directly
  bool tie_break = false;  // direct: settled by the tie-break; derived: every chain of results
                           // that implies it passes through a tie-break
};

// The direct results (in input order, duplicates removed) followed by their transitive closure
// within the group: a beat b and b beat c gives the derived (a, c), sorted by (positive,
// negative). Never derives a pair that was compared directly, or one whose reverse also
// follows (a cycle of contradictory results). Inputs with winner == loser are ignored.
std::vector<Ordering> derive_triplets(const std::vector<MatchResult>& decided);

}  // namespace retarget
