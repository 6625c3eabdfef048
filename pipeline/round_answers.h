// A round answered by people (`retarget pipeline` with annotators.kind: people): the pipeline
// waits for the round's project to be fully answered in the web tool, which someone serves
// beside it (`retarget annotate serve PROJECT`), and reports progress as answers arrive.
#pragma once

#include <string>

namespace retarget {

// Returns once every comparison of the project's store is decided, looking every
// `poll_seconds`; prints how to serve it and, on each change, "N of M comparisons decided".
// Throws retarget::Error naming the project when it cannot be read.
void wait_for_round_answers(const std::string& project, double poll_seconds);

}  // namespace retarget
