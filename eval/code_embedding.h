// The codes a VAE gives a dataset's samples, on their first two principal axes (the paper's
// Fig. 14: training and test codes embedded together), for `retarget plot`: whether unseen
// people's codes land among the training codes of the same expression, or apart.
#pragma once

#include <string>

#include "data/dataset.h"
#include "models/mesh_vae.h"

namespace retarget {

struct CodeEmbeddingOptions {
  int64_t max_train = 2000;  // training samples embedded at most (evenly spaced), >= 1
  int64_t batch = 64;        // samples per network batch, >= 1
  void validate() const;     // throws retarget::Error naming "codes.<field>"
};

struct CodeEmbedding {
  int64_t train = 0, test = 0;  // samples embedded
  double explained = 0;         // variance fraction the two axes hold
  std::string path;
};

// Encodes the samples (encoder means, eval mode, no gradients), projects them on the two
// principal axes of the training codes and writes `path` atomically: a header, then one line per
// sample "split<TAB>label<TAB>pc1<TAB>pc2" (split: train or test; label: a human dataset's
// expression name, "sample" for an avatar's). Throws retarget::Error when the dataset has no
// training samples or the VAE does not fit it.
CodeEmbedding write_code_embedding(MeshVaeImpl& vae, const Dataset& d, const std::string& path,
                                   const CodeEmbeddingOptions& options = {});

}  // namespace retarget
