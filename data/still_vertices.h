// The vertices a dataset never moves (the back of a head, a neck, a hat), which reconstruction
// can hold at their rest positions (ReconstructionOptions::anchors) instead of letting every
// small feature error of the moving region drift them.
//
// Avatars: the vertices no controller of the dataset's rig moves by more than the threshold at
// either end of its range (when the rig still loads and has the dataset's topology), else those
// the training samples' reconstructed meshes never move. Humans: none (the identity-averaged
// shapes a human VAE reconstructs sit on the training people's average neutral, not on the rest
// mesh, so no vertex is still relative to the rest).
#pragma once

#include <vector>

#include "data/dataset.h"

namespace retarget {

// threshold_mm: in millimetres at the eye-distance scale (or mesh units without eye landmarks).
// Returns ascending vertex indices; empty when everything moves, for human datasets, or when
// fewer than 3 vertices would be still (too few to hold a part).
std::vector<int> still_vertices(const Dataset& dataset, double threshold_mm = 0.01);

}  // namespace retarget
