// Building blocks of the procedural faces of synthetic/synthetic_faces.h: parameter grids cut
// along slits (eyelids, lips), smooth bump functions, eyelids that slide over an eyeball, and
// eyeball caps. Every face is laid out in its own 2D "canonical" coordinates (x, y), in cm,
// x towards the face's left (+x), y up; a face's base surface maps them to 3D (+z towards the
// viewer). Expressions and identity changes are fields over these coordinates, so they mean
// the same on every shape of one topology.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <functional>
#include <vector>

#include "geometry/mesh.h"

namespace retarget::synth {

// (1 - r^2)^3 for r < 1, 0 beyond: a C2 bump of compact support, 1 at r = 0.
double bump(double r);
// bump() of the elliptical distance of (x, y) from (cx, cy) with radii rx, ry.
double bump2(double x, double y, double cx, double cy, double rx, double ry);
// 1 within the elliptical distance `inner` (< 1) of (cx, cy) with radii rx, ry, falling smoothly
// to 0 at distance 1: a flat-topped weight, so a region moves as a whole.
double plateau(double x, double y, double cx, double cy, double rx, double ry, double inner);
// 0 at x = a, 1 at x = b, a cubic ramp in between (a > b allowed: a falling ramp).
double ramp(double a, double b, double x);
// max(a, b) rounded over a band of width k (>= max(a, b), within k/2 of it).
double smooth_max(double a, double b, double k);

// Catmull-Rom interpolation through (x_k, y_k) with increasing x_k; constant beyond the ends.
class Profile {
 public:
  Profile(std::vector<double> x, std::vector<double> y);
  double operator()(double x) const;

 private:
  std::vector<double> x_, y_;
};

// n values from lo to hi whose spacing is inversely proportional to density(t) (> 0).
std::vector<double> graded_samples(double lo, double hi, int n, const std::function<double(double)>& density);

// A mesh whose surface vertices come from grid points (i, j), j growing upwards. Vertex
// positions are left at zero for the caller. Slits duplicate the vertices along a grid line
// so that the two sides (lids, lips) can part.
struct GridMesh {
  Mesh mesh;                // faces (quads, triangles at poles); vertices #V x 3 zeros
  std::vector<int> gi, gj;  // #V grid coordinates (copies keep their original's)
  std::vector<int> slit;    // #V: index of the slit the vertex lies inside, or -1
  std::vector<int> side;    // #V: +1 the upper copy of a slit vertex, -1 the lower copy, 0 off slits
  std::vector<int> twin;    // #V: the other copy of a slit vertex, or -1
  int ni = 0, nj = 0;
  std::vector<int> index;  // ni * nj grid -> original vertex (-1 where none)
  int vertex(int i, int j) const { return index[static_cast<size_t>(j) * ni + i]; }
  int vertex_count() const { return static_cast<int>(gi.size()); }
};

// ni x nj vertices (i across, j up), vertex (i, j) = j * ni + i, (ni-1) x (nj-1) quads facing +z
// when i runs along +x and j along +y.
GridMesh open_grid(int ni, int nj);

// A closed latitude-longitude surface: `around` vertices per ring (i periodic), rings
// j = 1 .. rings - 1, and one pole vertex at each end (j = 0 and j = rings, gi = -1). The
// quads face outwards when i turns counter-clockwise seen from the j = rings pole.
GridMesh latlong_grid(int around, int rings);

// A cut along a polyline of grid vertices: `upper` holds the original vertices (faces on the
// upper side keep them), `lower` their copies; the two end vertices (the corners) stay shared.
struct Slit {
  std::vector<int> chain;  // all vertices along the slit, corners included (originals)
  std::vector<int> upper;  // chain without the corners
  std::vector<int> lower;  // the copies, parallel to `upper`
};

// Duplicates the interior vertices of `chain` (grid vertices, in order); faces for which
// is_lower(face) holds get the copies. Returns the slit; records `id` in grid.slit.
Slit cut_slit(GridMesh& grid, const std::vector<int>& chain, int id, const std::function<bool(int face)>& is_lower);

// The slit along grid row j from column i0 to i1 (i0 < i1); the lower side is j - 1.
Slit cut_row_slit(GridMesh& grid, int j, int i0, int i1, int id);

// Reverses the vertex order of every polygon (flips the facing); call before triangulate().
void reverse_faces(Mesh& mesh);

// Appends `part` (vertices and faces) to `mesh`; returns the index of its first vertex.
// Triangles are not rebuilt: call triangulate() once at the end.
int append_part(Mesh& mesh, const Mesh& part);

// A spherical cap with its pole on +z: 1 + rings * segments vertices on the unit sphere up to
// `max_angle` radians from the pole; triangles at the pole, quads elsewhere, facing outwards.
Mesh unit_cap(int rings, int segments, double max_angle);

// Cone-like closed part: `rings` circles of `segments` vertices from base to tip plus a tip
// vertex; faces outwards. Vertices are zeros (place them with the per-vertex (ring, segment)).
Mesh cone_part(int rings, int segments);

// Area-weighted vertex normals of `V` (#V x 3) on mesh's triangles (#V x 3, unit length).
Positions vertex_normals(const Mesh& mesh, const Positions& V);

// How far an eye's lids are open: the middle of the upper lid margin is `upper` cm above the
// slit line, the lower margin `lower` cm below it (negative values cross the line).
struct LidState {
  double upper = 0, lower = 0;
};

// An eye cut into a face, in canonical coordinates: the slit along y from x_in to x_out.
// The lid margins follow almond profiles; the lid skin above and below shifts with them over
// `upper_fall` and `lower_fall` cm.
struct EyeLayout {
  double x_in = 0, x_out = 0;  // canonical x of the two corners
  double y = 0;                // canonical y of the slit line
  double upper_fall = 1.3, lower_fall = 1.0;
  int slit = -1;  // GridMesh slit id
  // The almond profile in [0, 1] at canonical x (0 at the corners and beyond).
  double almond(double x) const;
  // Lid thickness over the ball at canonical x: `middle` in the middle of the opening, `corner`
  // at the corners.
  double lid_thickness(double x, double middle, double corner) const;
  // Vertical canonical shift of a surface vertex at (x, y_vertex) on the given side of the
  // slit (+1 upper, -1 lower) for these lids.
  double lid_shift(double x, double y_vertex, int side, const LidState& lids) const;
};

// An eyeball under the lids: the skin is pushed out to at least the sphere plus a lid.
struct Eyeball {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  double radius = 1;
  // The skin point P (cm) moved along the unit direction n (the skin's outward normal, +z on a
  // face seen from the front) until it lies `lid` cm outside the ball, by a smooth max so the
  // skin stays smooth where it leaves the ball. Beyond the ball's outline (seen along n) the
  // sphere continues steeply inwards, so the result is continuous.
  Eigen::Vector3d push(const Eigen::Vector3d& P, const Eigen::Vector3d& n, double lid) const;
};

// Eyeball caps are made with unit_cap(rings, segments, angle > kEyeballRim): the rings up to
// kEyeballRim from the pole lie on the ball; the rings beyond form a liner that flares outwards
// under the skin around the eye, so that no view looks past the ball through the eye corners.
constexpr double kEyeballRim = 80.0 * M_PI / 180.0;

// The liner's shape: it reaches `reach` cm beyond the ball's rim, rising by `rise` ball radii
// towards the skin (negative: backwards). It must stay under the skin around the eye.
struct EyeLiner {
  double reach = 1.2;
  double rise = 0.3;
};

// Positions of an eyeball cap (unit_cap directions, #cap x 3) on `ball`: a cornea bulge of
// `cornea` cm around the pole, which points along `axis` (unit); the liner turned towards
// `liner_axis` (unit; the face's normal there, so it stays behind a curved face).
Positions place_eyeball(const Positions& cap_directions, const Eyeball& ball, double cornea,
                        const Eigen::Vector3d& axis, const Eigen::Vector3d& liner_axis, const EyeLiner& liner);

// Per-vertex inputs of an expression field: canonical position, the vertex's share of the
// lower lip side (1 below the mouth slit, 0 above; in between only inside a mouth pocket,
// which is one connected surface), and the rest face's position and unit normal.
struct Site {
  double x = 0, y = 0;
  double lower = 0;
  Eigen::Vector3d P = Eigen::Vector3d::Zero(), n = Eigen::Vector3d::Zero();
};
using Field = std::function<Eigen::Vector3d(const Site&)>;

// Evaluates expression fields on the vertices that have canonical coordinates (the first
// xc.size() vertices of a #V-vertex mesh: the skin and any part laid out like it, such as a
// mouth pocket); the others (eyeballs, ears, ...) get zero offsets.
class FieldEvaluator {
 public:
  // lower: per vertex with canonical coordinates, its share of the lower lip side (Site::lower);
  // xc, yc: canonical coordinates; rest: #V x 3 rest positions; mesh: the full topology (normals).
  // The first `skin_count` of them are skin; the others (a mouth pocket) take the normal of the
  // skin vertex nearest in canonical coordinates, so that they move like the skin in front.
  FieldEvaluator(const std::vector<double>& lower, const std::vector<double>& xc, const std::vector<double>& yc,
                 int skin_count, const Mesh& mesh, const Positions& rest);
  // #V x 3 offsets. mirror: evaluate f at the mirror image (x -> -x) and mirror its result,
  // which turns a left shape into its right twin.
  Positions operator()(const Field& f, bool mirror = false) const;

 private:
  std::vector<Site> sites_;
  int vertex_count_;
};

// A pocket behind a mouth: an open ns x nt grid, vertex (i, j) = j * ns + i at pocket
// coordinates s = -1 + 2i/(ns-1) across, t = -1 + 2j/(nt-1) up; its faces point away from the
// viewer, so that from the front one sees its inside (drawn as back faces). Positions are the
// caller's: typically the skin at (s * half_width, mouth_y + t * half_height) moved back by an
// inset plus pocket_depth(s, t) * depth.
Mesh pocket_grid(int ns, int nt);
double pocket_depth(double s, double t);  // 0 on the rim, 1 in the middle
double pocket_lower(double t);            // the lower-lip share of pocket row t: 1 at t = -1, 0 at t = 1

// The lower jaw's share of a vertex: 1 on the lower side of the mouth between the corners,
// 0 on the upper side, and beyond the corners a smooth band around a line rising from the
// corner; zero beyond `reach` from the middle.
struct MouthLayout {
  double y = 0;                    // canonical y of the mouth line
  double corner = 1;               // canonical |x| of the corners
  double taper = 1;                // the lips part fully this far inside the corners
  double rise = 0.45;              // slope of the band's centre line beyond the corners
  double band = 1.1;               // half height of the band at the corners ...
  double band_growth = 0.35;       // ... growing by this much per cm beyond them
  double reach = 1e9;              // |x| beyond which nothing moves with the jaw (fades over 2 cm)
  double floor = -1e9;             // canonical y below which nothing moves with the jaw (fades in over
  double floor_fade = 2;           // floor_fade cm above it): keeps a closed head's bottom pole and back still
  double parting(double x) const;  // 1 in the middle, 0 at the corners and beyond
  double jaw_weight(const Site& s) const;
};

// Which side of slit `s` a surface vertex is on: its own copy for slit vertices, else by
// comparing its canonical y with the slit's.
inline int slit_side(const GridMesh& grid, int v, int s, double y_vertex, double y_slit) {
  if (grid.slit[v] == s) return grid.side[v];
  return y_vertex > y_slit ? 1 : -1;
}

}  // namespace retarget::synth
