// `retarget plot RUN`: a training run's curves from its metrics.csv (plot/run_plots.h).
#include <fmt/format.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "core/error.h"
#include "plot/gnuplot.h"
#include "plot/plot_parts.h"

namespace fs = std::filesystem;

namespace retarget {

namespace {

// metrics.csv's column names (its first line).
std::set<std::string> csv_columns(const std::string& csv) {
  std::ifstream in(csv);
  std::string header;
  if (!std::getline(in, header) || header.empty()) throw Error(csv + ":1", "expected a header line of column names");
  std::set<std::string> names;
  std::stringstream fields(header);
  for (std::string name; std::getline(fields, name, ',');) names.insert(name);
  if (!names.count("epoch")) throw Error(csv + ":1", "has no 'epoch' column (written by `retarget train`?)");
  return names;
}

std::string curve(const std::string& csv, const std::string& column, const std::string& style,
                  const std::string& title) {
  return fmt::format("{} using 'epoch':'{}' {} title {}", gnuplot_quote(csv), column, style, gnuplot_quote(title));
}

}  // namespace

std::string training_plot(const PlotOptions& options, const std::string& out) {
  const std::string csv = (fs::path(options.folder) / "metrics.csv").string();
  const std::set<std::string> columns = csv_columns(csv);
  const std::string png = (fs::path(out) / "training.png").string();
  std::string script = plot_header(options, png) + "set datafile separator ','\nset xlabel 'epoch'\nset logscale y\n";
  if (columns.count("validation_l1")) {
    script += fmt::format("set title {}\nset ylabel 'L1 of the normalised DR features (log)'\nplot ",
                          gnuplot_quote("VAE training: " + options.folder));
    script += curve(csv, "train_reconstruction", "with lines lw 2", "training reconstruction") + ", \\\n  ";
    script += curve(csv, "validation_l1", "with linespoints lw 2 pt 7", "validation L1") + ", \\\n  ";
    script +=
        curve(csv, "neutral_validation_l1", "with lines dt 2 lw 2", "the neutral answer (validation)") + ", \\\n  ";
    script += curve(csv, "mean_validation_l1", "with lines dt 3 lw 2", "the mean answer (validation)") + "\n";
  } else if (columns.count("paired")) {
    script += fmt::format(
        "set title {}\nset ylabel 'loss (log)'\nset y2label 'triplets right'\n"
        "set y2range [0:1]\nset y2tics\nplot ",
        gnuplot_quote("translation training: " + options.folder));
    script += curve(csv, "paired", "with lines lw 2", "L_P (paired)") + ", \\\n  ";
    script += curve(csv, "group", "with lines lw 2", "L_G (group)") + ", \\\n  ";
    script += curve(csv, "triplet", "with lines lw 2", "L_T (triplet)") + ", \\\n  ";
    script += curve(csv, "test_paired", "with lines dt 2 lw 2", "L_P, test people") + ", \\\n  ";
    script += curve(csv, "train_accuracy", "axes x1y2 with lines dt 3", "triplets right, training") + ", \\\n  ";
    script += curve(csv, "held_out_accuracy", "axes x1y2 with lines dt 4", "triplets right, held out") + "\n";
  } else if (columns.count("cycle")) {
    script += fmt::format("set title {}\nset ylabel 'loss (log)'\nplot ",
                          gnuplot_quote("CycleGAN+LFD training: " + options.folder));
    script += curve(csv, "cycle", "with lines lw 2", "cycle (|G'(G(x)) - x| + |G(G'(y)) - y|)") + ", \\\n  ";
    script += curve(csv, "adversarial", "with lines lw 2", "adversarial (generators)") + ", \\\n  ";
    script += curve(csv, "discriminator", "with lines lw 2", "discriminators") + ", \\\n  ";
    script += curve(csv, "similarity", "with lines dt 2 lw 2", "light-field distance of x to G(x), 0..1") + "\n";
  } else {
    throw Error(csv + ":1",
                "none of a VAE's (validation_l1), the translation network's (paired) or the CycleGAN's (cycle) "
                "columns");
  }
  run_gnuplot(script, (fs::path(out) / "training.gp").string());
  return png;
}

std::string codes_plot(const PlotOptions& options, const std::string& out) {
  const std::string tsv = (fs::path(options.folder) / "codes.tsv").string();
  const std::string png = (fs::path(out) / "codes.png").string();
  const std::string data = gnuplot_quote(tsv);
  std::string script = plot_header(options, png) + "set datafile separator '\\t'\nset key inside top right\n" +
                       "set xlabel 'first principal axis of the training codes'\n"
                       "set ylabel 'second principal axis'\n";
  script += fmt::format("set title {}\n",
                        gnuplot_quote("codes of training and test samples (retarget eval vae): " + options.folder));
  script += "plot " + data +
            " skip 1 using (strcol(1) eq 'train' ? $3 : NaN):4 with points pt 7 ps 0.4 lc rgb '#b8bcc6' "
            "title 'training samples', \\\n  " +
            data +
            " skip 1 using (strcol(1) eq 'test' ? $3 : NaN):4 with points pt 7 ps 0.7 lc rgb '#2f6fed' "
            "title 'test samples (people the training never saw)'\n";
  run_gnuplot(script, (fs::path(out) / "codes.gp").string());
  return png;
}

}  // namespace retarget
