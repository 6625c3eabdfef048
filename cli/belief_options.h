// --belief-prior-sd, --belief-weber, --belief-reading-sd, --belief-lapse, --belief-step,
// --belief-sparsity, --belief-passes and --belief-annotator-sd
// (correspond/belief_search.h) for the commands that run the belief search:
// `retarget correspond --informative` and `retarget rig-map fit --belief` (the last two are the
// rig head's alone).
#pragma once

#include <cxxopts.hpp>

#include "correspond/belief_search.h"

namespace retarget::cli {

// Adds the options with `defaults` (the search's, or BeliefSearchOptions::map_reading() for the
// rig head's reading of the answers).
void add_belief_options(cxxopts::Options& options, const BeliefSearchOptions& defaults = {});

// The settings the options give (validated: throws retarget::Error naming the option).
BeliefSearchOptions belief_options(const cxxopts::ParseResult& args);

}  // namespace retarget::cli
