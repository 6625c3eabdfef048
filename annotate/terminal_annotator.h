// A person annotating in a terminal: for each comparison it prints the paths of the three
// renders (the human expression - the anchor - and the two avatar candidates, to open in any
// image viewer) and reads one answer per line:
//   1 = left looks more like the anchor, 2 = right, d = draw (pass it to someone else),
//   u = undo my last answer, q = quit (the current comparison goes back to the queue).
// Input and output are plain streams, so a session can be scripted and tested.
#pragma once

#include <cstdint>
#include <functional>
#include <istream>
#include <ostream>
#include <string>

#include "annotate/annotation_store.h"

namespace retarget {

// Where the renders are; called once per comparison shown.
struct RenderPaths {
  std::function<std::string(const std::string& label)> anchor;  // the human expression `label`
  std::function<std::string(int64_t sample)> candidate;         // an avatar sample
};

struct TerminalOptions {
  double lease_seconds = 900;  // how long a shown comparison stays reserved for this person; > 0

  // Throws retarget::Error naming `key_path`.<field> for a value out of range.
  void validate(const std::string& key_path = "terminal") const;
};

struct TerminalSession {
  int decided = 0;  // left/right answers given
  int draws = 0;
  int undone = 0;
  bool quit = false;  // the person typed q or the input ended; false: nothing was left to compare
};

// Runs one person's session against `store` as `annotator` until they quit, the input ends, or
// no comparison is available to them. A store error (for example a lease lost to someone else
// after a long pause) is printed and the session goes on with the next comparison.
TerminalSession run_terminal_annotator(AnnotationStore& store, const std::string& annotator, const RenderPaths& renders,
                                       std::istream& in, std::ostream& out, const TerminalOptions& options = {});

}  // namespace retarget
