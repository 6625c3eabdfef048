#include "annotate/tournament.h"

#include <fmt/format.h>

#include <algorithm>
#include <map>
#include <set>
#include <utility>

#include "core/error.h"
#include "core/random.h"

namespace retarget {

Tournament::Tournament(int candidate_count, uint64_t seed) : candidate_count_(candidate_count), seed_(seed) {
  if (candidate_count < 2) {
    throw Error("tournament", fmt::format("needs at least 2 candidates, got {}", candidate_count));
  }
  if (candidate_count > (1 << 20)) {
    throw Error("tournament", fmt::format("at most {} candidates, got {}", 1 << 20, candidate_count));
  }
  while ((1 << round_count_) < candidate_count) ++round_count_;

  const std::vector<int64_t> order = Random(seed).permutation(candidate_count);

  // The first P - B/2 matches pair two candidates; the other B - P hold one candidate and a bye.
  const int size = bracket_size();
  const int real_matches = candidate_count - size / 2;
  slots_.assign(static_cast<size_t>(size), Match::kNone);
  size_t next = 0;
  for (int p = 0; p < size / 2; ++p) {
    slots_[static_cast<size_t>(2 * p)] = static_cast<int>(order[next++]);
    if (p < real_matches) slots_[static_cast<size_t>(2 * p + 1)] = static_cast<int>(order[next++]);
  }
  winners_.assign(static_cast<size_t>(size - 1), Match::kNone);
  for (int p = real_matches; p < size / 2; ++p) winner_at(1, p) = slots_[static_cast<size_t>(2 * p)];
}

void Tournament::check(int round, int position) const {
  if (round < 1 || round > round_count_) {
    throw Error("tournament", fmt::format("round {} does not exist ({} rounds for {} candidates)", round, round_count_,
                                          candidate_count_));
  }
  if (position < 0 || position >= matches_in_round(round)) {
    throw Error("tournament",
                fmt::format("round {} has no match {} (it has {})", round, position, matches_in_round(round)));
  }
}

int Tournament::entrant(int round, int position) const {
  return round == 0 ? slots_[static_cast<size_t>(position)] : winner_at(round, position);
}

Match Tournament::match(int round, int position) const {
  check(round, position);
  Match m;
  m.round = round;
  m.position = position;
  m.left = entrant(round - 1, 2 * position);
  m.right = entrant(round - 1, 2 * position + 1);
  m.bye = round == 1 && m.right == Match::kNone;
  m.winner = winner_at(round, position);
  return m;
}

std::vector<Match> Tournament::ready() const {
  std::vector<Match> out;
  for (int r = 1; r <= round_count_; ++r) {
    for (int p = 0; p < matches_in_round(r); ++p) {
      Match m = match(r, p);
      if (m.ready()) out.push_back(m);
    }
  }
  return out;
}

std::vector<Match> Tournament::decided() const {
  std::vector<Match> out;
  for (int r = 1; r <= round_count_; ++r) {
    for (int p = 0; p < matches_in_round(r); ++p) {
      Match m = match(r, p);
      if (m.decided() && !m.bye) out.push_back(m);
    }
  }
  return out;
}

int Tournament::decided_count() const { return static_cast<int>(decided().size()); }

void Tournament::decide(int round, int position, int winner) {
  const Match m = match(round, position);
  const std::string where = fmt::format("tournament: round {} match {}", round, position);
  if (m.bye) throw Error(where, "is a bye; its candidate advances without a comparison");
  if (m.decided()) throw Error(where, fmt::format("is already decided (candidate {} won)", m.winner));
  if (!m.ready()) throw Error(where, "is not ready: a match feeding it is still open");
  if (winner != m.left && winner != m.right) {
    throw Error(where, fmt::format("candidate {} is not in this match ({} vs {})", winner, m.left, m.right));
  }
  winner_at(round, position) = winner;
}

std::optional<Match> Tournament::next_match(int round, int position) const {
  check(round, position);
  if (round == round_count_) return std::nullopt;
  return match(round + 1, position / 2);
}

void Tournament::undo(int round, int position) {
  const Match m = match(round, position);
  const std::string where = fmt::format("tournament: round {} match {}", round, position);
  if (m.bye) throw Error(where, "is a bye and cannot be undone");
  if (!m.decided()) throw Error(where, "is not decided");
  if (const std::optional<Match> next = next_match(round, position); next && next->decided()) {
    throw Error(where, fmt::format("cannot be undone: round {} match {}, which its winner advanced to, is decided",
                                   next->round, next->position));
  }
  winner_at(round, position) = Match::kNone;
}

std::optional<int> Tournament::champion() const {
  const int winner = winner_at(round_count_, 0);
  if (winner == Match::kNone) return std::nullopt;
  return winner;
}

std::vector<Ordering> derive_triplets(const std::vector<MatchResult>& decided) {
  std::vector<Ordering> out;
  std::set<std::pair<int64_t, int64_t>> direct;
  std::map<int64_t, size_t> index;  // candidate id -> node
  for (const MatchResult& r : decided) {
    if (r.winner == r.loser) continue;
    index.emplace(r.winner, 0);
    index.emplace(r.loser, 0);
    if (direct.insert({r.winner, r.loser}).second) out.push_back({r.winner, r.loser, false, r.tie_break});
  }
  std::vector<int64_t> ids;
  for (auto& [id, node] : index) {
    node = ids.size();
    ids.push_back(id);
  }
  // Two closures by Floyd-Warshall: over every result, and over results people made (no
  // tie-break). A derived pair is a tie-break one when only the first implies it.
  const size_t n = ids.size();
  std::vector<char> any(n * n, 0), human(n * n, 0);
  for (const Ordering& o : out) {
    const size_t a = index[o.positive], b = index[o.negative];
    any[a * n + b] = 1;
    if (!o.tie_break) human[a * n + b] = 1;
  }
  for (std::vector<char>* reach : {&any, &human}) {
    std::vector<char>& r = *reach;
    for (size_t k = 0; k < n; ++k) {
      for (size_t i = 0; i < n; ++i) {
        if (!r[i * n + k]) continue;
        for (size_t j = 0; j < n; ++j) r[i * n + j] |= r[k * n + j];
      }
    }
  }
  for (size_t i = 0; i < n; ++i) {
    for (size_t j = 0; j < n; ++j) {
      if (i == j || !any[i * n + j] || any[j * n + i]) continue;  // unrelated, or contradicted by a cycle
      if (direct.count({ids[i], ids[j]})) continue;
      out.push_back({ids[i], ids[j], true, !human[i * n + j]});
    }
  }
  return out;
}

}  // namespace retarget
