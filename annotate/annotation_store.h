// The annotation store: one SQLite file per project holding the groups (a human reference
// expression and its avatar candidates), the tournament comparisons shown to annotators, their
// answers, and the annotators. Several annotators - threads or processes, each with its own
// AnnotationStore - share one file: work is handed out under leases inside BEGIN IMMEDIATE
// transactions, and every call commits before it returns, so a killed process loses nothing
// it was told had happened.
//
// The flow for one annotator:
//   AnnotationStore store = AnnotationStore::open("project/annotations.db");
//   while (auto a = store.next_comparison("alice", 300)) {
//     show(a->label, a->left, a->right);
//     store.answer(a->comparison, "alice", Answer::left);
//   }
//
// Draws: a comparison answered "draw" returns to the queue for annotators who have not drawn
// it. Once every active annotator has drawn it (with one annotator: after the first draw) it
// is handed out once more to anyone, and a draw by someone who drew it before is settled by
// the geometric tie-break - the candidate with the smaller distance to y0 wins - and marked
// tie_break.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace retarget {

enum class Answer { left, right, draw };

// "left", "right", "draw".
const char* answer_name(Answer answer);

struct StoreOptions {
  double busy_timeout_seconds = 30;  // how long a call waits while another connection writes; > 0
  double active_seconds = 900;       // annotators seen within this many seconds count as active when
                                     // deciding whether everyone has drawn a comparison; > 0
  std::function<double()> clock;     // current time in seconds (any fixed epoch); empty = the system
                                     // clock. Tests inject one to expire leases without sleeping.

  // Throws retarget::Error naming `key_path`.<field> for a value out of range.
  void validate(const std::string& key_path = "store") const;
};

// A group as created: the anchor (a human reference expression) and its candidates.
struct GroupInfo {
  int64_t id = 0;
  std::string label;                // names the human expression, unique in the store
  std::vector<int64_t> candidates;  // avatar sample ids, in the order given to create_group
  std::vector<double> distances;    // per candidate, its distance to y0 (tie-break: smaller wins)
  uint64_t seed = 0;                // the tournament's pairing seed
};

// One comparison handed to an annotator: which of `left` and `right` looks more like `label`?
struct Assignment {
  int64_t comparison = 0;  // id to pass to answer()
  int64_t group = 0;
  std::string label;  // the anchor: the human expression's label
  int round = 0;      // 1-based tournament round
  int64_t left = 0;   // avatar sample ids
  int64_t right = 0;
  double lease_expires = 0;  // clock time after which it may be handed to someone else
};

enum class AnswerStatus {
  decided,    // the annotator chose left or right
  requeued,   // a draw: back in the queue for another annotator (or once more for anyone)
  tie_break,  // a repeated draw, settled by the distance to y0
};

struct AnswerResult {
  AnswerStatus status = AnswerStatus::decided;
  std::optional<int64_t> winner;    // sample id that advanced, unless requeued
  std::vector<int64_t> opened;      // comparisons this answer made ready (the next round)
  std::optional<int64_t> champion;  // sample id, when this answer finished the group
};

enum class ComparisonState { open, assigned, decided };
const char* state_name(ComparisonState state);

// A comparison as stored, for inspection.
struct ComparisonRecord {
  int64_t id = 0;
  int64_t group = 0;
  int round = 0;
  int position = 0;  // within the round
  int64_t left = 0;  // sample ids
  int64_t right = 0;
  ComparisonState state = ComparisonState::open;
  std::string assigned_to;  // empty unless assigned (or the last holder once decided)
  double assigned_at = 0;
  int draw_count = 0;
  std::vector<std::string> drawn_by;  // annotators who answered draw, in order
  std::optional<int64_t> winner;      // sample id once decided
};

// One answer as stored (draws included).
struct DecisionRecord {
  int64_t id = 0;
  int64_t comparison = 0;
  std::string annotator;  // empty for a tie-break (the system decided)
  Answer answer = Answer::left;
  double time = 0;  // clock seconds
  bool tie_break = false;
};

struct GroupProgress {
  int64_t group = 0;
  std::string label;
  int done = 0;   // decided comparisons
  int total = 0;  // comparisons the tournament needs: candidates - 1
  int tie_breaks = 0;
  std::optional<int64_t> champion;  // sample id once the final is decided
};

struct AnnotatorProgress {
  std::string name;
  int decided = 0;  // left/right answers standing (undone ones are gone)
  int draws = 0;
  double last_seen = 0;
  int holding = 0;  // comparisons leased to them now (lease not run out)
};

struct StoreProgress {
  std::vector<GroupProgress> groups;          // by id
  std::vector<AnnotatorProgress> annotators;  // by name
  int held = 0;                               // comparisons under a live lease, all annotators
  int done() const;
  int total() const;
  bool finished() const { return done() == total(); }
};

// (anchor, positive, negative) for the translation network's triplet loss.
struct Triplet {
  int64_t group = 0;
  std::string anchor;    // the group's label: the human expression
  int64_t positive = 0;  // avatar sample id judged closer to the anchor
  int64_t negative = 0;
  bool derived = false;    // inferred by transitivity (a > b, b > c gives a > c)
  bool tie_break = false;  // rests on the geometric tie-break rather than a person's choice
  std::string annotator;   // who decided a direct one (the first to, for a repeated pair); empty for
                           // a tie-break or a derived one
};

struct SessionsEnded {
  int sessions = 0;  // sign-in sessions removed
  int released = 0;  // comparisons the annotator held, back in the queue
};

class AnnotationStore {
 public:
  // 2: sign-in sessions. Version 1 files are upgraded on open.
  static constexpr int kSchemaVersion = 2;

  // Opens the store at `path`, creating the file, its folder and the schema when new. Turns on
  // WAL journaling (readers never block the writer), foreign keys and the busy timeout. Throws
  // retarget::Error naming the path if the file is not an SQLite database, was written by
  // another application, or has a different schema version.
  static AnnotationStore open(const std::string& path, const StoreOptions& options = {});

  AnnotationStore(AnnotationStore&&) noexcept;
  AnnotationStore& operator=(AnnotationStore&&) noexcept;
  ~AnnotationStore();

  const std::string& path() const;

  // Adds a group for the human expression `label` (non-empty, unique in the store) with its
  // avatar candidates (sample ids, >= 2, distinct) and each one's distance to y0 (finite, same
  // length), and creates its first comparisons; Tournament(candidates.size(), seed) pairs them.
  // Returns the group id. Throws retarget::Error for bad arguments or a duplicate label.
  int64_t create_group(const std::string& label, const std::vector<int64_t>& candidates,
                       const std::vector<double>& distances, uint64_t seed);
  std::vector<GroupInfo> groups() const;
  // Throws retarget::Error for an unknown id.
  GroupInfo group(int64_t id) const;

  // Records `name` (non-empty) as an annotator, or marks it as seen now. next_comparison() does
  // this implicitly; call it up front so an annotator counts as active before asking for work.
  void register_annotator(const std::string& name);

  // Leases a comparison to `annotator` (registering it if new) for `lease_seconds` (> 0): the
  // one it already holds if any (most recent first, lease renewed), else the longest-queued
  // comparison that is open or whose holder's lease has run out (abandoned), and that this
  // annotator has not drawn unless every active annotator has. nullopt when nothing is
  // available to this annotator right now; others may still be working (see finished()).
  std::optional<Assignment> next_comparison(const std::string& annotator, double lease_seconds);

  // Records `annotator`'s answer to comparison `comparison` and advances the tournament in the
  // same transaction. Throws retarget::Error if the comparison does not exist or is decided, if
  // the annotator is unknown or does not hold its lease.
  AnswerResult answer(int64_t comparison, const std::string& annotator, Answer answer);

  // Hands a leased comparison back to the queue (keeping its place). Throws retarget::Error if
  // `annotator` does not hold it.
  void release(int64_t comparison, const std::string& annotator);

  // Takes back `annotator`'s most recent answer and leases its comparison to them again (for
  // lease_seconds) to be answered anew; an undone tie-break's draw takes the tie-break with it.
  // Repeated calls walk further back. Throws retarget::Error if the annotator has no answer left
  // to undo, or something depends on it: the comparison its winner advanced to has been answered
  // (that comparison is withdrawn otherwise), or after a draw, someone else has decided the
  // comparison or holds it.
  Assignment undo_last(const std::string& annotator, double lease_seconds = 300);

  std::vector<ComparisonRecord> comparisons(std::optional<int64_t> group = std::nullopt) const;
  // Whether comparison `id` exists (in any state) / `sample` is a candidate of some group.
  bool has_comparison(int64_t id) const;
  bool has_sample(int64_t sample) const;
  std::vector<DecisionRecord> decisions() const;
  StoreProgress progress() const;
  // True when every group's tournament has a champion.
  bool finished() const;

  // Sign-in sessions of the web tool (annotate/annotation_server.h): `token` (>= 16 characters,
  // unique; the server makes it random) stands for `annotator`, registered if new. Sessions
  // outlive the server process, so a restarted server still knows its signed-in annotators.
  void add_session(const std::string& token, const std::string& annotator);
  // The annotator a token stands for; nullopt for an unknown token.
  std::optional<std::string> session_annotator(const std::string& token) const;
  bool has_session(const std::string& annotator) const;
  // Ends every session of `annotator` and hands the comparisons they hold back to the queue.
  // Throws retarget::Error for an unknown annotator.
  SessionsEnded end_sessions(const std::string& annotator);

  // Every decided comparison as a triplet (by group, then in the order decided), followed per
  // group by the transitive ones when include_derived (derive_triplets in tournament.h).
  std::vector<Triplet> triplets(bool include_derived = true) const;
  // triplets(include_derived) as CSV with the header group,anchor,positive,negative,derived,
  // tie_break (flags 0/1, anchor quoted when needed), written atomically to `path`.
  void export_csv(const std::string& path, bool include_derived = true) const;

 private:
  struct Impl;
  explicit AnnotationStore(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

// One CSV field: quoted (with doubled quotes) when it holds a comma, quote or line break.
std::string csv_field(const std::string& text);

}  // namespace retarget
