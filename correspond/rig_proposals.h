// Group members proposed by the avatar's rig (beyond the paper): in a later round of
// tournaments, each group can hold new rig expressions around its start (the previous round's
// champion, or the deformation transfer projected onto the rig) instead of only the avatar
// dataset's samples nearest to it. The dataset is a fixed, sparse cover of the rig's weight
// space (2,000 samples of 1-5 random controllers for 11 controllers), so the samples nearest to
// a champion rarely improve on it: on the shared rabbit the champions' rig-weight distance to
// the truth stopped at 0.28 after 8 rounds while the dataset itself held samples at 0.09.
// Proposals move the start in the rig's own parameters, so each round can refine it as finely
// as the annotators can tell the candidates apart.
//
// A proposal moves `controllers` distinct controllers of the start, chosen uniformly at random,
// each by a normal step of standard deviation `sigma` times the controller's range, clamped
// into the range. The first proposal of every group is the start itself, so a round never loses
// what the previous one found.
#pragma once

#include <torch/torch.h>

#include <cstdint>
#include <string>

#include "geometry/rig.h"

namespace retarget {

struct RigProposalOptions {
  int count = 0;        // proposals per group, the start included; 0 = none
  double sigma = 0.4;   // step size, a fraction of each controller's range; finite, > 0
  int controllers = 2;  // controllers each proposal moves (at most the rig's); >= 1
  uint64_t seed = 1;    // same seed, start and rig: same proposals on every machine

  // Throws retarget::Error naming `key_path`.<field> for a value out of range.
  void validate(const std::string& key_path = "correspond.proposals") const;
};

// The proposals around each start: starts [K, C] float64 rig weights (C = the rig's controller
// count, each inside its range) -> [K, count, C] float64, row 0 of each group the start itself.
// Group k draws from its own stream (seed, k), so a group's proposals do not depend on the
// others. Throws retarget::Error for invalid options, a shape that does not fit the rig, or a
// start weight outside its controller's range (by more than 1e-9 of the range).
torch::Tensor propose_rig_weights(const Rig& rig, const torch::Tensor& starts, const RigProposalOptions& options);

}  // namespace retarget
