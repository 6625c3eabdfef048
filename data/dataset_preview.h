// A picture of a dataset: a few samples rebuilt from their stored DR features (which checks
// the features as much as it shows them) and drawn as a captioned grid.
#pragma once

#include "data/dataset.h"
#include "render/render.h"

namespace retarget {

struct DatasetPreviewOptions {
  int count = 12;          // samples shown (humans: spread over up to 3 training subjects)
  int size = 256;          // pixels per picture
  bool both_views = true;  // front and 3/4 side by side
  void validate() const;   // throws retarget::Error naming the option
};

// Avatars: the rest pose and evenly spaced samples, captioned with their strongest
// controllers ("jawOpen .83 + smileLeft .41"). Humans: the identity-averaged targets of a few
// expressions, then those expressions for up to 3 training subjects, captioned
// "subject: expression". Each sample is reconstructed from its raw features against the
// dataset's rest mesh (one factorisation), aligned to the rest pose.
Image dataset_preview(const Dataset& dataset, const DatasetPreviewOptions& options = {});

}  // namespace retarget
