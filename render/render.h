// Pictures of meshes without a GPU or a display: a software rasteriser (z-buffer, per-pixel
// shading, anti-aliasing by supersampling), captioned grids of pictures, and PNG output.
// Used by `retarget render`, the annotation tool's turntables and the reports' contact sheets.
//
// Frames: meshes are drawn in their own frame, +y up and +z towards the viewer (like the ICT
// face). The camera is orthographic; it orbits the frame box's centre by a yaw about +y
// (positive yaw moves the camera towards +x, the face's left) and a pitch (positive: from above).
// Images: 8-bit RGB, row 0 at the top, x to the right.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "geometry/mesh.h"

namespace retarget {

// A width x height RGB picture: rgb[3 * (y * width + x) + c], c = 0, 1, 2 for R, G, B; y = 0 is
// the top row.
struct Image {
  int width = 0, height = 0;
  std::vector<uint8_t> rgb;

  Image() = default;
  // colour: linear 0..1 RGB, stored as round(255 * colour).
  Image(int width, int height, const Eigen::Vector3f& colour);
  uint8_t* pixel(int x, int y) { return rgb.data() + 3 * (static_cast<size_t>(y) * width + x); }
  const uint8_t* pixel(int x, int y) const { return rgb.data() + 3 * (static_cast<size_t>(y) * width + x); }
};

// Per-vertex albedo: #V x 3 RGB in 0..1, interpolated across each triangle.
using VertexColours = Eigen::Matrix<float, Eigen::Dynamic, 3, Eigen::RowMajor>;

// The axis-aligned box around V (#V x 3, mesh units and frame): what the camera frames. Merge
// the boxes of several meshes (box.extend(other)) to give them one shared frame.
Eigen::AlignedBox3d frame_box(const Positions& V);

struct RenderOptions {
  enum class View { front, three_quarter, side };  // camera yaw 0, 35 and 90 degrees

  int width = 512, height = 512;  // pixels, 1..8192 each
  View view = View::front;
  // Override the view's camera angles, degrees (turntables): yaw about +y, towards +x; pitch in
  // [-89, 89], positive from above.
  std::optional<double> yaw_deg, pitch_deg;
  // What the camera frames: this box (mesh units and frame) instead of the mesh's own bounding
  // box, so the pictures of several meshes share one scale and centre (a grid of one face's
  // expressions). The box's corners as seen in this view fill the image minus the margin.
  std::optional<Eigen::AlignedBox3d> frame;
  // Frame the box as seen from every yaw (the vertical cylinder around it) so that the frames of
  // a turntable keep one scale and centre; off: framed tightly for this view.
  bool turntable_frame = false;
  double margin = 0.05;  // empty border on each side, a fraction of the width / height, in [0, 0.45]

  Eigen::Vector3f colour{0.80f, 0.74f, 0.70f};      // surface albedo, RGB 0..1 (a skin-ish grey)
  Eigen::Vector3f background{0.97f, 0.97f, 0.97f};  // RGB 0..1
  // Per-vertex normals interpolated and shaded per pixel (Phong); off: one normal per triangle.
  // Lights are fixed to the camera: a key light from the upper left, a fill from the right,
  // ambient and a little specular. Back faces (seen from behind, as inside an open mesh's mouth)
  // are lit with the flipped normal and drawn darker; nothing is culled.
  bool smooth_shading = true;
  bool wireframe_overlay = false;  // the mesh's own polygon edges, darkened, where visible
  // s x s samples per pixel, averaged (smooth edges), 1..4; at most 2^26 samples in all
  // (8192 x 8192 pixels, or 4096 x 4096 with 2 x 2 samples).
  int supersample = 2;

  // Throws retarget::Error naming the option ("render.width", ...) and what is wrong.
  void validate() const;
};

// "front", "three_quarter", "side"; parse_view throws retarget::Error naming `where` (an option
// such as "--view") and listing the names for anything else.
const char* view_name(RenderOptions::View view);
RenderOptions::View parse_view(const std::string& name, const std::string& where);

// Draws `vertices` (#V x 3, mesh units, +y up, +z towards the viewer) with the triangles of
// `topology` (and its polygons for the wireframe) into an options.width x options.height image.
// colours: optional #V x 3 per-vertex albedo replacing options.colour.
// Throws retarget::Error for invalid options, a vertex count other than topology's, colours of
// the wrong size, or an empty mesh.
Image render(const Mesh& topology, const Positions& vertices, const RenderOptions& options = {},
             const VertexColours& colours = {});
Image render(const Mesh& mesh, const RenderOptions& options = {});

// Where `point` (mesh units and frame) lands in the picture render(topology, vertices, options)
// draws: (x, y) in pixels of the final image (x right, y down, the centre of pixel (i, j) at
// i + 0.5, j + 0.5) and the camera depth (mesh units, larger is nearer). For labelling points.
Eigen::Vector3d project_to_image(const Positions& vertices, const RenderOptions& options, const Eigen::Vector3d& point);

// A turntable strip: `frames` (1..64) pictures of options.width x options.height side by side,
// the camera's yaw going from -max_yaw_deg to +max_yaw_deg (0..180) in equal steps (0 for one
// frame), framed with turntable_frame so that scale and centre stay put. options.yaw_deg is
// ignored. Size: frames * width x height.
Image render_turntable(const Mesh& topology, const Positions& vertices, int frames, double max_yaw_deg,
                       RenderOptions options = {}, const VertexColours& colours = {});

// One cell of a grid: a mesh drawn in one or several views, with a caption underneath.
struct GridCell {
  std::shared_ptr<const Mesh> mesh;  // topology, and the positions unless `vertices` is given
  Positions vertices;                // optional #V x 3 positions on mesh's topology (an expression)
  VertexColours colours;             // optional #V x 3 per-vertex albedo
  std::string caption;               // "" = none; printable ASCII, cut with "..." to fit the cell
};

struct GridOptions {
  RenderOptions render;  // each picture: render.width x render.height pixels, colours and lighting
  // Pictures per cell, left to right; render.view is ignored (render.yaw_deg would override all).
  std::vector<RenderOptions::View> views{RenderOptions::View::front};
  // Frame every cell with the union of all cells' boxes (or render.frame when set): one scale and
  // centre, so nothing jumps between the expressions of one face. Off: each cell fills its pictures.
  bool share_frame = true;
  std::string title;   // a line above the grid, "" = none
  int text_scale = 2;  // stb_easy_font's 1-pixel strokes drawn text_scale pixels wide, 1..8
  Eigen::Vector3f text_colour{0.12f, 0.12f, 0.12f};

  void validate() const;  // throws retarget::Error naming the option ("grid.views", ...)
};

// Height of a caption or title band: one line of text with padding, 16 * text_scale pixels.
int text_band_height(int text_scale);

// Cells fill rows of `columns` (>= 1) left to right. Each cell is views.size() pictures side by
// side above a caption band (present when any cell has a caption); the title band is on top.
// Size: columns * views.size() * render.width  x  title band + rows * (render.height + caption band),
// rows = ceil(cells / columns); unused cells at the end stay background.
// Throws retarget::Error for no cells, columns < 1, a cell without a mesh, or what render() throws.
Image render_grid(const std::vector<GridCell>& cells, int columns, const GridOptions& options = {});

// Text with stb_easy_font (printable ASCII; other bytes are drawn as '?'), top-left corner at
// (x, y) pixels, each font pixel a scale x scale block; clipped to the image.
void draw_text(Image& image, int x, int y, const std::string& text, int scale, const Eigen::Vector3f& colour);
int text_width(const std::string& text, int scale);  // pixels

// Copies `source` into `target` with its top-left corner at (x, y), clipped to the target.
void blit(Image& target, const Image& source, int x, int y);
// Images side by side (top-aligned) / stacked (left-aligned); the gaps are filled with `background`.
Image hconcat(const std::vector<Image>& images, const Eigen::Vector3f& background);
Image vconcat(const std::vector<Image>& images, const Eigen::Vector3f& background);

// The PNG file (8-bit RGB) of `image`, in memory, through stb_image_write. Throws
// retarget::Error naming `what` for an empty or inconsistent image.
std::string encode_png(const Image& image, const std::string& what = "PNG image");

// Writes a PNG (8-bit RGB) through stb_image_write, atomically (see write_file_atomically).
// Throws retarget::Error naming the path if encoding or writing fails.
void write_png(const std::string& path, const Image& image);

}  // namespace retarget
