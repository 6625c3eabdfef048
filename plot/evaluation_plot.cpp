// `retarget plot EVAL`: an evaluation's pictures from its metrics.json (plot/run_plots.h).
#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "core/atomic_file.h"
#include "core/error.h"
#include "plot/gnuplot.h"
#include "plot/plot_parts.h"

namespace fs = std::filesystem;
using json = nlohmann::ordered_json;  // the evaluation's own order of methods

namespace retarget {

namespace {

// The methods in the evaluation's order (the neutral answer, DT, DT on the rig, then as given).
std::vector<std::string> method_order(const json& methods) {
  std::vector<std::string> order;
  for (const auto& [name, m] : methods.items()) order.push_back(name);
  return order;
}

// The sets to draw: metrics.json's "sets" (references, blends), or everything as "all".
std::vector<std::pair<std::string, json>> sets_of(const json& metrics, const std::string& path) {
  std::vector<std::pair<std::string, json>> sets;
  if (metrics.contains("sets"))
    for (const auto& [name, set] : metrics["sets"].items()) sets.emplace_back(name, set);
  if (sets.empty() && metrics.contains("methods")) sets.emplace_back("all", metrics);
  if (sets.empty()) throw Error(path, "has no \"methods\" (written by `retarget eval retarget`?)");
  return sets;
}

void write_tsv(const std::string& path, const std::string& text) {
  write_file_atomically(path, [&](std::ostream& out) { out << text; });
}

std::string methods_plot(const PlotOptions& options, const std::string& out,
                         const std::vector<std::pair<std::string, json>>& sets) {
  const std::vector<std::string> order = method_order(sets.front().second["methods"]);
  std::string tsv = "method";
  for (const auto& [name, set] : sets) tsv += "\t" + name + "_mm";
  for (const auto& [name, set] : sets) tsv += "\t" + name + "_weights";
  tsv += "\n";
  for (const std::string& method : order) {
    tsv += method;
    for (const char* key : {"moving_fraction_of_neutral", "weight_active_fraction_of_neutral"})
      for (const auto& [name, set] : sets)
        tsv += "\t" + (set["methods"].contains(method) ? fmt::format("{:.4f}", set["methods"][method].value(key, 0.0))
                                                       : std::string("NaN"));
    tsv += "\n";
  }
  const std::string data = (fs::path(out) / "methods.tsv").string(), png = (fs::path(out) / "methods.png").string();
  write_tsv(data, tsv);
  const size_t n = sets.size();
  std::string script = plot_header(options, png) +
                       "set style data histograms\nset style histogram clustered gap 1\n"
                       "set style fill solid 0.85 border -1\nset xtics rotate by -30\nset yrange [0:*]\n"
                       "set key inside top right\nset ylabel 'x the neutral answer (lower is better)'\n"
                       "set arrow 1 from graph 0, first 1 to graph 1, first 1 nohead dt 2 lw 2\n";
  script += fmt::format(
      "set multiplot layout 1,2 title {}\n",
      gnuplot_quote("each method's error as a multiple of the neutral answer's, per set: " + options.folder));
  for (int panel = 0; panel < 2; ++panel) {
    script += fmt::format("set title '{}'\nplot ", panel == 0 ? "mm over moving vertices" : "active rig weights");
    for (size_t i = 0; i < n; ++i)
      script += fmt::format("{}{} using {}{} title columnhead", i ? ", " : "", i ? "''" : gnuplot_quote(data),
                            2 + panel * n + i, i ? "" : ":xtic(1)");
    script += "\n";
  }
  script += "unset multiplot\n";
  run_gnuplot(script, (fs::path(out) / "methods.gp").string());
  return png;
}

std::string regions_plot(const PlotOptions& options, const std::string& out, const std::string& set_name,
                         const json& set) {
  const std::vector<std::string> order = method_order(set["methods"]);
  std::vector<std::string> regions;
  for (const auto& [region, value] : set["methods"][order.front()]["region_mm"].items()) regions.push_back(region);
  std::string tsv = "method";
  for (const std::string& r : regions) tsv += "\t" + r;
  tsv += "\n";
  for (const std::string& method : order) {
    tsv += method;
    for (const std::string& r : regions)
      tsv += fmt::format("\t{:.4f}", set["methods"][method]["region_mm"].value(r, 0.0));
    tsv += "\n";
  }
  const std::string data = (fs::path(out) / "regions.tsv").string(), png = (fs::path(out) / "regions.png").string();
  write_tsv(data, tsv);
  std::string script = plot_header(options, png) +
                       "set style data histograms\nset style histogram clustered gap 1\n"
                       "set style fill solid 0.85 border -1\nset xtics rotate by -30\nset yrange [0:*]\n"
                       "set ylabel 'mean error over the region, mm'\n";
  script += fmt::format("set title {}\nplot ", gnuplot_quote("error per region, " + set_name + ": " + options.folder));
  for (size_t i = 0; i < regions.size(); ++i)
    script += fmt::format("{}{} using {}{} title columnhead", i ? ", " : "", i ? "''" : gnuplot_quote(data), 2 + i,
                          i ? "" : ":xtic(1)");
  script += "\n";
  run_gnuplot(script, (fs::path(out) / "regions.gp").string());
  return png;
}

std::string expressions_plot(const PlotOptions& options, const std::string& out, const std::string& set_name,
                             const json& set) {
  std::vector<std::string> methods;
  for (const char* name : {"neutral", "stage1", "full", "rig_head"})
    if (set["methods"].contains(name)) methods.push_back(name);
  if (methods.empty()) methods.push_back(method_order(set["methods"]).front());
  const json& worst_by = set["methods"][methods.size() > 1 ? methods[methods.size() - 2] : methods.back()];
  std::vector<std::pair<double, std::string>> expressions;
  for (const auto& [name, value] : worst_by["expression_moving_mm"].items())
    expressions.emplace_back(value.get<double>(), name);
  std::sort(expressions.rbegin(), expressions.rend());
  std::string tsv = "expression";
  for (const std::string& m : methods) tsv += "\t" + m;
  tsv += "\n";
  for (const auto& [value, name] : expressions) {
    tsv += name;
    for (const std::string& m : methods)
      tsv += fmt::format("\t{:.4f}", set["methods"][m]["expression_moving_mm"].value(name, 0.0));
    tsv += "\n";
  }
  const std::string data = (fs::path(out) / "expressions.tsv").string(),
                    png = (fs::path(out) / "expressions.png").string();
  write_tsv(data, tsv);
  std::string script = plot_header(options, png) +
                       "set style data histograms\nset style histogram clustered gap 1\n"
                       "set style fill solid 0.85 border -1\nset xtics rotate by -90 font ',9'\nset yrange [0:*]\n"
                       "set ylabel 'mm over moving vertices'\n";
  script += fmt::format("set title {}\nplot ",
                        gnuplot_quote("error per expression, " + set_name + " (worst first): " + options.folder));
  for (size_t i = 0; i < methods.size(); ++i)
    script += fmt::format("{}{} using {}{} title columnhead", i ? ", " : "", i ? "''" : gnuplot_quote(data), 2 + i,
                          i ? "" : ":xtic(1)");
  script += "\n";
  run_gnuplot(script, (fs::path(out) / "expressions.gp").string());
  return png;
}

// Identity independence (the paper's Fig. 11): each method's spread across people per set.
std::string identity_plot(const PlotOptions& options, const std::string& out,
                          const std::vector<std::pair<std::string, json>>& sets) {
  const std::vector<std::string> order = method_order(sets.front().second["methods"]);
  std::string tsv = "method";
  for (const auto& [name, set] : sets) tsv += "\t" + name;
  tsv += "\n";
  for (const std::string& method : order) {
    tsv += method;
    for (const auto& [name, set] : sets)
      tsv += set["methods"].contains(method)
                 ? fmt::format("\t{:.4f}", set["methods"][method].value("identity_spread_mm", 0.0))
                 : std::string("\tNaN");
    tsv += "\n";
  }
  const std::string data = (fs::path(out) / "identity.tsv").string(), png = (fs::path(out) / "identity.png").string();
  write_tsv(data, tsv);
  std::string script = plot_header(options, png) +
                       "set style data histograms\nset style histogram clustered gap 1\n"
                       "set style fill solid 0.85 border -1\nset xtics rotate by -30\nset yrange [0:*]\n"
                       "set key inside top right\n"
                       "set ylabel 'mm: each person from the mean of everyone making the expression'\n";
  script +=
      fmt::format("set title {}\nplot ",
                  gnuplot_quote("identity independence: the same expression from different people, " + options.folder));
  for (size_t i = 0; i < sets.size(); ++i)
    script += fmt::format("{}{} using {}{} title columnhead", i ? ", " : "", i ? "''" : gnuplot_quote(data), 2 + i,
                          i ? "" : ":xtic(1)");
  script += "\n";
  run_gnuplot(script, (fs::path(out) / "identity.gp").string());
  return png;
}

}  // namespace

std::vector<std::string> evaluation_plots(const PlotOptions& options, const std::string& out) {
  const std::string path = (fs::path(options.folder) / "metrics.json").string();
  std::ifstream in(path);
  json metrics;
  try {
    metrics = json::parse(in);
  } catch (const std::exception& e) {
    throw Error(path, std::string("not JSON: ") + e.what());
  }
  const std::vector<std::pair<std::string, json>> sets = sets_of(metrics, path);
  const auto references = std::find_if(sets.begin(), sets.end(), [](const auto& s) { return s.first == "references"; });
  const auto& [name, set] = references != sets.end() ? *references : sets.front();
  return {methods_plot(options, out, sets), regions_plot(options, out, name, set),
          expressions_plot(options, out, name, set), identity_plot(options, out, sets)};
}

}  // namespace retarget
