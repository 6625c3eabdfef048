// A stylized avatar of synthetic_faces.h as data: the tables of avatar_tables.cpp (one
// AvatarSpec per avatar) are read by one builder, build_avatar(). A spec names its parameter
// grid, the eye and mouth cuts, the base surface and its relief, the extra parts (ears,
// antennae), the controllers in rig order with the deformation each one applies, and the
// landmarks. Geometry that genuinely differs between avatars (a grid layout, a base surface,
// a part) is a named kind with its own numbers; everything else is shared.
//
// Units and frame (synthetic_faces.h): cm, +y up, +z towards the viewer, +x the face's own
// left. Positions named (x, y) are canonical coordinates (synthetic_surface.h), in cm. Where a
// spec describes one side ("Left", `_L`, an anchor), it is the +x side; the other is its
// mirror image.
#pragma once

#include <string>
#include <variant>
#include <vector>

#include "synthetic/synthetic_faces.h"
#include "synthetic/synthetic_surface.h"

namespace retarget::synth {

struct Vec2 {
  double x = 0, y = 0;
};
struct Vec3 {
  double x = 0, y = 0, z = 0;
};

// ---- the grid ---------------------------------------------------------------------------------

// Spacing of samples over a parameter range: density 1 + peak * exp(-u^2), u = (t - centre) /
// width (graded_samples). peak = 0: evenly spaced, lo + (hi - lo) k / (count - 1).
struct Density {
  double peak = 0;
  double centre = 0;
  double width = 1;
  // width holds the squared width and u^2 = (t - centre)^2 / width (how one avatar's numbers
  // were first written; the two spellings differ in the last bit).
  bool squared = false;
};

// The canonical coordinates of one family of grid lines.
enum class Mapping {
  kLinear,  // scale * t
  kCosine,  // -scale * cos(t): t in [0, pi] over [-scale, scale]
};
struct Samples {
  double lo = 0, hi = 1;  // parameter range, both ends sampled
  int count = 2;
  Density density;
  bool symmetric = false;  // mirror-symmetric about `centre` (pairs averaged; see symmetrize)
  double centre = 0;
  bool periodic = false;  // the last sample repeats the first: dropped
  Mapping mapping = Mapping::kLinear;
  double scale = 1;
};

enum class GridKind {
  kSphere,    // latlong_grid: i around (longitude: canonical x), j up (latitude: y); poles at x = 0
  kOpen,      // open_grid: i across (x), j up (y)
  kSideways,  // latlong_grid on its side: rings about the x axis, j along x (poles at the left and
              // right ends), i around (y); faces reversed so they face outwards
};
struct GridSpec {
  GridKind kind = GridKind::kOpen;
  Samples x, y;  // canonical x and y of the grid lines (kSphere x: periodic)
};

// ---- eyes and mouth ---------------------------------------------------------------------------

// The eyes: each is cut along the grid line nearest y, between the lines nearest x -/+
// half_width (the right eye at the mirrored lines), with an eyeball behind it.
struct EyeSpec {
  double x = 0, y = 0, half_width = 1;        // the left eye, cm
  double upper_fall = 1.3, lower_fall = 1.0;  // EyeLayout
  LidState open;                              // the lids at rest
  double ball_radius = 1;
  double ball_recess = 0;  // the ball's front this far behind the base surface (negative: in front)
  double lid = 0.2;        // lid thickness over the ball in the middle (cm)
  double cornea = 0.1;     // cornea bulge (cm)
  EyeLiner liner;
  int cap_rings = 6, cap_segments = 16;  // the ball's cap (two more liner rings are added)
};

// The mouth: cut along the grid line nearest y between the lines nearest -/+ corner, with a
// pocket behind it (pocket_grid) and the jaw's share of each vertex (MouthLayout).
struct MouthSpec {
  double y = 0, corner = 1;  // cm
  // MouthLayout's fields (its y and corner come from the cut).
  double taper = 1, rise = 0.45, band = 1.1, band_growth = 0.35, reach = 1e9, floor = -1e9, floor_fade = 2;
  // The pocket: columns x rows vertices; half width a fraction of the mouth's, half height,
  // depth and inset in cm.
  int pocket_columns = 13, pocket_rows = 8;
  double pocket_width = 1.08, pocket_height = 0.6, pocket_depth = 1.5, pocket_inset = 0.25;
};

// ---- the base surface and its relief ----------------------------------------------------------

enum class SurfaceKind {
  // (x, y) as longitude x / a and latitude y / b (clamped to the poles) on the ellipsoid with
  // semi-axes a, b, c.
  kEllipsoid,
  // The square [-extent_x, extent_x] x [-extent_y, extent_y] mapped onto the elliptical disc
  // with half axes a x b, domed forwards: z = c * (sqrt(max(0, crown - q)) - drop), q the
  // disc's elliptical radius squared.
  kDomedDisc,
  // Poles at x = -/+ a: the cross-section at x has radius (1 - (x/a)^2)^exponent times b (up)
  // and c (forwards); y / b is the angle about the x axis from the front.
  kSidewaysEllipsoid,
};
struct SurfaceSpec {
  SurfaceKind kind = SurfaceKind::kEllipsoid;
  double a = 1, b = 1, c = 1;                              // cm
  double extent_x = 1, extent_y = 1, crown = 1, drop = 0;  // kDomedDisc
  double exponent = 0.5;                                   // kSidewaysEllipsoid
};

// What a bump's centre is measured from.
enum class Anchor {
  kFace,         // the canonical origin
  kMouthLine,    // (0, mouth y)
  kMouthCorner,  // (mouth corner, mouth y): the left corner
};
// bump2() around (cx, cy) with radii (rx, ry).
struct Bump {
  double cx = 0, cy = 0, rx = 1, ry = 1;  // cm
  Anchor anchor = Anchor::kFace;
  bool symmetric = false;  // evaluated at |x|: the bump and its mirror image
};
// bump((y - mouth y) / half_height), fading out from |x| = fade_from to fade_to: a band along
// the mouth line.
struct Band {
  double half_height = 1, fade_from = 0, fade_to = 1;  // cm
};

// Relief along the base normal (cm): the sum of its terms, in order.
struct BumpRelief {
  double weight = 0;  // cm
  Bump bump;
};
struct BandRelief {
  double weight = 0;  // cm
  Band band;
};
// A ridge along y (a snout): height(y) * bump(x / (width_scale * width(y))), both Profiles.
struct RidgeRelief {
  std::vector<double> height_at, height;  // y knots (cm), heights (cm)
  std::vector<double> width_at, width;    // y knots (cm), widths (cm)
  double width_scale = 1;
};
using ReliefTerm = std::variant<BumpRelief, BandRelief, RidgeRelief>;

// The mouth line's corners lifted into a grin: y moves up by lift * (x / corner_x)^2 *
// bump((y - mouth y) / half_height), fading out from |x| = fade_from to fade_to. lift = 0: none.
struct GrinSpec {
  double lift = 0, corner_x = 1, half_height = 1, fade_from = 0, fade_to = 1;  // cm
};

// ---- parts ------------------------------------------------------------------------------------

// Parts come in mirrored pairs (the first on the left) made with cone_part(rings, segments);
// each stands on the skin at canonical `anchor` (the right one at -x).
//
// Ears: flattened cones sunk `sink` cm along -z, pointing along `axis` (x mirrored); ring u in
// [0, 1) has half width width * (1 - u)^taper across and depth * (1 - u)^taper front to back.
// Poses tilt them sideways (swing) and back.
struct EarsSpec {
  int rings = 7, segments = 14;
  Vec2 anchor;
  double sink = 0;
  Vec3 axis;
  double length = 1, width = 1, depth = 1, taper = 1;  // cm, cm, cm, exponent
};
// Antennae: stalks sunk `sink` cm along the skin normal, pointing along normal + lean (x
// mirrored), radius radius * (1 - taper * u) + bulb * bump((u - bulb_at) / bulb_width) at ring
// u; poses bend them (swing) in an arc about an axis between forwards and inwards (bend_inwards
// of the lateral axis), more towards the tip.
struct AntennaeSpec {
  int rings = 10, segments = 8;
  Vec2 anchor;
  double sink = 0;
  Vec3 lean;
  double length = 1, radius = 0.3, taper = 0.5, bulb = 0, bulb_at = 1, bulb_width = 0.1, bend_inwards = 0.5;
};
using PartsSpec = std::variant<std::monostate, EarsSpec, AntennaeSpec>;

// ---- controllers ------------------------------------------------------------------------------

// Both eyes' lids at `state` for the controller's eye (the other one open).
struct Lids {
  LidState state;
};

// One term of a displacement field: weight * bump * a direction.
enum class Motion {
  kAlong,     // along `direction`
  kNormal,    // along the rest surface's unit normal
  kUpperLip,  // along `direction`, times (1 - lower-lip share) * MouthLayout::parting(x)
};
struct FieldTerm {
  double weight = 1;  // cm (per unit direction)
  Bump bump;
  Vec3 direction;
  Motion motion = Motion::kAlong;
};
// A displacement field over the canonical layout: the sum of its terms, in order.
struct Displacement {
  std::vector<FieldTerm> terms;
};
// Lips drawn together and pushed forwards: (-pinch * x * in, 0, forward * out) for the bumps
// `in` and `out`.
struct Pucker {
  double pinch = 0;
  Bump in;
  double forward = 0;  // cm
  Bump out;
};
// The mouth stretched wide: with r = the band, (out * x * r, -down * r * ramp(down_from,
// down_to, |x|), 0).
struct Stretch {
  Band band;
  double out = 0, down = 0, down_from = 0, down_to = 1;
};
// The jaw's share of each vertex (MouthLayout::jaw_weight) rotated by `angle` radians (opening)
// about the x axis through `pivot` (cm, frame coordinates).
struct Jaw {
  Vec3 pivot;
  double angle = 0;
};
// Every vertex moves by (P - base) * scale, per axis: a squash of the whole head.
struct Squash {
  Vec3 base, scale;
};
// The eyeballs' radii times ball_scale (centres fixed).
struct EyePop {
  double ball_scale = 1;
};
// Parts: one part tilts sideways (ears) or bends (antennae) by `amount` radians.
struct PartSwing {
  double amount = 0;
};
// Parts: both ears tilt back by `amount` radians.
struct PartsBack {
  double amount = 0;
};
using Deformation = std::variant<Lids, Displacement, Pucker, Stretch, Jaw, Squash, EyePop, PartSwing, PartsBack>;

enum class Sides {
  kOne,     // one controller, `name`
  kPair,    // nameLeft (the deformation as given) and nameRight (its mirror image)
  kSummed,  // one controller, `name`: the deformation plus its mirror image (Displacement only)
};
// A controller (range [0, 1]) and its correspondence row: each human name with weight 1. With
// kPair the names are the left controller's and end in `_L` or `Left`; the right one's end in
// `_R` or `Right`. No names: no human counterpart.
struct ControllerSpec {
  std::string name;
  Sides sides = Sides::kOne;
  Deformation deformation;
  std::vector<std::string> human;
};

// ---- landmarks and the whole ------------------------------------------------------------------

// A landmark at the surface vertex nearest canonical (x, y); a name ending in "_left" gets a
// "_right" twin at (-x, y). Every avatar also has the eye and mouth landmarks of its cuts.
struct LandmarkSpec {
  std::string name;
  double x = 0, y = 0;  // cm
};

struct AvatarSpec {
  std::string name;         // the rig's name
  std::string description;  // one line (SyntheticAvatar::description)
  GridSpec grid;
  EyeSpec eyes;
  MouthSpec mouth;
  SurfaceSpec surface;
  GrinSpec grin;
  std::vector<ReliefTerm> relief;
  PartsSpec parts;
  std::vector<ControllerSpec> controllers;  // in rig order
  std::vector<LandmarkSpec> landmarks;

  // Throws Error naming the field ("fox.controllers[3].deformation: ...") for what the builder
  // cannot build: too few grid lines, non-positive radii, part motions without parts, kSummed
  // on anything but a Displacement, repeated controller names, pair names without a side.
  void validate() const;
};

// The avatar a spec describes. Deterministic: the same spec gives identical numbers.
SyntheticAvatar build_avatar(const AvatarSpec& spec);

// The bundled avatars' tables (avatar_tables.cpp), in synthetic_avatars() order.
const std::vector<AvatarSpec>& avatar_specs();

}  // namespace retarget::synth
