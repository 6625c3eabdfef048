// `retarget plot` draws real PNGs with gnuplot from a training run's metrics.csv and an
// evaluation's metrics.json: pictures that decode, are not blank, at the size asked, with the
// data they were drawn from beside them.
#include <stb/stb_image.h>

#include <catch2/catch.hpp>
#include <filesystem>
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
  REQUIRE(pictures.size() == 3);
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
  CHECK_THAT(error_of([&] { write_plots(o); }), Catch::Contains("metrics.csv:1: neither a VAE's"));
  o.width = 10;
  CHECK_THAT(error_of([&] { write_plots(o); }), Catch::Contains("plot.width"));
}
