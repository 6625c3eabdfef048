#include "annotate/tournament.h"

#include <algorithm>
#include <catch2/catch.hpp>
#include <set>
#include <string>
#include <vector>

#include "core/error.h"

namespace retarget {
namespace {

// Plays a whole tournament with a consistent oracle: the lower score always wins. Returns the
// number of comparisons made.
int play(Tournament& t, const std::vector<double>& score) {
  int comparisons = 0;
  for (std::vector<Match> ready = t.ready(); !ready.empty(); ready = t.ready()) {
    for (const Match& m : ready) {
      t.decide(m.round, m.position, score[m.left] < score[m.right] ? m.left : m.right);
      ++comparisons;
    }
  }
  return comparisons;
}

std::vector<double> scrambled_scores(int count) {
  std::vector<double> s;
  for (int i = 0; i < count; ++i) s.push_back((i * 37 + 11) % 101);
  return s;
}

int argmin(const std::vector<double>& v) { return static_cast<int>(std::min_element(v.begin(), v.end()) - v.begin()); }

}  // namespace

TEST_CASE("16 candidates take 8 + 4 + 2 + 1 = 15 comparisons", "[tournament]") {
  Tournament t(16, 7);
  CHECK(t.round_count() == 4);
  CHECK(t.comparison_count() == 15);
  CHECK(t.ready().size() == 8);
  std::vector<int> per_round(5, 0);
  const std::vector<double> score = scrambled_scores(16);
  for (std::vector<Match> ready = t.ready(); !ready.empty(); ready = t.ready()) {
    for (const Match& m : ready) {
      ++per_round[m.round];
      t.decide(m.round, m.position, score[m.left] < score[m.right] ? m.left : m.right);
    }
  }
  CHECK(per_round == std::vector<int>{0, 8, 4, 2, 1});
  CHECK(t.decided_count() == 15);
  REQUIRE(t.finished());
}

TEST_CASE("the true best always wins under a consistent oracle, with and without byes", "[tournament]") {
  const int count = GENERATE(2, 3, 5, 11, 16, 17, 21, 32);
  for (uint64_t seed : {1u, 2u, 99u}) {
    Tournament t(count, seed);
    const std::vector<double> score = scrambled_scores(count);
    CHECK(play(t, score) == count - 1);
    REQUIRE(t.champion());
    CHECK(*t.champion() == argmin(score));
  }
}

TEST_CASE("byes: every candidate in one first-round slot, at most one bye per match", "[tournament]") {
  for (int count = 2; count <= 40; ++count) {
    Tournament t(count, 3);
    std::multiset<int> seen;
    int byes = 0;
    for (int p = 0; p < t.matches_in_round(1); ++p) {
      const Match m = t.match(1, p);
      REQUIRE(m.left != Match::kNone);  // never a match of two byes
      seen.insert(m.left);
      if (m.bye) {
        ++byes;
        CHECK(m.winner == m.left);  // a bye advances its candidate at once
      } else {
        seen.insert(m.right);
      }
    }
    CHECK(byes == t.bracket_size() - count);
    CHECK(seen.size() == static_cast<size_t>(count));
    CHECK(std::set<int>(seen.begin(), seen.end()).size() == static_cast<size_t>(count));
    CHECK(t.decided().empty());  // byes are not comparisons
  }
}

TEST_CASE("five candidates: one first-round comparison, the others start in round 2", "[tournament]") {
  Tournament t(5, 11);
  CHECK(t.bracket_size() == 8);
  const std::vector<Match> ready = t.ready();
  // Round 1 holds one real match; two byes meet at once in round 2 (matches fed by two byes).
  REQUIRE(ready.size() == 2);
  CHECK(ready[0].round == 1);
  CHECK(ready[1].round == 2);
  CHECK(play(t, scrambled_scores(5)) == 4);
}

TEST_CASE("the same seed gives the same bracket, another seed another one", "[tournament]") {
  CHECK(Tournament(16, 42).slots() == Tournament(16, 42).slots());
  CHECK(Tournament(16, 42).slots() != Tournament(16, 43).slots());
  CHECK(Tournament(11, 5).slots() == Tournament(11, 5).slots());
  // Fixed by mt19937_64 and our own Fisher-Yates (core/random.h): identical on every machine and library (checked
  // against an independent Python implementation of the engine and the shuffle).
  CHECK(Tournament(16, 1).slots() == std::vector<int>{13, 6, 5, 1, 10, 2, 7, 9, 11, 14, 3, 0, 15, 4, 12, 8});
  CHECK(Tournament(5, 1).slots() == std::vector<int>{1, 4, 0, -1, 2, -1, 3, -1});
}

TEST_CASE("decide and undo check the bracket", "[tournament]") {
  Tournament t(4, 1);
  const Match first = t.match(1, 0);
  CHECK_THROWS_WITH(t.decide(2, 0, first.left), Catch::Contains("not ready"));
  CHECK_THROWS_WITH(t.decide(1, 0, 77), Catch::Contains("candidate 77 is not in this match"));
  CHECK_THROWS_WITH(t.decide(3, 0, 0), Catch::Contains("round 3 does not exist"));
  CHECK_THROWS_WITH(t.decide(1, 2, 0), Catch::Contains("round 1 has no match 2"));
  t.decide(1, 0, first.left);
  CHECK_THROWS_WITH(t.decide(1, 0, first.left), Catch::Contains("already decided"));
  const Match second = t.match(1, 1);
  t.decide(1, 1, second.right);
  REQUIRE(t.match(2, 0).ready());
  CHECK(t.match(2, 0).left == first.left);
  CHECK(t.match(2, 0).right == second.right);
  t.decide(2, 0, second.right);
  CHECK(t.champion() == second.right);
  CHECK_THROWS_WITH(t.undo(1, 0), Catch::Contains("round 2 match 0, which its winner advanced to, is decided"));
  t.undo(2, 0);
  t.undo(1, 0);
  CHECK_FALSE(t.match(2, 0).ready());
  CHECK_THROWS_WITH(t.undo(1, 0), Catch::Contains("is not decided"));
  CHECK_THROWS_WITH(Tournament(1, 0), Catch::Contains("needs at least 2 candidates, got 1"));
  Tournament with_bye(3, 1);
  CHECK_THROWS_WITH(with_bye.decide(1, 1, with_bye.match(1, 1).left), Catch::Contains("is a bye"));
}

TEST_CASE("derive_triplets: transitive closure of a hand-worked 8-candidate tournament", "[tournament]") {
  // Round 1: 1>2, 3>4, 5>6, 7>8; round 2: 1>3, 5>7; final: 1>5.
  const std::vector<MatchResult> results = {{1, 2}, {3, 4}, {5, 6}, {7, 8}, {1, 3}, {5, 7}, {1, 5}};
  const std::vector<Ordering> all = derive_triplets(results);
  std::vector<std::pair<int64_t, int64_t>> direct, derived;
  for (const Ordering& o : all) (o.derived ? derived : direct).push_back({o.positive, o.negative});
  CHECK(direct == std::vector<std::pair<int64_t, int64_t>>{{1, 2}, {3, 4}, {5, 6}, {7, 8}, {1, 3}, {5, 7}, {1, 5}});
  // 1 beat 3 who beat 4; 1 beat 5 who beat 6 and 7, who beat 8; 5 beat 7 who beat 8.
  CHECK(derived == std::vector<std::pair<int64_t, int64_t>>{{1, 4}, {1, 6}, {1, 7}, {1, 8}, {5, 8}});
}

TEST_CASE("derive_triplets: a full 16-candidate tournament gives 17 derived triplets", "[tournament]") {
  Tournament t(16, 5);
  play(t, scrambled_scores(16));
  std::vector<MatchResult> results;
  for (const Match& m : t.decided()) results.push_back({m.winner, m.loser()});
  const std::vector<Ordering> all = derive_triplets(results);
  const auto derived = std::count_if(all.begin(), all.end(), [](const Ordering& o) { return o.derived; });
  // Closure: the champion is above 15, the finalist 7, the semi-finalists 3 each, the quarter-finalists
  // 1 each: 32 ordered pairs, 15 of them compared directly.
  CHECK(all.size() == 32);
  CHECK(derived == 17);
}

TEST_CASE("derive_triplets never contradicts a direct result and removes duplicates", "[tournament]") {
  // A cycle of direct results (people disagree): no derived pair, both directions stay direct.
  const std::vector<Ordering> cycle = derive_triplets({{1, 2}, {2, 3}, {3, 1}, {1, 2}, {4, 4}});
  CHECK(cycle.size() == 3);
  for (const Ordering& o : cycle) CHECK_FALSE(o.derived);

  // 1 > 2 > 3 > 4 plus a contradicting 4 > 2: 2, 3 and 4 form a cycle, only 1's pairs derive.
  const std::vector<Ordering> out = derive_triplets({{1, 2}, {2, 3}, {3, 4}, {4, 2}});
  std::set<std::pair<int64_t, int64_t>> pairs, direct;
  for (const Ordering& o : out) {
    CHECK(pairs.insert({o.positive, o.negative}).second);
    if (!o.derived) direct.insert({o.positive, o.negative});
  }
  for (const Ordering& o : out) {
    if (o.derived) CHECK_FALSE(direct.count({o.negative, o.positive}));
  }
  CHECK(pairs.count({1, 3}));
  CHECK(pairs.count({1, 4}));
  CHECK_FALSE(pairs.count({2, 4}));  // 2 > 3 > 4, but 4 > 2 was said directly
  CHECK_FALSE(pairs.count({3, 2}));
}

TEST_CASE("derive_triplets marks derived pairs that rest on a tie-break", "[tournament]") {
  // 1 > 2 by tie-break, 2 > 3 by a person: 1 > 3 rests on the tie-break.
  std::vector<Ordering> out = derive_triplets({{1, 2, true}, {2, 3, false}});
  REQUIRE(out.size() == 3);
  CHECK(out[0].tie_break);
  CHECK_FALSE(out[1].tie_break);
  CHECK(out[2].derived);
  CHECK(out[2].tie_break);
  // Another chain of people's choices (1 > 4 > 3) supports 1 > 3 without the tie-break.
  out = derive_triplets({{1, 2, true}, {2, 3, false}, {1, 4, false}, {4, 3, false}});
  for (const Ordering& o : out) {
    if (o.positive == 1 && o.negative == 3) CHECK_FALSE(o.tie_break);
  }
}

}  // namespace retarget
