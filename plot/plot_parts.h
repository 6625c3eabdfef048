// What the plots of plot/run_plots.h share (internal to plot/).
#pragma once

#include <string>

#include "plot/run_plots.h"

namespace retarget {

// The terminal (PNG at the options' size) and output lines every script starts with.
std::string plot_header(const PlotOptions& options, const std::string& png);

// plot/training_plot.cpp: OUT/training.png from FOLDER/metrics.csv; returns its path.
std::string training_plot(const PlotOptions& options, const std::string& out);

// plot/training_plot.cpp: OUT/codes.png from FOLDER/codes.tsv (retarget eval vae); returns its path.
std::string codes_plot(const PlotOptions& options, const std::string& out);

// plot/budget_plot.cpp: OUT/curve.png from FOLDER/curve.csv (scripts/budget_curve.sh).
std::string budget_plot(const PlotOptions& options, const std::string& out);

// plot/evaluation_plot.cpp: OUT/{methods,regions,expressions}.png from FOLDER/metrics.json.
std::vector<std::string> evaluation_plots(const PlotOptions& options, const std::string& out);

}  // namespace retarget
