#include "render/render.h"

#include <fmt/format.h>
#include <stb_image_write.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/parallel_for.h"

// stb_easy_font is a header of static functions; we use two of them.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wunused-function"
#pragma GCC diagnostic ignored "-Wsign-compare"
#include <stb_easy_font.h>
#pragma GCC diagnostic pop

namespace retarget {

namespace {

using Vec3f = Eigen::Vector3f;
using Rows3f = Eigen::Matrix<float, Eigen::Dynamic, 3, Eigen::RowMajor>;

uint8_t to_byte(float v) { return static_cast<uint8_t>(std::clamp(v, 0.0f, 1.0f) * 255.0f + 0.5f); }

// Orthographic camera. Camera coordinates: x right, y up, z towards the viewer (larger is nearer).
struct Camera {
  Eigen::Matrix3d rotation;  // rows: the camera's x, y, z axes in the mesh frame
  Eigen::Vector3d centre;    // the mesh-frame point drawn at the image centre
  double scale = 1;          // pixels per mesh unit
};

Camera make_camera(const RenderOptions& o, const Eigen::AlignedBox3d& box, int width, int height) {
  static const double view_yaw[] = {0, 35, 90};
  const double yaw = o.yaw_deg.value_or(view_yaw[static_cast<int>(o.view)]) * M_PI / 180;
  const double pitch = o.pitch_deg.value_or(0) * M_PI / 180;
  const Eigen::Vector3d towards(std::sin(yaw) * std::cos(pitch), std::sin(pitch), std::cos(yaw) * std::cos(pitch));
  const Eigen::Vector3d right(std::cos(yaw), 0, -std::sin(yaw));
  Camera camera;
  camera.rotation.row(0) = right;
  camera.rotation.row(1) = towards.cross(right);
  camera.rotation.row(2) = towards;
  camera.centre = box.center();
  // Half extents on screen of what must fit: the box's corners, or the cylinder about +y that
  // holds the box at every yaw.
  const Eigen::Vector3d half = box.sizes() / 2;
  double hx, hy;
  if (o.turntable_frame) {
    hx = std::hypot(half.x(), half.z());
    hy = half.y() * std::cos(pitch) + hx * std::abs(std::sin(pitch));
  } else {
    hx = camera.rotation.row(0).cwiseAbs().dot(half);
    hy = camera.rotation.row(1).cwiseAbs().dot(half);
  }
  double scale = std::numeric_limits<double>::infinity();
  if (hx > 0) scale = std::min(scale, width * (1 - 2 * o.margin) / (2 * hx));
  if (hy > 0) scale = std::min(scale, height * (1 - 2 * o.margin) / (2 * hy));
  camera.scale = std::isfinite(scale) && scale > 0 ? scale : 1;  // a single point: any scale
  return camera;
}

// Samples are at x + 0.5 for x = 0 .. n - 1: the first at or after v, the last at or before v
// (clamped to the image, so that a huge v cannot overflow an int).
int first_sample(double v, int n) { return static_cast<int>(std::clamp(std::ceil(v - 0.5), 0.0, double(n))); }
int last_sample(double v, int n) { return static_cast<int>(std::clamp(std::floor(v - 0.5), -1.0, n - 1.0)); }

// A * x + B * y + C: an edge function, a barycentric coordinate or depth over the image.
struct Linear {
  double A, B, C;
  double operator()(double x, double y) const { return A * x + B * y + C; }
};

// Lights in camera coordinates (towards the light), weights of the shading terms.
struct Lights {
  Vec3f key = Vec3f(-0.55f, 0.6f, 0.75f).normalized();
  Vec3f fill = Vec3f(0.75f, 0.05f, 0.6f).normalized();
  Vec3f half_key = (key + Vec3f::UnitZ()).normalized();  // Blinn-Phong half vector
  float ambient = 0.22f, key_weight = 0.72f, fill_weight = 0.28f, specular = 0.10f;
  float back_face = 0.45f;  // back faces are drawn this much as bright
};

Vec3f shade(Vec3f n, bool back, const Vec3f& albedo, const Lights& l) {
  const float length = n.norm();
  n = length > 0 ? Vec3f(n / length) : Vec3f::UnitZ();
  if (back) n = -n;
  float s = std::max(0.0f, n.dot(l.half_key));
  s *= s, s *= s, s *= s, s *= s;  // s^16
  const float light =
      l.ambient + l.key_weight * std::max(0.0f, n.dot(l.key)) + l.fill_weight * std::max(0.0f, n.dot(l.fill));
  const Vec3f c = albedo * light + Vec3f::Constant(l.specular * s);
  return back ? Vec3f(c * l.back_face) : c;
}

// Printable ASCII only: stb_easy_font indexes its tables by (c - 32).
std::string printable(const std::string& text) {
  std::string clean = text;
  for (char& c : clean)
    if (c < 32 || c > 126) c = '?';
  return clean;
}

// `text`, cut and ended with "..." if needed so that it is at most max_width pixels wide.
std::string fit_text(const std::string& text, int max_width, int scale) {
  if (text_width(text, scale) <= max_width) return text;
  std::string cut = text;
  while (!cut.empty() && text_width(cut + "...", scale) > max_width) cut.pop_back();
  return cut + "...";
}

// One sample of the supersampled grid (kept small: the visibility pass is memory-bound).
struct Sample {
  float depth = -std::numeric_limits<float>::infinity();  // camera z, larger is nearer
  int triangle = -1;                                      // -1: background
};

using ScreenPoints = Eigen::Matrix<double, Eigen::Dynamic, 2, Eigen::RowMajor>;

// Per sample (W x H, row-major), 1 where a polygon's edge is drawn: `S` the vertices' sample
// coordinates (y down), `P` their camera coordinates; an edge point counts unless it lies more
// than `tolerance` (camera units) behind the nearest surface there.
std::vector<uint8_t> wireframe(const Polygons& faces, const ScreenPoints& S, const Rows3f& P,
                               const std::vector<Sample>& buffer, int W, int H, float tolerance) {
  std::vector<uint8_t> wire(buffer.size(), 0);
  for (int f = 0; f < faces.size(); ++f)
    for (int k = 0, d = faces.degree(f); k < d; ++k) {
      const int u = faces.begin(f)[k], v = faces.begin(f)[(k + 1) % d];
      const double length = std::max(std::abs(S(v, 0) - S(u, 0)), std::abs(S(v, 1) - S(u, 1)));
      if (!std::isfinite(length)) continue;
      const int steps = static_cast<int>(std::min<double>(std::ceil(length) + 1, 4 * (W + H)));
      for (int s = 0; s <= steps; ++s) {
        const double a = static_cast<double>(s) / steps;
        const int x = static_cast<int>(std::floor(S(u, 0) + a * (S(v, 0) - S(u, 0))));
        const int y = static_cast<int>(std::floor(S(u, 1) + a * (S(v, 1) - S(u, 1))));
        if (x < 0 || y < 0 || x >= W || y >= H) continue;
        const size_t i = static_cast<size_t>(y) * W + x;
        if (P(u, 2) + a * (P(v, 2) - P(u, 2)) >= buffer[i].depth - tolerance) wire[i] = 1;
      }
    }
  return wire;
}

}  // namespace

Image::Image(int width, int height, const Eigen::Vector3f& colour)
    : width(width), height(height), rgb(3 * static_cast<size_t>(width) * height) {
  const uint8_t c[3] = {to_byte(colour.x()), to_byte(colour.y()), to_byte(colour.z())};
  for (size_t i = 0; i < rgb.size(); i += 3) std::copy(c, c + 3, rgb.begin() + i);
}

Eigen::AlignedBox3d frame_box(const Positions& V) {
  if (V.rows() == 0) return {};
  return {V.colwise().minCoeff().transpose(), V.colwise().maxCoeff().transpose()};
}

void RenderOptions::validate() const {
  auto fail = [](const char* name, const std::string& what) { throw Error(std::string("render.") + name, what); };
  if (width < 1 || width > 8192) fail("width", fmt::format("expected 1..8192 pixels, got {}", width));
  if (height < 1 || height > 8192) fail("height", fmt::format("expected 1..8192 pixels, got {}", height));
  if (yaw_deg && !std::isfinite(*yaw_deg)) fail("yaw_deg", fmt::format("expected a finite angle, got {}", *yaw_deg));
  if (pitch_deg && !(std::abs(*pitch_deg) <= 89))
    fail("pitch_deg", fmt::format("expected degrees in [-89, 89], got {}", *pitch_deg));
  if (frame && (frame->isEmpty() || !frame->min().allFinite() || !frame->max().allFinite()))
    fail("frame", "expected a non-empty box with finite corners");
  if (!(margin >= 0 && margin <= 0.45)) fail("margin", fmt::format("expected a fraction in [0, 0.45], got {}", margin));
  auto check_colour = [&](const char* name, const Eigen::Vector3f& c) {
    if (!((c.array() >= 0).all() && (c.array() <= 1).all()))
      fail(name, fmt::format("expected RGB components in [0, 1], got ({}, {}, {})", c.x(), c.y(), c.z()));
  };
  check_colour("colour", colour);
  check_colour("background", background);
  if (supersample < 1 || supersample > 4) fail("supersample", fmt::format("expected 1..4, got {}", supersample));
  // 8 bytes per sample: keep a render below 512 MB.
  const double samples = double(width) * height * supersample * supersample;
  if (samples > (1 << 26))
    fail("supersample", fmt::format("{} x {} pixels with {} x {} samples each is more than 2^26 samples; lower one",
                                    width, height, supersample, supersample));
}

const char* view_name(RenderOptions::View view) {
  switch (view) {
    case RenderOptions::View::front:
      return "front";
    case RenderOptions::View::three_quarter:
      return "three_quarter";
    case RenderOptions::View::side:
      return "side";
  }
  return "?";
}

RenderOptions::View parse_view(const std::string& name, const std::string& where) {
  for (auto view : {RenderOptions::View::front, RenderOptions::View::three_quarter, RenderOptions::View::side})
    if (name == view_name(view)) return view;
  throw Error(where, fmt::format("unknown view \"{}\"; expected front, three_quarter or side", name));
}

Eigen::Vector3d project_to_image(const Positions& vertices, const RenderOptions& options,
                                 const Eigen::Vector3d& point) {
  options.validate();
  const Camera camera =
      make_camera(options, options.frame.value_or(frame_box(vertices)), options.width, options.height);
  const Eigen::Vector3d p = camera.rotation * (point - camera.centre);
  return {options.width / 2.0 + camera.scale * p.x(), options.height / 2.0 - camera.scale * p.y(), p.z()};
}

Image render(const Mesh& topology, const Positions& vertices, const RenderOptions& options,
             const VertexColours& colours) {
  options.validate();
  const std::string where = topology.source.empty() ? "render" : topology.source;
  const int n = static_cast<int>(vertices.rows());
  if (n != topology.vertex_count())
    throw Error(where, fmt::format("{} positions given for a mesh of {} vertices", n, topology.vertex_count()));
  if (n == 0 || topology.triangle_count() == 0) throw Error(where, "nothing to render: the mesh has no triangles");
  if (colours.rows() != 0 && colours.rows() != n)
    throw Error(where, fmt::format("{} vertex colours given for a mesh of {} vertices", colours.rows(), n));

  // Everything below works on the supersampled grid: W x H samples.
  const int ss = options.supersample, W = options.width * ss, H = options.height * ss;
  const Camera camera = make_camera(options, options.frame.value_or(frame_box(vertices)), W, H);
  Rows3f P(n, 3);        // camera coordinates
  ScreenPoints S(n, 2);  // samples, y down
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d p = camera.rotation * (vertices.row(i).transpose() - camera.centre);
    P.row(i) = p.cast<float>().transpose();
    S.row(i) << W / 2.0 + camera.scale * p.x(), H / 2.0 - camera.scale * p.y();
  }
  const Triangles& T = topology.triangles;
  const int triangle_count = static_cast<int>(T.rows());
  Rows3f face_normal(triangle_count, 3), vertex_normal = Rows3f::Zero(n, 3);
  for (int t = 0; t < triangle_count; ++t) {
    const Vec3f a = P.row(T(t, 0)), b = P.row(T(t, 1)), c = P.row(T(t, 2));
    face_normal.row(t) = (b - a).cross(c - a).transpose();  // length: twice the area
    for (int k = 0; k < 3; ++k) vertex_normal.row(T(t, k)) += face_normal.row(t);
  }

  // Visibility: the nearest triangle per sample (kept small: the pass is memory-bound), and per
  // triangle the barycentric coordinates of its corners 1 and 2 as functions of the sample.
  const size_t samples = static_cast<size_t>(W) * H;
  std::vector<Sample> buffer(samples);
  std::vector<std::array<Linear, 2>> barycentric(triangle_count);
  for (int t = 0; t < triangle_count; ++t) {
    const int i0 = T(t, 0), i1 = T(t, 1), i2 = T(t, 2);
    const double x0 = S(i0, 0), y0 = S(i0, 1), x1 = S(i1, 0), y1 = S(i1, 1), x2 = S(i2, 0), y2 = S(i2, 1);
    const double area = (x1 - x0) * (y2 - y0) - (y1 - y0) * (x2 - x0);
    if (!(std::abs(area) > 1e-12)) continue;  // degenerate on screen (or not finite)
    // Sample (x + 0.5, y + 0.5) is inside when all three normalised edge functions are >= 0.
    const int xmin = first_sample(std::min({x0, x1, x2}), W), xmax = last_sample(std::max({x0, x1, x2}), W);
    const int ymin = first_sample(std::min({y0, y1, y2}), H), ymax = last_sample(std::max({y0, y1, y2}), H);
    if (xmin > xmax || ymin > ymax) continue;
    // Edge function of (u -> v) at p, divided by the area: the barycentric coordinate of the
    // third corner.
    auto edge = [area](double ux, double uy, double vx, double vy) {
      return Linear{-(vy - uy) / area, (vx - ux) / area, ((vy - uy) * ux - (vx - ux) * uy) / area};
    };
    const Linear e[3] = {edge(x1, y1, x2, y2), edge(x2, y2, x0, y0), edge(x0, y0, x1, y1)};
    barycentric[t] = {e[1], e[2]};
    const double z0 = P(i0, 2), z1 = P(i1, 2), z2 = P(i2, 2);
    const Linear z{e[0].A * z0 + e[1].A * z1 + e[2].A * z2, e[0].B * z0 + e[1].B * z1 + e[2].B * z2,
                   e[0].C * z0 + e[1].C * z1 + e[2].C * z2};
    for (int y = ymin; y <= ymax; ++y) {
      const double py = y + 0.5;
      // Along a row each edge function is linear in x: keep the span where all three are >= 0.
      double lo = xmin + 0.5, hi = xmax + 0.5;
      for (const Linear& f : e) {
        const double at_zero = f.B * py + f.C;
        if (f.A > 0)
          lo = std::max(lo, -at_zero / f.A);
        else if (f.A < 0)
          hi = std::min(hi, -at_zero / f.A);
        else if (at_zero < 0)
          hi = -1;
      }
      const int x_end = last_sample(hi, W);
      const double row_z = z.B * py + z.C;
      for (int x = first_sample(lo, W); x <= x_end; ++x) {
        const double px = x + 0.5;
        const float depth_here = static_cast<float>(z.A * px + row_z);
        const size_t s = static_cast<size_t>(y) * W + x;
        Sample& sample = buffer[s];
        if (depth_here <= sample.depth) continue;
        sample = {depth_here, t};
      }
    }
  }

  // Wireframe: the polygons' edges where they are not behind the surface (a depth tolerance
  // of two samples' width keeps the lines on their own faces).
  std::vector<uint8_t> wire;
  if (options.wireframe_overlay)
    wire = wireframe(topology.faces, S, P, buffer, W, H, static_cast<float>(2 / camera.scale));

  // Shade each sample and average the ss x ss samples of each pixel; a pixel whose samples all
  // see one triangle (most of them) is shaded once, at its centre, as multisampling does.
  const Lights lights;
  auto surface = [&](int t, double px, double py) -> Vec3f {  // px, py: sample coordinates
    const int i0 = T(t, 0), i1 = T(t, 1), i2 = T(t, 2);
    const float w1 = static_cast<float>(barycentric[t][0](px, py));
    const float w2 = static_cast<float>(barycentric[t][1](px, py)), w0 = 1 - w1 - w2;
    const Vec3f normal =
        options.smooth_shading
            ? Vec3f(w0 * vertex_normal.row(i0) + w1 * vertex_normal.row(i1) + w2 * vertex_normal.row(i2))
            : Vec3f(face_normal.row(t));
    const Vec3f albedo = colours.rows() == 0
                             ? options.colour
                             : Vec3f(w0 * colours.row(i0) + w1 * colours.row(i1) + w2 * colours.row(i2));
    return shade(normal, face_normal(t, 2) < 0, albedo, lights);
  };
  Image image(options.width, options.height, options.background);
  const float weight = 1.0f / (ss * ss);
  for (int y = 0; y < options.height; ++y)
    for (int x = 0; x < options.width; ++x) {
      const size_t first = static_cast<size_t>(y * ss) * W + x * ss;
      bool uniform = wire.empty();
      for (int sy = 0; sy < ss && uniform; ++sy)
        for (int sx = 0; sx < ss; ++sx) uniform &= buffer[first + sy * W + sx].triangle == buffer[first].triangle;
      Vec3f colour = Vec3f::Zero();
      if (uniform) {
        if (buffer[first].triangle < 0) continue;
        colour = surface(buffer[first].triangle, (x + 0.5) * ss, (y + 0.5) * ss);
      } else {
        for (int sy = 0; sy < ss; ++sy)
          for (int sx = 0; sx < ss; ++sx) {
            const size_t s = first + sy * W + sx;
            const int t = buffer[s].triangle;
            Vec3f c = t >= 0 ? surface(t, x * ss + sx + 0.5, y * ss + sy + 0.5) : options.background;
            if (!wire.empty() && wire[s]) c *= 0.3f;
            colour += c * weight;
          }
      }
      uint8_t* p = image.pixel(x, y);
      for (int k = 0; k < 3; ++k) p[k] = to_byte(colour[k]);
    }
  return image;
}

Image render(const Mesh& mesh, const RenderOptions& options) { return render(mesh, mesh.vertices, options); }

Image render_turntable(const Mesh& topology, const Positions& vertices, int frames, double max_yaw_deg,
                       RenderOptions options, const VertexColours& colours) {
  if (frames < 1 || frames > 64) throw Error("turntable.frames", fmt::format("expected 1..64, got {}", frames));
  if (!(max_yaw_deg >= 0 && max_yaw_deg <= 180))
    throw Error("turntable.max_yaw_deg", fmt::format("expected 0..180 degrees, got {}", max_yaw_deg));
  options.turntable_frame = true;
  options.yaw_deg = 0.0;
  options.validate();
  // Frames are independent: render them on the machine's cores.
  std::vector<Image> pictures(static_cast<size_t>(frames));
  parallel_for(frames, [&](int f) {
    RenderOptions o = options;
    o.yaw_deg = frames == 1 ? 0.0 : -max_yaw_deg + 2.0 * max_yaw_deg * f / (frames - 1);
    pictures[static_cast<size_t>(f)] = render(topology, vertices, o, colours);
  });
  return hconcat(pictures, options.background);
}

void GridOptions::validate() const {
  render.validate();
  if (views.empty()) throw Error("grid.views", "expected at least one view");
  if (text_scale < 1 || text_scale > 8)
    throw Error("grid.text_scale", fmt::format("expected 1..8, got {}", text_scale));
  if (!((text_colour.array() >= 0).all() && (text_colour.array() <= 1).all()))
    throw Error("grid.text_colour", "expected RGB components in [0, 1]");
}

int text_band_height(int text_scale) { return 16 * text_scale; }

Image render_grid(const std::vector<GridCell>& cells, int columns, const GridOptions& options) {
  options.validate();
  if (cells.empty()) throw Error("render_grid", "no cells to draw");
  if (columns < 1) throw Error("grid.columns", fmt::format("expected at least 1, got {}", columns));
  columns = std::min<int>(columns, static_cast<int>(cells.size()));
  auto positions = [](const GridCell& cell) -> const Positions& {
    return cell.vertices.rows() ? cell.vertices : cell.mesh->vertices;
  };
  RenderOptions render_options = options.render;
  Eigen::AlignedBox3d shared;
  for (size_t k = 0; k < cells.size(); ++k) {
    if (!cells[k].mesh) throw Error(fmt::format("grid cell {}", k), "has no mesh");
    shared.extend(frame_box(positions(cells[k])));
  }
  if (options.share_frame && !render_options.frame) render_options.frame = shared;

  const int scale = options.text_scale, w = render_options.width, h = render_options.height;
  const bool captions = std::any_of(cells.begin(), cells.end(), [](const GridCell& c) { return !c.caption.empty(); });
  const int caption_band = captions ? text_band_height(scale) : 0;
  const int title_band = options.title.empty() ? 0 : text_band_height(scale);
  const int cell_width = static_cast<int>(options.views.size()) * w, cell_height = h + caption_band;
  const int rows = (static_cast<int>(cells.size()) + columns - 1) / columns;
  Image grid(columns * cell_width, title_band + rows * cell_height, render_options.background);
  // The font's capitals are 7 of its 12-pixel line: this centres them in the 16-pixel band.
  const int text_top = 4 * scale;
  if (title_band) {
    const std::string title = fit_text(options.title, grid.width - 2 * scale, scale);
    draw_text(grid, (grid.width - text_width(title, scale)) / 2, text_top, title, scale, options.text_colour);
  }
  for (size_t k = 0; k < cells.size(); ++k) {
    const GridCell& cell = cells[k];
    const int x = static_cast<int>(k % columns) * cell_width,
              y = title_band + static_cast<int>(k / columns) * cell_height;
    for (size_t v = 0; v < options.views.size(); ++v) {
      render_options.view = options.views[v];
      blit(grid, render(*cell.mesh, positions(cell), render_options, cell.colours), x + static_cast<int>(v) * w, y);
    }
    const std::string caption = fit_text(cell.caption, cell_width - 2 * scale, scale);
    draw_text(grid, x + (cell_width - text_width(caption, scale)) / 2, y + h + text_top, caption, scale,
              options.text_colour);
  }
  return grid;
}

int text_width(const std::string& text, int scale) {
  std::string clean = printable(text);
  return stb_easy_font_width(clean.data()) * scale;
}

void draw_text(Image& image, int x, int y, const std::string& text, int scale, const Eigen::Vector3f& colour) {
  if (text.empty()) return;
  std::string clean = printable(text);
  // 4 vertices of 16 bytes (x, y, z floats, RGBA) per quad; no glyph has more than 30 quads.
  std::vector<char> buffer(clean.size() * 30 * 64 + 64);
  const int quads = stb_easy_font_print(0, 0, clean.data(), nullptr, buffer.data(), static_cast<int>(buffer.size()));
  const uint8_t c[3] = {to_byte(colour.x()), to_byte(colour.y()), to_byte(colour.z())};
  for (int q = 0; q < quads; ++q) {
    const float* corner0 = reinterpret_cast<const float*>(buffer.data() + 64 * q);
    const float* corner2 = reinterpret_cast<const float*>(buffer.data() + 64 * q + 32);
    const int left = std::max(0, x + static_cast<int>(std::lround(corner0[0] * scale)));
    const int top = std::max(0, y + static_cast<int>(std::lround(corner0[1] * scale)));
    const int right = std::min(image.width, x + static_cast<int>(std::lround(corner2[0] * scale)));
    const int bottom = std::min(image.height, y + static_cast<int>(std::lround(corner2[1] * scale)));
    for (int py = top; py < bottom; ++py)
      for (int px = left; px < right; ++px) std::copy(c, c + 3, image.pixel(px, py));
  }
}

void blit(Image& target, const Image& source, int x, int y) {
  const int left = std::max(0, x), right = std::min(target.width, x + source.width);
  if (left >= right) return;
  for (int row = std::max(0, y); row < std::min(target.height, y + source.height); ++row)
    std::copy(source.pixel(left - x, row - y), source.pixel(left - x, row - y) + 3 * (right - left),
              target.pixel(left, row));
}

Image hconcat(const std::vector<Image>& images, const Eigen::Vector3f& background) {
  int width = 0, height = 0;
  for (const Image& image : images) width += image.width, height = std::max(height, image.height);
  Image out(width, height, background);
  int x = 0;
  for (const Image& image : images) blit(out, image, x, 0), x += image.width;
  return out;
}

Image vconcat(const std::vector<Image>& images, const Eigen::Vector3f& background) {
  int width = 0, height = 0;
  for (const Image& image : images) width = std::max(width, image.width), height += image.height;
  Image out(width, height, background);
  int y = 0;
  for (const Image& image : images) blit(out, image, 0, y), y += image.height;
  return out;
}

std::string encode_png(const Image& image, const std::string& what) {
  if (image.width < 1 || image.height < 1 || image.rgb.size() != 3 * static_cast<size_t>(image.width) * image.height)
    throw Error(what, fmt::format("cannot write a {} x {} image with {} bytes as PNG", image.width, image.height,
                                  image.rgb.size()));
  std::string png;
  auto append = [](void* context, void* data, int size) {
    static_cast<std::string*>(context)->append(static_cast<const char*>(data), size);
  };
  if (!stbi_write_png_to_func(append, &png, image.width, image.height, 3, image.rgb.data(), 3 * image.width))
    throw Error(what, "PNG encoding failed");
  return png;
}

void write_png(const std::string& path, const Image& image) {
  const std::string png = encode_png(image, path);
  write_file_atomically(path,
                        [&](std::ostream& out) { out.write(png.data(), static_cast<std::streamsize>(png.size())); });
}

}  // namespace retarget
