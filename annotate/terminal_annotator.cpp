#include "annotate/terminal_annotator.h"

#include <fmt/format.h>

#include <cctype>
#include <cmath>
#include <optional>

#include "core/config.h"
#include "core/error.h"

namespace retarget {

namespace {

std::string trimmed_lower(const std::string& line) {
  size_t begin = 0, end = line.size();
  while (begin < end && std::isspace(static_cast<unsigned char>(line[begin]))) ++begin;
  while (end > begin && std::isspace(static_cast<unsigned char>(line[end - 1]))) --end;
  std::string out = line.substr(begin, end - begin);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

void show(std::ostream& out, const Assignment& a, const RenderPaths& renders) {
  out << fmt::format("\n[{}] round {}, comparison {}\n", a.label, a.round, a.comparison);
  out << "  anchor: " << renders.anchor(a.label) << '\n';
  out << "  1: " << renders.candidate(a.left) << '\n';
  out << "  2: " << renders.candidate(a.right) << '\n';
  out << "Which looks more like the anchor? 1 / 2 / d (draw) / u (undo) / q (quit): " << std::flush;
}

std::string group_status(AnnotationStore& store, int64_t group) {
  for (const GroupProgress& g : store.progress().groups) {
    if (g.group != group) continue;
    if (g.champion) return fmt::format("'{}' is finished: sample {} is the best match", g.label, *g.champion);
    return fmt::format("{} of {} comparisons decided in '{}'", g.done, g.total, g.label);
  }
  return std::string();
}

// Hands the comparison on screen back to the queue. It may be gone already (withdrawn by an undo,
// or its lease lost to someone else after a long pause); then there is nothing to hand back.
void release_quietly(AnnotationStore& store, int64_t comparison, const std::string& annotator) {
  try {
    store.release(comparison, annotator);
  } catch (const Error&) {
  }
}

}  // namespace

void TerminalOptions::validate(const std::string& key_path) const {
  require(std::isfinite(lease_seconds) && lease_seconds > 0, key_path + ".lease_seconds",
          fmt::format("expected a positive number of seconds, got {}", lease_seconds));
}

TerminalSession run_terminal_annotator(AnnotationStore& store, const std::string& annotator, const RenderPaths& renders,
                                       std::istream& in, std::ostream& out, const TerminalOptions& options) {
  options.validate();
  if (!renders.anchor || !renders.candidate) throw Error("terminal annotator", "the render path callbacks are not set");
  store.register_annotator(annotator);
  TerminalSession session;
  std::optional<Assignment> current;
  while (true) {
    if (!current) current = store.next_comparison(annotator, options.lease_seconds);
    if (!current) {
      out << "\nNothing left to compare for now. Thank you!\n";
      return session;
    }
    show(out, *current, renders);
    std::string line;
    if (!std::getline(in, line)) {
      out << '\n';
      release_quietly(store, current->comparison, annotator);
      session.quit = true;
      return session;
    }
    const std::string choice = trimmed_lower(line);
    try {
      if (choice == "q") {
        release_quietly(store, current->comparison, annotator);
        out << "Bye: your answers are saved.\n";
        session.quit = true;
        return session;
      }
      if (choice == "u") {
        const Assignment previous = store.undo_last(annotator, options.lease_seconds);
        ++session.undone;
        // The comparison on screen may have been withdrawn by the undo (it was fed by the answer).
        if (previous.comparison != current->comparison) release_quietly(store, current->comparison, annotator);
        out << fmt::format("Undone: comparison {} is yours to answer again.\n", previous.comparison);
        current = previous;
        continue;
      }
      if (choice != "1" && choice != "2" && choice != "d") {
        out << "Please type 1, 2, d, u or q.\n";
        continue;
      }
      const Answer answer = choice == "1" ? Answer::left : choice == "2" ? Answer::right : Answer::draw;
      const AnswerResult result = store.answer(current->comparison, annotator, answer);
      if (answer == Answer::draw) {
        ++session.draws;
      } else {
        ++session.decided;
      }
      switch (result.status) {
        case AnswerStatus::decided:
          out << fmt::format("Recorded. {}.\n", group_status(store, current->group));
          break;
        case AnswerStatus::requeued:
          out << "Draw: the comparison goes to another annotator.\n";
          break;
        case AnswerStatus::tie_break:
          out << fmt::format(
              "Draw again: settled by the distance to the transferred expression (sample {} wins). {}.\n",
              result.winner.value_or(0), group_status(store, current->group));
          break;
      }
      current.reset();
    } catch (const Error& e) {
      out << "Error: " << e.what() << '\n';
      if (choice != "u") current.reset();
    }
  }
}

}  // namespace retarget
