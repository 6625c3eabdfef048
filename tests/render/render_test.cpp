#include "render/render.h"

#include <stb/stb_image.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <memory>

#include "core/error.h"
#include "test_support.h"

using namespace retarget;
using Catch::Contains;
using View = RenderOptions::View;

namespace {

// Squares facing +z (counter-clockwise seen from +z), or -z with flipped = true, in one mesh:
// each row of `squares` is x0, y0, x1, y1, z.
Mesh squares(const std::vector<std::array<double, 5>>& squares, bool flipped = false) {
  Positions V(4 * squares.size(), 3);
  Triangles T(2 * squares.size(), 3);
  for (size_t k = 0; k < squares.size(); ++k) {
    const auto [x0, y0, x1, y1, z] = squares[k];
    V.block<4, 3>(4 * k, 0) << x0, y0, z, x1, y0, z, x1, y1, z, x0, y1, z;
    const int a = static_cast<int>(4 * k);
    T.row(2 * k) << a, a + 1, a + 2;
    T.row(2 * k + 1) << a, a + 2, a + 3;
    if (flipped) T.block<2, 2>(2 * k, 1) = T.block<2, 2>(2 * k, 1).rowwise().reverse().eval();
  }
  return mesh_from_triangles(V, T);
}

Eigen::Vector3i at(const Image& image, int x, int y) {
  const uint8_t* p = image.pixel(x, y);
  return {p[0], p[1], p[2]};
}

bool is_background(const Image& image, int x, int y, const RenderOptions& options = {}) {
  return at(image, x, y) == (options.background * 255).array().round().cast<int>().matrix();
}

// Columns (or rows) holding at least one foreground pixel: first and last, -1 if none.
std::pair<int, int> foreground_span(const Image& image, bool columns) {
  int first = -1, last = -1;
  const int n = columns ? image.width : image.height, m = columns ? image.height : image.width;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < m; ++j)
      if (!(columns ? is_background(image, i, j) : is_background(image, j, i))) {
        if (first < 0) first = i;
        last = i;
        break;
      }
  return {first, last};
}

}  // namespace

TEST_CASE("a square facing the camera fills the centre and leaves the corners empty", "[render]") {
  RenderOptions options;
  options.width = 96;
  options.height = 64;
  const Image image = render(squares({{{0, 0, 2, 2, 0}}}), options);
  REQUIRE(image.width == 96);
  REQUIRE(image.height == 64);
  REQUIRE(image.rgb.size() == 96 * 64 * 3);
  CHECK_FALSE(is_background(image, 48, 32));
  for (auto [x, y] : {std::pair{0, 0}, {95, 0}, {0, 63}, {95, 63}, {10, 32}, {85, 32}})
    CHECK(is_background(image, x, y));
  // Framed to fill the height minus the 5% margins: rows 3..60 (of 64).
  const auto [top, bottom] = foreground_span(image, false);
  CHECK(top == Approx(3.2).margin(1));
  CHECK(bottom == Approx(60.8).margin(1));
}

TEST_CASE("a mesh appears where it is in a shared frame: left is left, up is up", "[render]") {
  RenderOptions options;
  options.width = options.height = 64;
  options.frame = Eigen::AlignedBox3d(Eigen::Vector3d(-3, -3, -1), Eigen::Vector3d(3, 3, 1));
  const Image left = render(squares({{{-3, -0.5, -2, 0.5, 0}}}), options);
  const auto [first, last] = foreground_span(left, true);
  CHECK(first >= 0);
  CHECK(last < 16);
  const Image up = render(squares({{{-0.5, 2, 0.5, 3, 0}}}), options);
  const auto [top, bottom] = foreground_span(up, false);
  CHECK(top >= 0);
  CHECK(bottom < 16);
}

TEST_CASE("the z-buffer shows the nearer surface whatever the drawing order", "[render]") {
  // A big red square at z = 0 and a small blue one in front of its centre at z = 1.
  for (bool near_first : {false, true}) {
    INFO("near square drawn first: " << near_first);
    const std::array<double, 5> far{-2, -2, 2, 2, 0}, near{-0.5, -0.5, 0.5, 0.5, 1};
    const Mesh mesh = near_first ? squares({near, far}) : squares({far, near});
    VertexColours colours(8, 3);
    const Eigen::RowVector3f red(0.9f, 0.1f, 0.1f), blue(0.1f, 0.1f, 0.9f);
    for (int i = 0; i < 8; ++i) colours.row(i) = (i < 4) == near_first ? blue : red;
    RenderOptions options;
    options.width = options.height = 64;
    const Image image = render(mesh, mesh.vertices, options, colours);
    const Eigen::Vector3i centre = at(image, 32, 32), rim = at(image, 8, 32);
    CHECK(centre.z() > 2 * centre.x());  // blue in the overlap
    CHECK(rim.x() > 2 * rim.z());        // red where only the far square is
  }
}

TEST_CASE("views turn the camera about +y towards +x", "[render]") {
  // A sphere red on its +x half, blue on its -x half.
  const Mesh sphere = uv_sphere(24, 48);
  VertexColours colours(sphere.vertex_count(), 3);
  for (int i = 0; i < sphere.vertex_count(); ++i)
    colours.row(i) =
        sphere.vertices(i, 0) > 0 ? Eigen::RowVector3f(0.9f, 0.1f, 0.1f) : Eigen::RowVector3f(0.1f, 0.1f, 0.9f);
  RenderOptions options;
  options.width = options.height = 64;
  const Image front = render(sphere, sphere.vertices, options, colours);
  CHECK(at(front, 16, 32).z() > at(front, 16, 32).x());  // -x on the left
  CHECK(at(front, 48, 32).x() > at(front, 48, 32).z());
  options.view = View::side;
  const Image side = render(sphere, sphere.vertices, options, colours);
  CHECK(at(side, 32, 32).x() > 2 * at(side, 32, 32).z());  // looking at the +x side
  options.yaw_deg = -90;
  const Image other_side = render(sphere, sphere.vertices, options, colours);
  CHECK(at(other_side, 32, 32).z() > 2 * at(other_side, 32, 32).x());
}

TEST_CASE("back faces are drawn, darker than front faces", "[render]") {
  RenderOptions options;
  options.width = options.height = 32;
  const Eigen::Vector3i front = at(render(squares({{{0, 0, 1, 1, 0}}}), options), 16, 16);
  const Eigen::Vector3i back = at(render(squares({{{0, 0, 1, 1, 0}}}, true), options), 16, 16);
  CHECK_FALSE(is_background(render(squares({{{0, 0, 1, 1, 0}}}, true), options), 16, 16));
  CHECK(back.sum() < 0.8 * front.sum());
}

TEST_CASE("a turntable frame keeps one scale at every yaw", "[render]") {
  // An ellipsoid 4 wide, 2 tall, 1 deep: framed per view, its height in pixels changes with yaw.
  Mesh ellipsoid = uv_sphere(16, 32);
  ellipsoid.vertices = ellipsoid.vertices * Eigen::Vector3d(2, 1, 0.5).asDiagonal();
  RenderOptions options;
  options.width = options.height = 80;
  auto height_at = [&](double yaw) {
    options.yaw_deg = yaw;
    const auto [top, bottom] = foreground_span(render(ellipsoid, options), false);
    return bottom - top;
  };
  CHECK(height_at(90) > height_at(0) + 10);
  options.turntable_frame = true;
  CHECK(height_at(90) == height_at(0));
  CHECK(height_at(35) == height_at(0));
}

TEST_CASE("a turntable strip holds the frames from -yaw to +yaw side by side", "[render]") {
  Mesh ellipsoid = uv_sphere(12, 24);
  ellipsoid.vertices = ellipsoid.vertices * Eigen::Vector3d(2, 1, 0.5).asDiagonal();
  RenderOptions options;
  options.width = 40;
  options.height = 30;
  const Image strip = render_turntable(ellipsoid, ellipsoid.vertices, 5, 60, options);
  CHECK(strip.width == 5 * 40);
  CHECK(strip.height == 30);
  // Frame f is the picture at yaw -60 + 30 f, framed as a turntable.
  options.turntable_frame = true;
  for (int f = 0; f < 5; ++f) {
    options.yaw_deg = -60.0 + 30.0 * f;
    const Image one = render(ellipsoid, options);
    bool same = true;
    for (int y = 0; y < 30 && same; ++y)
      for (int x = 0; x < 40 && same; ++x)
        for (int c = 0; c < 3; ++c) same = same && one.pixel(x, y)[c] == strip.pixel(40 * f + x, y)[c];
    INFO("frame " << f);
    CHECK(same);
  }
  // The camera moves: the first and the middle frame differ.
  int differ = 0;
  for (int y = 0; y < 30; ++y)
    for (int x = 0; x < 40; ++x) differ += at(strip, x, y) != at(strip, 2 * 40 + x, y);
  CHECK(differ > 20);
  CHECK_THROWS_WITH(render_turntable(ellipsoid, ellipsoid.vertices, 0, 30, options),
                    Catch::Contains("turntable.frames"));
  CHECK_THROWS_WITH(render_turntable(ellipsoid, ellipsoid.vertices, 3, 200, options),
                    Catch::Contains("turntable.max_yaw_deg"));
  // In memory as PNG: the signature and a non-trivial size.
  const std::string png = encode_png(strip);
  CHECK(png.substr(1, 3) == "PNG");
  CHECK(png.size() > 100);
  CHECK_THROWS_WITH(encode_png(Image{}, "nothing.png"), Catch::Contains("nothing.png"));
}

TEST_CASE("the wireframe overlay darkens the polygon edges", "[render]") {
  const Mesh grid = quad_grid(4, 4, 1, 1);
  RenderOptions options;
  options.width = options.height = 64;
  const Image plain = render(grid, options);
  options.wireframe_overlay = true;
  const Image wired = render(grid, options);
  int darker = 0;
  for (size_t i = 0; i < plain.rgb.size(); ++i) darker += wired.rgb[i] + 20 < plain.rgb[i];
  CHECK(darker > 3 * 5 * 40);  // at least 5 lines of ~40 pixels
}

TEST_CASE("a 11k-triangle sphere renders flat and smooth with every option combination", "[render]") {
  const Mesh sphere = uv_sphere(60, 100);
  for (bool smooth : {true, false})
    for (int supersample : {1, 3}) {
      RenderOptions options;
      options.smooth_shading = smooth;
      options.supersample = supersample;
      options.width = 100;
      options.height = 120;
      const Image image = render(sphere, options);
      CHECK_FALSE(is_background(image, 50, 60));
      CHECK(is_background(image, 1, 1));
    }
}

TEST_CASE("a PNG is written atomically and reads back with stb_image", "[render]") {
  RenderOptions options;
  options.width = 40;
  options.height = 30;
  const Image image = render(test::bumpy_patch(), options);
  const std::string path = (test::scratch_dir("render_png") / "sub" / "patch.png").string();
  write_png(path, image);
  std::ifstream in(path, std::ios::binary);
  char signature[8] = {};
  in.read(signature, 8);
  CHECK(std::string(signature, 8) == std::string("\x89PNG\r\n\x1a\n", 8));
  int width = 0, height = 0, channels = 0;
  uint8_t* pixels = stbi_load(path.c_str(), &width, &height, &channels, 3);
  REQUIRE(pixels != nullptr);
  CHECK(width == 40);
  CHECK(height == 30);
  CHECK(std::equal(image.rgb.begin(), image.rgb.end(), pixels));
  stbi_image_free(pixels);

  // A path below a regular file cannot be created.
  CHECK_THROWS_WITH(write_png(path + "/x.png", image), Contains("patch.png"));
  CHECK_THROWS_WITH(write_png(path, Image()), Contains("cannot write a 0 x 0 image"));
}

TEST_CASE("a grid has one cell per mesh, views side by side, captions underneath", "[render]") {
  const auto mesh = std::make_shared<const Mesh>(test::bumpy_patch(12));
  GridOptions options;
  options.render.width = 48;
  options.render.height = 40;
  options.views = {View::front, View::three_quarter};
  std::vector<GridCell> cells(3, GridCell{mesh, {}, {}, "abc"});
  cells[1].vertices = mesh->vertices * 1.5;  // an "expression": bigger in a shared frame
  cells[2].caption = "";
  const int band = text_band_height(options.text_scale);
  CHECK(band == 32);

  const Image grid = render_grid(cells, 2, options);
  CHECK(grid.width == 2 * 2 * 48);
  CHECK(grid.height == 2 * (40 + band));
  // Dark caption pixels in the band under cells 0 and 1, none under cell 2.
  auto dark_in = [&](int x0, int y0, int w, int h) {
    int dark = 0;
    for (int y = y0; y < y0 + h; ++y)
      for (int x = x0; x < x0 + w; ++x) dark += at(grid, x, y).maxCoeff() < 50;
    return dark;
  };
  CHECK(dark_in(0, 40, 96, band) > 20);
  CHECK(dark_in(96, 40, 96, band) > 20);
  CHECK(dark_in(0, 2 * 40 + band, 96, band) == 0);
  CHECK(dark_in(0, 0, 96, 40) == 0);  // no text over the pictures
  // A shared frame: the unscaled mesh does not fill its picture, the scaled one does.
  // The frame is the scaled mesh's box [0, 3]^2: 12 pixels per unit around (1.5, 1.5).
  CHECK(is_background(grid, 36, 20, options.render));
  CHECK_FALSE(is_background(grid, 96 + 36, 20, options.render));
  CHECK_FALSE(is_background(grid, 20, 20, options.render));

  options.title = "Title";
  options.share_frame = false;
  cells[0].caption = cells[1].caption = "";
  const Image titled = render_grid(cells, 5, options);  // columns beyond the cell count are dropped
  CHECK(titled.width == 3 * 2 * 48);
  CHECK(titled.height == band + 40);
}

TEST_CASE("captions too wide for their cell are cut", "[render]") {
  GridOptions options;
  options.render.width = options.render.height = 32;
  const auto mesh = std::make_shared<const Mesh>(test::bumpy_patch(6));
  const Image grid = render_grid({GridCell{mesh, {}, {}, "a very long caption for a small cell"}}, 1, options);
  CHECK(grid.width == 32);
  CHECK(text_width("abc", 2) == 2 * text_width("abc", 1));
}

TEST_CASE("hconcat and vconcat pad with the background", "[render]") {
  const Eigen::Vector3f white(1, 1, 1), black(0, 0, 0);
  const Image a(3, 2, black), b(4, 5, black);
  const Image h = hconcat({a, b}, white), v = vconcat({a, b}, white);
  CHECK((h.width == 7 && h.height == 5));
  CHECK((v.width == 4 && v.height == 7));
  CHECK(at(h, 0, 4) == Eigen::Vector3i(255, 255, 255));
  CHECK(at(h, 6, 4) == Eigen::Vector3i(0, 0, 0));
  CHECK(at(v, 3, 0) == Eigen::Vector3i(255, 255, 255));
}

TEST_CASE("bad options and inputs throw messages naming them", "[render]") {
  const Mesh mesh = test::bumpy_patch(4);
  using Edit = std::function<void(RenderOptions&)>;
  const std::vector<std::pair<Edit, std::string>> table = {
      {[](RenderOptions& o) { o.width = 0; }, "render.width: expected 1..8192 pixels, got 0"},
      {[](RenderOptions& o) { o.height = 9000; }, "render.height"},
      {[](RenderOptions& o) { o.margin = 0.5; }, "render.margin"},
      {[](RenderOptions& o) { o.pitch_deg = 90; }, "render.pitch_deg"},
      {[](RenderOptions& o) { o.yaw_deg = std::nan(""); }, "render.yaw_deg"},
      {[](RenderOptions& o) { o.supersample = 0; }, "render.supersample"},
      {[](RenderOptions& o) { o.width = o.height = 8192, o.supersample = 2; }, "more than 2^26 samples"},
      {[](RenderOptions& o) { o.colour.x() = 2; }, "render.colour"},
      {[](RenderOptions& o) { o.background.y() = -1; }, "render.background"},
      {[](RenderOptions& o) { o.frame = Eigen::AlignedBox3d(); }, "render.frame"},
  };
  for (const auto& [edit, message] : table) {
    RenderOptions options;
    edit(options);
    CHECK_THROWS_WITH(render(mesh, options), Contains(message));
  }
  CHECK_THROWS_WITH(render(mesh, Positions::Zero(3, 3)), Contains("3 positions given for a mesh of 25 vertices"));
  CHECK_THROWS_WITH(render(mesh, mesh.vertices, {}, VertexColours::Zero(2, 3)), Contains("2 vertex colours"));
  CHECK_THROWS_WITH(parse_view("sideways", "--view"), Contains("--view") && Contains("three_quarter"));
  CHECK(parse_view("three_quarter", "x") == View::three_quarter);

  GridOptions grid;
  GridCell cell;
  cell.mesh = std::make_shared<const Mesh>(mesh);
  CHECK_THROWS_WITH(render_grid({}, 1, grid), Contains("no cells"));
  CHECK_THROWS_WITH(render_grid({cell}, 0, grid), Contains("grid.columns"));
  CHECK_THROWS_WITH(render_grid({GridCell()}, 1, grid), Contains("grid cell 0"));
  grid.views.clear();
  CHECK_THROWS_WITH(render_grid({cell}, 1, grid), Contains("grid.views"));
  grid.views = {View::front};
  grid.text_scale = 0;
  CHECK_THROWS_WITH(render_grid({cell}, 1, grid), Contains("grid.text_scale"));
  grid.text_scale = 1;
  grid.render.width = -5;
  CHECK_THROWS_WITH(render_grid({cell}, 1, grid), Contains("render.width"));
}
