// `retarget plot`: pictures of a run folder's training curves and of an evaluation, drawn by
// gnuplot (plot/gnuplot.h), each with the data it was drawn from beside it.
//
//   training run (metrics.csv):  PLOTS/training.png  losses per epoch, log scale; a VAE's
//                                validation L1 beside the trivial answers' (neutral, mean); the
//                                translation network's L_P, L_G, L_T and triplet accuracies;
//                                PLOTS/codes.png when the run has codes.tsv (retarget eval vae):
//                                training and test codes on their two principal axes (Fig. 14)
//   evaluation (metrics.json):   PLOTS/methods.png   each method's error as a multiple of the
//                                neutral answer's, mm over moving vertices and active rig weights,
//                                per set (references, blends)
//                                PLOTS/regions.png   mm over each region's vertices per method
//                                PLOTS/expressions.png  mm per reference expression: neutral,
//                                stage 1, full, rig head (worst first)
//                                PLOTS/identity.png  the spread of the same expression across
//                                people per method and set (Fig. 11)
//   budget curve (curve.csv):    PLOTS/curve.png     each method's error against the number of
//                                comparisons, per set, in mm and in rig weights
//                                (scripts/budget_curve.sh draws it into its own folder)
// PLOTS defaults to FOLDER/plots.
#pragma once

#include <string>
#include <vector>

namespace retarget {

struct PlotOptions {
  std::string folder;              // a training run (with metrics.csv) or an evaluation (with metrics.json)
  std::string out;                 // "": folder/plots
  int width = 1200, height = 700;  // pixels of each picture
  void validate() const;
};

// Writes the pictures for what `folder` holds; returns their paths. Throws retarget::Error
// naming the folder when it holds none of metrics.csv, metrics.json and curve.csv, or a file that
// does not read (the line, for CSV).
std::vector<std::string> write_plots(const PlotOptions& options);

}  // namespace retarget
