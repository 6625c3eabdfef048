// `retarget plot BUDGET`: the error against the annotation budget from scripts/budget_curve.sh's
// curve.csv (plot/run_plots.h).
#include <fmt/format.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "core/atomic_file.h"
#include "core/error.h"
#include "plot/gnuplot.h"
#include "plot/plot_parts.h"

namespace fs = std::filesystem;

namespace retarget {

namespace {

// curve.csv's rows: budget, set, method and the two fractions of the neutral answer's.
struct CurveRows {
  std::vector<std::string> methods;  // in first-seen order
  std::set<std::string> sets;
  std::map<std::string, std::map<int, std::map<std::string, std::pair<double, double>>>> value;  // set budget method
};

CurveRows read_curve(const std::string& csv) {
  std::ifstream in(csv);
  std::string line;
  if (!std::getline(in, line) || line.rfind("budget,set,method,moving_fraction_of_neutral,weight_active", 0) != 0)
    throw Error(csv + ":1", "expected the header of scripts/budget_curve.sh's curve.csv");
  CurveRows rows;
  for (int number = 2; std::getline(in, line); ++number) {
    if (line.empty()) continue;
    std::stringstream fields(line);
    std::string budget, set, method, mm, weights;
    if (!std::getline(fields, budget, ',') || !std::getline(fields, set, ',') || !std::getline(fields, method, ',') ||
        !std::getline(fields, mm, ',') || !std::getline(fields, weights, ','))
      throw Error(fmt::format("{}:{}", csv, number), "expected budget,set,method,mm fraction,weights fraction,...");
    try {
      rows.value[set][std::stoi(budget)][method] = {std::stod(mm), std::stod(weights)};
    } catch (const std::exception&) {
      throw Error(fmt::format("{}:{}", csv, number), "expected numbers, got \"" + line + "\"");
    }
    rows.sets.insert(set);
    if (std::find(rows.methods.begin(), rows.methods.end(), method) == rows.methods.end())
      rows.methods.push_back(method);
  }
  if (rows.sets.empty()) throw Error(csv, "has no rows");
  return rows;
}

}  // namespace

std::string budget_plot(const PlotOptions& options, const std::string& out) {
  const CurveRows rows = read_curve((fs::path(options.folder) / "curve.csv").string());
  const std::string png = (fs::path(out) / "curve.png").string();
  std::string script = plot_header(options, png) +
                       "set logscale x\nset xlabel 'annotation budget (comparisons)'\nset yrange [0:*]\n"
                       "set key inside top right\n";
  script += fmt::format("set multiplot layout 2,{} title {}\n", rows.sets.size(),
                        gnuplot_quote("each method's error as a multiple of the neutral answer's: " + options.folder));
  for (int measure = 0; measure < 2; ++measure) {
    for (const std::string& set : rows.sets) {
      std::string tsv = "budget";
      for (const std::string& m : rows.methods) tsv += "\t" + m;
      tsv += "\n";
      for (const auto& [budget, methods] : rows.value.at(set)) {
        tsv += std::to_string(budget);
        for (const std::string& m : rows.methods) {
          const auto it = methods.find(m);
          tsv +=
              it == methods.end() ? "\tNaN" : fmt::format("\t{:.4f}", measure ? it->second.second : it->second.first);
        }
        tsv += "\n";
      }
      const std::string data =
          (fs::path(out) / fmt::format("curve_{}_{}.tsv", set, measure ? "weights" : "mm")).string();
      write_file_atomically(data, [&](std::ostream& o) { o << tsv; });
      script +=
          fmt::format("set title {}\nset ylabel {}\n", gnuplot_quote(set),
                      gnuplot_quote(measure ? "x neutral (active rig weights)" : "x neutral (mm, moving vertices)"));
      script += fmt::format("plot for [i=2:{}] {} using 1:i with linespoints lw 2 title columnhead(i)\n",
                            rows.methods.size() + 1, gnuplot_quote(data));
    }
  }
  script += "unset multiplot\n";
  run_gnuplot(script, (fs::path(out) / "curve.gp").string());
  return png;
}

}  // namespace retarget
