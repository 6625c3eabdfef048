// `retarget render MESH... --out out.png`: one mesh in one view makes one picture; several
// meshes or views make a captioned grid (render/render.h does the drawing).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cxxopts.hpp>
#include <filesystem>
#include <iostream>
#include <set>

#include "cli/command_options.h"
#include "cli/commands.h"
#include "core/error.h"
#include "core/timer.h"
#include "geometry/mesh_io.h"
#include "render/render.h"

namespace retarget::cli {

namespace fs = std::filesystem;

namespace {

// Captions from file names: the stem ("jawOpen"), or folder/stem when stems repeat.
std::vector<std::string> default_captions(const std::vector<std::string>& paths) {
  std::vector<std::string> stems;
  for (const std::string& path : paths) stems.push_back(fs::path(path).stem().string());
  if (std::set<std::string>(stems.begin(), stems.end()).size() == stems.size()) return stems;
  for (size_t k = 0; k < paths.size(); ++k)
    stems[k] = (fs::path(paths[k]).parent_path().filename() / fs::path(paths[k]).stem()).string();
  return stems;
}

}  // namespace

int render_command(int argc, char** argv) {
  cxxopts::Options options(
      "retarget render",
      "Draw meshes to PNG (+y up, +z towards the viewer). One mesh in one view makes one picture;\n"
      "several meshes or --view both make a grid with a caption under each mesh.");
  options.add_options()("out", "PNG file to write", cxxopts::value<std::string>())(
      "view", "front, three_quarter, side, or both (front and three_quarter side by side)",
      cxxopts::value<std::string>()->default_value("front"))("size", "pixels per picture (square), 16..4096",
                                                             cxxopts::value<int>()->default_value("512"))(
      "columns", "meshes per grid row (default: a roughly square grid)", cxxopts::value<int>())(
      "captions", "comma-separated captions, one per mesh (default: the file names)",
      cxxopts::value<std::vector<std::string>>())(
      "share-frame",
      "one scale and centre for every mesh, so nothing jumps between pictures (default: on when all meshes "
      "have the same vertex count; --share-frame=false turns it off)",
      cxxopts::value<bool>())("title", "a line above the grid", cxxopts::value<std::string>())(
      "wireframe", "draw the polygon edges over the surface", cxxopts::value<bool>()->default_value("false"))(
      "meshes", "mesh files", cxxopts::value<std::vector<std::string>>());
  options.parse_positional({"meshes"});
  options.positional_help("MESH... --out OUT.png");
  const std::optional<cxxopts::ParseResult> parsed = parse_options(options, argc, argv);
  if (!parsed) return 0;
  const cxxopts::ParseResult& args = *parsed;
  if (!args.count("meshes")) throw Error("retarget render", "give at least one mesh file (see --help)");
  if (!args.count("out")) throw Error("retarget render", "give the picture to write with --out FILE.png");
  const std::vector<std::string> paths = args["meshes"].as<std::vector<std::string>>();
  const std::string out = args["out"].as<std::string>();
  if (fs::path(out).extension() != ".png") throw Error("--out " + out, "expected a file name ending in .png");
  const int size = args["size"].as<int>();
  if (size < 16 || size > 4096) throw Error("--size", fmt::format("expected 16..4096 pixels, got {}", size));
  const std::string view = args["view"].as<std::string>();
  std::vector<RenderOptions::View> views{RenderOptions::View::front, RenderOptions::View::three_quarter};
  if (view != "both") {
    try {
      views = {parse_view(view, "--view")};
    } catch (const Error&) {
      throw Error("--view", fmt::format("unknown view \"{}\"; expected front, three_quarter, side or both", view));
    }
  }
  std::vector<std::string> captions = default_captions(paths);
  if (args.count("captions")) {
    captions = args["captions"].as<std::vector<std::string>>();
    if (captions.size() != paths.size())
      throw Error("--captions", fmt::format("{} captions for {} meshes", captions.size(), paths.size()));
  }
  const int pictures_across = static_cast<int>(std::ceil(std::sqrt(double(paths.size() * views.size()))));
  const int columns = args.count("columns") ? args["columns"].as<int>()
                                            : std::max<int>(1, (pictures_across + views.size() - 1) / views.size());
  if (columns < 1) throw Error("--columns", fmt::format("expected at least 1, got {}", columns));

  Stopwatch clock;
  std::vector<GridCell> cells;
  for (size_t k = 0; k < paths.size(); ++k)
    cells.push_back({std::make_shared<const Mesh>(read_mesh(paths[k])), {}, {}, captions[k]});
  const double read_ms = clock.restart() * 1e3;
  GridOptions grid;
  grid.render.width = grid.render.height = size;
  grid.render.wireframe_overlay = args["wireframe"].as<bool>();
  grid.views = views;
  grid.share_frame = args.count("share-frame") ? args["share-frame"].as<bool>()
                                               : std::all_of(cells.begin(), cells.end(), [&](const GridCell& c) {
                                                   return c.mesh->vertex_count() == cells[0].mesh->vertex_count();
                                                 });
  if (args.count("title")) grid.title = args["title"].as<std::string>();

  Image image;
  if (cells.size() == 1 && views.size() == 1 && grid.title.empty()) {
    grid.render.view = views[0];
    image = render(*cells[0].mesh, grid.render);
  } else {
    image = render_grid(cells, columns, grid);
  }
  const double render_ms = clock.restart() * 1e3;
  write_png(out, image);
  std::cout << fmt::format("wrote {}: {} x {} pixels, {} mesh{} x {} view{}{}; read {:.0f} ms, rendered {:.0f} ms\n",
                           out, image.width, image.height, cells.size(), cells.size() == 1 ? "" : "es", views.size(),
                           views.size() == 1 ? "" : "s",
                           cells.size() > 1 && grid.share_frame ? ", one shared frame" : "", read_ms, render_ms);
  return 0;
}

}  // namespace retarget::cli
