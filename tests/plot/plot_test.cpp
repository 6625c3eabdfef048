// `retarget plot` draws real PNGs with gnuplot from a training run's metrics.csv and an
// evaluation's metrics.json: pictures that decode, are not blank, at the size asked, with the
// data they were drawn from beside them.
#include <stb/stb_image.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>

#include "plot/run_plots.h"
#include "scratch.h"

using namespace retarget;
using namespace retarget::test;
namespace fs = std::filesystem;

namespace {

// Decodes the PNG; returns how many distinct colours a coarse sample of it holds.
int colours_in(const std::string& png, int want_width, int want_height) {
  int w = 0, h = 0, channels = 0;
  unsigned char* pixels = stbi_load(png.c_str(), &w, &h, &channels, 3);
  REQUIRE(pixels != nullptr);
  CHECK(w == want_width);
  CHECK(h == want_height);
  std::set<int> colours;
  for (int y = 0; y < h; y += 3)
    for (int x = 0; x < w; x += 3) {
      const unsigned char* p = pixels + 3 * (y * w + x);
      colours.insert(p[0] << 16 | p[1] << 8 | p[2]);
    }
  stbi_image_free(pixels);
  return static_cast<int>(colours.size());
}

}  // namespace

TEST_CASE("a VAE run's curves and an evaluation's errors are drawn as PNGs", "[plot]") {
  const fs::path dir = scratch_dir("plots");
  fs::create_directories(dir / "run");
  write_file(dir / "run", "metrics.csv",
             "epoch,lr,train_loss,train_reconstruction,train_kl,validation_l1,neutral_validation_l1,"
             "mean_validation_l1,seconds,samples_per_second\n"
             "1,0.001,0.5,0.4,80,0.30,0.9,0.6,1,100\n2,0.001,0.3,0.2,81,0.20,0.9,0.6,1,100\n"
             "3,0.001,0.2,0.1,82,0.15,0.9,0.6,1,100\n");
  PlotOptions o;
  o.folder = (dir / "run").string();
  o.width = 640;
  o.height = 400;
  const std::vector<std::string> training = write_plots(o);
  REQUIRE(training.size() == 1);
  CHECK(colours_in(training[0], 640, 400) > 3);
  CHECK(fs::exists(dir / "run/plots/training.gp"));

  fs::create_directories(dir / "eval");
  const std::string method = R"({"moving_fraction_of_neutral": %F, "weight_active_fraction_of_neutral": 0.5,
    "region_mm": {"eyes": 0.1, "mouth": %F}, "expression_moving_mm": {"smile": %F, "angry": 0.2}})";
  auto with = [&](double f) {
    std::string m = method;
    for (size_t at; (at = m.find("%F")) != std::string::npos;) m.replace(at, 2, std::to_string(f));
    return m;
  };
  write_file(dir / "eval", "metrics.json",
             R"({"sets": {"references": {"samples": 2, "methods": {"neutral": )" + with(1.0) + R"(, "full": )" +
                 with(0.3) + R"(, "rig_head": )" + with(0.25) +
                 R"(}}, "blends": {"samples": 2, "methods": {"neutral": )" + with(1.0) + R"(, "full": )" + with(0.6) +
                 R"(, "rig_head": )" + with(0.4) + "}}}}");
  o.folder = (dir / "eval").string();
  const std::vector<std::string> pictures = write_plots(o);
  REQUIRE(pictures.size() == 4);
  CHECK(fs::path(pictures[3]).filename() == "identity.png");
  for (const std::string& png : pictures) CHECK(colours_in(png, 640, 400) > 3);
  CHECK(fs::exists(dir / "eval/plots/methods.tsv"));
  CHECK(fs::exists(dir / "eval/plots/expressions.tsv"));
}

TEST_CASE("plot refuses a folder that holds nothing to draw, and a metrics.csv of another kind", "[plot]") {
  const fs::path dir = scratch_dir("plots_bad");
  PlotOptions o;
  o.folder = dir.string();
  CHECK_THAT(error_of([&] { write_plots(o); }), Catch::Contains("holds neither metrics.csv"));
  write_file(dir, "metrics.csv", "epoch,whatever\n1,2\n");
  CHECK_THAT(error_of([&] { write_plots(o); }), Catch::Contains("metrics.csv:1: none of a VAE's"));
  o.width = 10;
  CHECK_THAT(error_of([&] { write_plots(o); }), Catch::Contains("plot.width"));
}

TEST_CASE("the error against the budget is drawn from budget_curve.sh's curve.csv", "[plot]") {
  const fs::path dir = scratch_dir("plots_budget");
  write_file(dir, "curve.csv",
             "budget,set,method,moving_fraction_of_neutral,weight_active_fraction_of_neutral,moving_mm\n"
             "700,references,full,0.45,0.26,0.5\n700,references,rig_head,0.07,0.25,0.07\n"
             "2000,references,full,0.39,0.21,0.43\n2000,references,rig_head,0.06,0.14,0.06\n"
             "700,blends,full,1.5,0.38,0.2\n2000,blends,full,1.55,0.35,0.22\n");
  PlotOptions o;
  o.folder = dir.string();
  o.width = 800;
  o.height = 600;
  const std::vector<std::string> pictures = write_plots(o);
  REQUIRE(pictures.size() == 1);
  CHECK(fs::path(pictures[0]).filename() == "curve.png");
  CHECK(colours_in(pictures[0], 800, 600) > 3);
  // One table per set and measure, a column per method (NaN where a set lacks it).
  std::ifstream blends(dir / "plots/curve_blends_mm.tsv");
  std::string header, first;
  std::getline(blends, header);
  std::getline(blends, first);
  CHECK(header == "budget\tfull\trig_head");
  CHECK(first == "700\t1.5000\tNaN");
  write_file(dir, "curve.csv",
             "budget,set,method,moving_fraction_of_neutral,weight_active_fraction_of_neutral\n700,x\n");
  CHECK_THAT(error_of([&] { write_plots(o); }), Catch::Contains("curve.csv:2"));
}
