#include "plot/run_plots.h"

#include <fmt/format.h>

#include <filesystem>

#include "core/config.h"
#include "core/error.h"
#include "plot/gnuplot.h"
#include "plot/plot_parts.h"

namespace fs = std::filesystem;

namespace retarget {

void PlotOptions::validate() const {
  require(!folder.empty(), "plot.folder", "expected a training run or an evaluation folder");
  require_in_range(width, 200, 8000, "plot.width");
  require_in_range(height, 150, 8000, "plot.height");
}

std::string plot_header(const PlotOptions& options, const std::string& png) {
  return fmt::format(
      "set terminal pngcairo size {},{} noenhanced font ',11'\nset output {}\nset grid\n"
      "set key outside right top\n",
      options.width, options.height, gnuplot_quote(png));
}

std::vector<std::string> write_plots(const PlotOptions& options) {
  options.validate();
  const fs::path folder(options.folder);
  if (!fs::is_directory(folder)) throw Error(options.folder, "is not a folder");
  const std::string out = options.out.empty() ? (folder / "plots").string() : options.out;
  fs::create_directories(out);
  if (fs::exists(folder / "metrics.csv")) {
    std::vector<std::string> pictures{training_plot(options, out)};
    if (fs::exists(folder / "codes.tsv")) pictures.push_back(codes_plot(options, out));
    return pictures;
  }
  if (fs::exists(folder / "metrics.json")) return evaluation_plots(options, out);
  if (fs::exists(folder / "curve.csv")) return {budget_plot(options, out)};
  throw Error(options.folder,
              "holds neither metrics.csv (a training run), metrics.json (an evaluation) nor curve.csv "
              "(scripts/budget_curve.sh)");
}

}  // namespace retarget
