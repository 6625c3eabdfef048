#include <stb/stb_image.h>

#include <catch2/catch.hpp>
#include <string>
#include <vector>

#include "cli/commands.h"
#include "core/error.h"
#include "geometry/mesh_io.h"
#include "render/render.h"
#include "test_support.h"

using namespace retarget;
using Catch::Contains;

namespace {

int run_render(std::vector<std::string> args) {
  args.insert(args.begin(), "render");
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  return cli::render_command(static_cast<int>(argv.size()), argv.data());
}

std::pair<int, int> png_size(const std::string& path) {
  int width = 0, height = 0, channels = 0;
  uint8_t* pixels = stbi_load(path.c_str(), &width, &height, &channels, 3);
  REQUIRE(pixels != nullptr);
  stbi_image_free(pixels);
  return {width, height};
}

}  // namespace

TEST_CASE("retarget render draws one picture or a captioned grid", "[render]") {
  const auto dir = test::scratch_dir("render_command");
  const std::string a = (dir / "a.obj").string(), b = (dir / "b.obj").string();
  Mesh patch = test::bumpy_patch(8);
  write_mesh(a, patch);
  patch.vertices.col(2) *= 2.0;
  write_mesh(b, patch);

  const std::string one = (dir / "one.png").string();
  CHECK(run_render({a, "--out", one, "--size", "64"}) == 0);
  CHECK(png_size(one) == std::pair{64, 64});

  const std::string grid = (dir / "out" / "grid.png").string();
  CHECK(run_render({a, b, "--out", grid, "--size", "64", "--view", "both", "--columns", "1", "--captions", "x,y"}) ==
        0);
  CHECK(png_size(grid) == std::pair{2 * 64, 2 * (64 + text_band_height(2))});
}

TEST_CASE("retarget render refuses what it cannot draw, saying why", "[render]") {
  const auto dir = test::scratch_dir("render_command_errors");
  const std::string a = (dir / "a.obj").string(), out = (dir / "x.png").string();
  write_mesh(a, test::bumpy_patch(4));
  CHECK_THROWS_WITH(run_render({"--out", out}), Contains("at least one mesh"));
  CHECK_THROWS_WITH(run_render({a}), Contains("--out"));
  CHECK_THROWS_WITH(run_render({a, "--out", (dir / "x.jpg").string()}), Contains(".png"));
  CHECK_THROWS_WITH(run_render({a, "--out", out, "--size", "0"}), Contains("--size: expected 16..4096 pixels, got 0"));
  CHECK_THROWS_WITH(run_render({a, "--out", out, "--view", "top"}),
                    Contains("--view") && Contains("three_quarter, side or both"));
  CHECK_THROWS_WITH(run_render({a, a, "--out", out, "--captions", "only-one"}), Contains("1 captions for 2 meshes"));
  CHECK_THROWS_WITH(run_render({a, a, "--out", out, "--columns", "0"}), Contains("--columns"));
  CHECK_THROWS_WITH(run_render({(dir / "missing.obj").string(), "--out", out}), Contains("missing.obj"));
}
