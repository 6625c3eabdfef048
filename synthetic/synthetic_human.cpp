// The procedural human face model of synthetic_faces.h.
//
// Layout: a quad grid over canonical coordinates (x, y) in cm, x = kR0 * azimuth (azimuth
// about the vertical head axis, 0 at the front), y = height (0 at the eyes). The base surface
// wraps the grid around the front of an ellipsoidal head whose width, depth and midline
// profile vary with height; relief (nose, brows, sockets, cheeks, lips, chin) is added along
// +z at canonical positions, and the skin over each eye is pushed out over an eyeball sphere.
// Identity modes are finite differences of named shape parameters (one standard deviation
// each); expressions are displacement fields over the canonical layout, evaluated once on the
// model's mean face.
#include <Eigen/Geometry>
#include <array>
#include <cmath>

#include "core/random.h"
#include "synthetic/synthetic_faces.h"
#include "synthetic/synthetic_surface.h"

namespace retarget {

namespace {

using namespace synth;
using Eigen::Vector3d;

constexpr double kR0 = 7.0;  // canonical x per radian of azimuth (cm)
constexpr int kColumns = 91, kRows = 75;
constexpr double kAzimuthMax = 1.75;  // radians (~100 degrees) to each side
constexpr double kBottom = -13.5, kTop = 9.0;
constexpr double kEyeX = 3.08;          // canonical |x| of the eye centres (~3.1 cm on the surface)
constexpr double kEyeHalfWidth = 1.15;  // canonical half width of the eye opening
constexpr double kMouthY = -7.2;        // canonical height of the mouth line (target; snapped to a row)
constexpr double kMouthCorner = 2.65;   // canonical |x| of the mouth corners (target; snapped to a column)
constexpr double kBallRadius = 1.42;
constexpr double kBallRecess = 0.8;  // eyeball front behind the base surface (cm)

const LidState kOpen{0.55, 0.42};

// The mouth pocket: columns x rows, its half width (fraction of the mouth's), half height and
// depth (cm), and how far its rim sits behind the skin.
constexpr int kPocketColumns = 15, kPocketRows = 10;
constexpr double kPocketWidth = 1.05, kPocketHeight = 0.85, kPocketDepth = 2.2, kPocketInset = 0.3;

// ---------------------------------------------------------------------------------------------
// Identity parameters: deviations from the nominal face (0), in the unit of their sigma.
enum Param : int {
  kFaceWidth,
  kFaceLength,
  kFaceDepth,
  kJawWidth,
  kForeheadHeight,
  kForeheadSlope,
  kEyeSpacing,
  kEyeHeight,
  kEyeSize,
  kEyeDepth,
  kEyeTilt,
  kBrowRidge,
  kNoseLength,
  kNoseWidth,
  kNoseProjection,
  kNoseBridge,
  kCheekbones,
  kCheekFullness,
  kMouthWidth,
  kMouthHeight,
  kUpperLip,
  kLowerLip,
  kLipHeight,
  kChinHeight,
  kChinProjection,
  kAsymFace,
  kAsymEyes,
  kAsymNose,
  kAsymMouth,
  kParamCount
};

struct ParamInfo {
  const char* name;
  double sigma;  // one standard deviation, in the parameter's unit
};

// Units: fractions for scalings, cm for shifts, slopes for tilts.
const std::array<ParamInfo, kParamCount> kParams = {{
    {"faceWidth", 0.05},      {"faceLength", 0.045},   {"faceDepth", 0.06},      {"jawWidth", 0.07},
    {"foreheadHeight", 0.10}, {"foreheadSlope", 0.5},  {"eyeSpacing", 0.22},     {"eyeHeight", 0.25},
    {"eyeSize", 0.06},        {"eyeDepth", 0.15},      {"eyeTilt", 0.12},        {"browRidge", 0.3},
    {"noseLength", 0.3},      {"noseWidth", 0.12},     {"noseProjection", 0.12}, {"noseBridge", 0.22},
    {"cheekbones", 0.25},     {"cheekFullness", 0.3},  {"mouthWidth", 0.08},     {"mouthHeight", 0.22},
    {"upperLip", 0.12},       {"lowerLip", 0.14},      {"lipHeight", 0.16},      {"chinHeight", 0.4},
    {"chinProjection", 0.3},  {"asymmetryFace", 0.02}, {"asymmetryEyes", 0.12},  {"asymmetryNose", 0.15},
    {"asymmetryMouth", 0.06},
}};

using Params = std::array<double, kParamCount>;

// ---------------------------------------------------------------------------------------------
// Profiles of the base head by height (cm).
const Profile& half_width() {
  static const Profile p({-13.5, -11, -8.5, -5, -2, 0, 3, 6, 9}, {4.9, 4.9, 5.6, 6.6, 7.2, 7.25, 7.0, 6.5, 5.8});
  return p;
}
const Profile& half_depth() {
  static const Profile p({-11, -7, -2, 4, 10}, {7.5, 8.6, 9.0, 9.0, 8.5});
  return p;
}
const Profile& midline() {
  static const Profile p({-11.5, -10, -8, -5, -2, 0, 2, 4.5, 7, 9},
                         {-0.75, -0.35, -0.1, 0.15, 0.2, 0.0, 0.15, -0.2, -1.2, -2.9});
  return p;
}
const Profile& nose_height() {
  static const Profile p({-5.75, -5.4, -5.05, -4.45, -3.2, -1.6, 0.0, 0.7, 1.4},
                         {0.0, 0.25, 1.3, 2.35, 1.85, 1.2, 0.55, 0.25, 0.0});
  return p;
}
const Profile& nose_half_width() {
  static const Profile p({-5.5, -4.5, -3.0, -1.5, 0.5}, {1.5, 1.15, 0.85, 0.65, 0.75});
  return p;
}

// The layout: grid, slits, canonical coordinates, mouth pocket, eyeball caps.
struct HumanLayout {
  GridMesh grid;
  Mesh mesh;  // grid faces, the mouth pocket, two eyeball caps (triangulated)
  std::vector<double> xc, yc;
  EyeLayout eye[2];  // 0: left (+x), 1: right
  Slit eye_slit[2], mouth;
  double eye_y = 0, mouth_y = kMouthY, mouth_corner = kMouthCorner;
  int surface_count = 0;      // skin vertices (grid and slit copies)
  int pocket_first = 0;       // the mouth pocket's vertices follow the skin's
  std::vector<double> lower;  // per skin and pocket vertex: share of the lower lip side (Site::lower)
  int ball_first[2] = {0, 0};
  Positions cap;  // unit directions of one eyeball cap
};

HumanLayout make_layout() {
  HumanLayout L;
  std::vector<double> azimuth =
      graded_samples(-kAzimuthMax, kAzimuthMax, kColumns, [](double a) { return 1 + 2.0 * std::exp(-a * a / 0.49); });
  for (int k = 0; k < kColumns / 2; ++k) {
    const double v = 0.5 * (azimuth[kColumns - 1 - k] - azimuth[k]);
    azimuth[k] = -v;
    azimuth[kColumns - 1 - k] = v;
  }
  azimuth[kColumns / 2] = 0;
  const std::vector<double> rows = graded_samples(kBottom, kTop, kRows, [](double y) {
    const double t = (y + 3.0) / 5.5;
    return 1 + 1.8 * std::exp(-t * t);
  });
  auto nearest = [](const std::vector<double>& values, double target) {
    int best = 0;
    for (int k = 1; k < static_cast<int>(values.size()); ++k)
      if (std::abs(values[k] - target) < std::abs(values[best] - target)) best = k;
    return best;
  };
  std::vector<double> xs(kColumns);
  for (int i = 0; i < kColumns; ++i) xs[i] = kR0 * azimuth[i];
  const int eye_row = nearest(rows, 0.0), mouth_row = nearest(rows, kMouthY);
  L.eye_y = rows[eye_row];
  L.mouth_y = rows[mouth_row];

  L.grid = open_grid(kColumns, kRows);
  const int centre = kColumns / 2;
  const int eye_in = nearest(xs, kEyeX - kEyeHalfWidth), eye_out = nearest(xs, kEyeX + kEyeHalfWidth);
  const int mouth_right = nearest(xs, kMouthCorner);
  L.eye_slit[0] = cut_row_slit(L.grid, eye_row, eye_in, eye_out, 0);
  L.eye_slit[1] = cut_row_slit(L.grid, eye_row, 2 * centre - eye_out, 2 * centre - eye_in, 1);
  L.mouth = cut_row_slit(L.grid, mouth_row, 2 * centre - mouth_right, mouth_right, 2);
  L.mouth_corner = xs[mouth_right];
  for (int e = 0; e < 2; ++e) {
    const double sign = e == 0 ? 1 : -1;
    L.eye[e].x_in = sign * xs[eye_in];
    L.eye[e].x_out = sign * xs[eye_out];
    L.eye[e].y = L.eye_y;
    L.eye[e].upper_fall = 1.7;
    L.eye[e].lower_fall = 1.1;
    L.eye[e].slit = e;
  }
  L.surface_count = L.grid.vertex_count();
  L.xc.resize(L.surface_count);
  L.yc.resize(L.surface_count);
  for (int v = 0; v < L.surface_count; ++v) {
    L.xc[v] = xs[L.grid.gi[v]];
    L.yc[v] = rows[L.grid.gj[v]];
  }
  L.mesh = L.grid.mesh;
  for (int v = 0; v < L.surface_count; ++v)
    L.lower.push_back(slit_side(L.grid, v, 2, L.yc[v], L.mouth_y) < 0 ? 1.0 : 0.0);
  // The mouth pocket, laid out in canonical coordinates like the skin in front of it.
  L.pocket_first = append_part(L.mesh, pocket_grid(kPocketColumns, kPocketRows));
  for (int j = 0; j < kPocketRows; ++j)
    for (int i = 0; i < kPocketColumns; ++i) {
      const double s = -1 + 2.0 * i / (kPocketColumns - 1), t = -1 + 2.0 * j / (kPocketRows - 1);
      L.xc.push_back(s * kPocketWidth * L.mouth_corner);
      L.yc.push_back(L.mouth_y + t * kPocketHeight);
      L.lower.push_back(pocket_lower(t));
    }
  const Mesh cap = unit_cap(10, 20, 100.0 * M_PI / 180.0);  // 8 rings on the ball, 2 of liner
  L.cap = cap.vertices;
  L.ball_first[0] = append_part(L.mesh, cap);
  L.ball_first[1] = append_part(L.mesh, cap);
  triangulate(L.mesh);
  return L;
}

const HumanLayout& layout() {
  static const HumanLayout L = make_layout();
  return L;
}

// ---------------------------------------------------------------------------------------------
// Shape: canonical warps (identity), base surface, relief, eyeballs.

Eigen::Vector2d identity_warp(const Params& p, const HumanLayout& L, double x, double y) {
  double dx = 0, dy = 0;
  // Flat-topped weights: the skin around an eye moves with its eyeball, so the lids keep
  // resting on it; around the nose and the mouth whole features scale.
  for (int e = 0; e < 2; ++e) {
    const double s = e == 0 ? 1 : -1, ex = s * kEyeX, ey = L.eye_y;
    const double b = plateau(x, y, ex, ey, 3.5, 3.1, 0.42);
    dx += s * p[kEyeSpacing] * b;
    dy += (p[kEyeHeight] + s * p[kAsymEyes]) * b;
    const double bs = plateau(x, y, ex, ey, 3.5, 3.1, 0.4);
    dx += p[kEyeSize] * (x - ex) * bs;
    dy += p[kEyeSize] * (y - ey) * bs + p[kEyeTilt] * s * (x - ex) * bs;
  }
  dx += p[kNoseWidth] * x * plateau(x, y, 0, -3.6, 3.2, 3.6, 0.5);
  dy -= p[kNoseLength] * ramp(1.0, -4.5, y) * (1 - ramp(-5.3, -7.0, y)) * bump(x / 3.5);
  dx += p[kAsymNose] * plateau(x, y, 0, -3.8, 2.6, 3.0, 0.5);
  const double bm = plateau(x, y, 0, L.mouth_y, 4.6, 2.8, 0.55);
  dx += p[kMouthWidth] * x * bm;
  // The mouth moves up or down between the nose base and the chin (the lips stretch evenly).
  const double ym = L.mouth_y;
  const double along = y > ym ? 1 - ramp(ym, ym + 1.9, y) : 1 - ramp(ym, ym - 3.5, y);
  dy += p[kMouthHeight] * along * bump(x / 6.0) + p[kAsymMouth] * x * bm;
  // d * bump(d / R) stretches the lips and never compresses anything by more than ~60% of p.
  dy += p[kLipHeight] * (y - L.mouth_y) * bump2(x, y, 0, L.mouth_y, 4.5, 3.2);
  return {x + dx, y + dy};
}

// The midline below the chin: canonical y below kChin is arc length along a curve that turns
// from the chin's slope to straight backwards (radius kChinRadius), so shifts of y slide along
// the under-chin instead of cutting across it. Returns (height, depth) on the midline.
constexpr double kChin = -11.0, kChinRadius = 1.0;
Eigen::Vector2d midline_point(double y) {
  if (y >= kChin) return {y, midline()(y)};
  const double h = 1e-3;
  const double slope = (midline()(kChin + h) - midline()(kChin)) / h;  // dz/dy at the chin
  const double start = std::atan(slope);                               // turn from straight down, towards -z
  const double t = kChin - y, turn = 0.5 * M_PI - start, arc = turn * kChinRadius;
  // Along the arc the direction (down, back) turns from `start` to pi/2.
  auto along = [&](double u) {
    const double a = start + u / kChinRadius;
    // Integral of (cos, sin) of the turning angle from 0 to u.
    return Eigen::Vector2d(kChinRadius * (std::sin(a) - std::sin(start)),
                           kChinRadius * (std::cos(start) - std::cos(a)));
  };
  Eigen::Vector2d d = t <= arc ? along(t) : Eigen::Vector2d(along(arc) + Eigen::Vector2d(0, t - arc));
  return {kChin - d.x(), midline()(kChin) - d.y()};
}

// The base head at warped canonical (x, y), no relief.
Vector3d base_surface(const Params& p, double x, double y) {
  const double azimuth = x / kR0;
  double a = half_width()(y) * (1 + p[kFaceWidth]) * (1 + p[kJawWidth] * ramp(-3, -9, y));
  a *= azimuth > 0 ? 1 + p[kAsymFace] : 1 - p[kAsymFace];
  const double c = half_depth()(y) * (1 + p[kFaceDepth]);
  const double above = std::max(0.0, y - 3.0);
  Eigen::Vector2d mid = midline_point(y);
  if (y < kChin) {
    // Under the chin the front turns backwards; towards the sides, where the face already
    // wraps backwards, the rows go a little way down instead (the jaw's underside seen from
    // the side).
    const double f = std::pow(std::max(0.0, std::cos(azimuth)), 2);
    const double chin_depth = midline()(kChin);
    mid = {kChin + (mid.x() - kChin) * f + 0.3 * (y - kChin) * (1 - f), chin_depth + (mid.y() - chin_depth) * f};
  }
  const double z0 = mid.y() - p[kForeheadSlope] * above * above / 49.0;
  // Vertical proportions stretch the finished heights (linear in the parameters): face length
  // from the eyes to the jaw, the forehead above the brows, the chin below the mouth.
  const double h = mid.x(), px = a * std::sin(azimuth);
  const double height = h + p[kFaceLength] * std::max(h, -8.0) + p[kForeheadHeight] * std::max(0.0, h - 2.0) -
                        p[kChinHeight] * ramp(-8.0, -11.0, h) * bump(px / 6.0);
  return {px, height, z0 + c * (std::cos(azimuth) - 1)};
}

double nose(double x, double y) {
  const double ridge = nose_height()(y) * bump(x / (1.9 * nose_half_width()(y)));
  const double wings = 0.85 * (bump2(x, y, 1.3, -4.75, 0.75, 0.65) + bump2(x, y, -1.3, -4.75, 0.75, 0.65));
  const double tip = 0.25 * bump2(x, y, 0, -4.3, 0.6, 0.6);
  return ridge + wings + tip;
}

// Relief along +z at canonical (x, y) (before warps).
double relief(const Params& p, const HumanLayout& L, double x, double y) {
  const double ax = std::abs(x), ye = L.eye_y, ym = L.mouth_y;
  double f = 0;
  f -= (1.25 + p[kEyeDepth]) * bump2(ax, y, kEyeX, ye + 0.15, 2.2, 2.0);
  f += 0.55 * (1 + p[kBrowRidge]) * bump2(ax, y, 2.8, ye + 1.75, 3.4, 1.1);
  f += 0.3 * bump2(x, y, 0, ye + 1.3, 1.4, 1.2);
  f += 0.3 * bump2(ax, y, 2.6, 5.5, 3.0, 3.0);
  f -= 0.35 * bump2(ax, y, 6.4, 1.8, 1.4, 2.6);
  f += (0.6 + p[kCheekbones]) * bump2(ax, y, 4.4, -2.3, 2.4, 1.7);
  f += (0.45 + p[kCheekFullness]) * bump2(ax, y, 3.9, -5.2, 2.4, 2.3);
  f += (1 + p[kNoseProjection]) * nose(x, y) + p[kNoseBridge] * bump2(x, y, 0, -1.3, 0.75, 1.5);
  f += 0.75 * bump2(x, y, 0, ym + 0.2, 4.0, 3.4);
  // Lips: equal at the mouth line (both copies of a lip vertex get the same height).
  const double d = y - ym;
  const double lx = std::pow(bump(x / (L.mouth_corner + 0.25)), 0.5);
  auto q = [](double t) { return t > 0 && t < 1 ? std::pow(std::sin(M_PI * t), 0.7) : 0.0; };
  const double lips =
      0.1 * bump(d / 1.3) + (d > 0 ? (0.5 + p[kUpperLip]) * q(d / 1.05) : (0.6 + p[kLowerLip]) * q(-d / 1.2));
  f += lx * lips;
  f += 0.05 * bump((d - 1.03) / 0.18) * lx;  // the upper lip's border
  f -= 0.09 * bump2(x, y, 0, ym + 1.6, 0.32, 0.9);
  f += 0.06 * (bump2(x, y, 0.42, ym + 1.5, 0.2, 0.8) + bump2(x, y, -0.42, ym + 1.5, 0.2, 0.8));
  f -= 0.3 * bump2(x, y, 0, ym - 1.75, 2.2, 0.65);
  f += (0.75 + p[kChinProjection]) * bump2(x, y, 0, -10.4, 2.2, 1.7);
  return f;
}

// Lid thickness in the middle of the opening; the upper lid is a little thicker, so a closed
// upper lid lies over the lower one.
double side_lid(const GridMesh& grid, int v, int eye, double y, double eye_y) {
  return slit_side(grid, v, eye, y, eye_y) > 0 ? 0.25 : 0.2;
}

struct HumanShape {
  Positions V;  // all vertices
  Eyeball balls[2];
};

HumanShape human_shape(const Params& p, const LidState lids[2]) {
  const HumanLayout& L = layout();
  HumanShape out;
  out.V.resize(L.mesh.vertex_count(), 3);
  for (int e = 0; e < 2; ++e) {
    const double s = e == 0 ? 1 : -1;
    const Eigen::Vector2d c = identity_warp(p, L, s * kEyeX, L.eye_y);
    Vector3d centre = base_surface(p, c.x(), c.y());
    const double radius = kBallRadius * (1 + p[kEyeSize]);
    centre.z() -= kBallRecess + p[kEyeDepth] + radius;
    out.balls[e].centre = centre;
    out.balls[e].radius = radius;
  }
  for (int v = 0; v < L.surface_count; ++v) {
    const double x = L.xc[v], y = L.yc[v];
    double dy = 0;
    for (int e = 0; e < 2; ++e) dy += L.eye[e].lid_shift(x, y, slit_side(L.grid, v, e, y, L.eye_y), lids[e]);
    const Eigen::Vector2d w = identity_warp(p, L, x, y + dy);
    Vector3d P = base_surface(p, w.x(), w.y());
    P.z() += relief(p, L, x, y);
    for (int e = 0; e < 2; ++e) {
      const Eyeball& ball = out.balls[e];
      if (std::abs(P.x() - ball.centre.x()) < 2.5 && std::abs(P.y() - ball.centre.y()) < 2.5)
        P = ball.push(P, Vector3d::UnitZ(), L.eye[e].lid_thickness(x, side_lid(L.grid, v, e, y, L.eye_y), 0.06));
    }
    out.V.row(v) = P.transpose();
  }
  for (int v = L.pocket_first; v < L.pocket_first + kPocketColumns * kPocketRows; ++v) {
    const int k = v - L.pocket_first;
    const double s = -1 + 2.0 * (k % kPocketColumns) / (kPocketColumns - 1),
                 t = -1 + 2.0 * (k / kPocketColumns) / (kPocketRows - 1);
    const Eigen::Vector2d w = identity_warp(p, L, L.xc[v], L.yc[v]);
    Vector3d P = base_surface(p, w.x(), w.y());
    P.z() += relief(p, L, L.xc[v], L.yc[v]) - kPocketInset - kPocketDepth * pocket_depth(s, t);
    out.V.row(v) = P.transpose();
  }
  for (int e = 0; e < 2; ++e) {
    // The liner follows the face's slope at the eye (the base surface's normal).
    const Vector3d& c = out.balls[e].centre;
    const double h = 0.05;
    const Vector3d nx = base_surface(p, kR0 * std::asin(std::clamp((c.x() + h) / 7.2, -1.0, 1.0)), c.y()) -
                        base_surface(p, kR0 * std::asin(std::clamp((c.x() - h) / 7.2, -1.0, 1.0)), c.y());
    const Vector3d liner_axis = Vector3d(-nx.z(), 0, nx.x()).normalized();
    out.V.middleRows(L.ball_first[e], L.cap.rows()) =
        place_eyeball(L.cap, out.balls[e], 0.08, Vector3d::UnitZ(), liner_axis, {1.4, 0.3});
  }
  return out;
}

// ---------------------------------------------------------------------------------------------
// Expressions.

std::vector<Blendshape> human_expressions(const Params& mean_params, const Positions& mean) {
  const HumanLayout& L = layout();
  const FieldEvaluator B(L.lower, L.xc, L.yc, L.surface_count, L.mesh, mean);
  const double ym = L.mouth_y, corner = L.mouth_corner;
  MouthLayout mouth;
  mouth.y = ym;
  mouth.corner = corner;
  mouth.taper = 1.4;
  std::vector<Blendshape> out;
  auto add = [&](const std::string& name, Positions offset) { out.push_back({name, std::move(offset)}); };
  // A left shape and its mirror image as the right shape.
  auto add_pair = [&](const std::string& stem, const Field& f) {
    add(stem + "_L", B(f));
    add(stem + "_R", B(f, true));
  };
  auto taper = [&](double x) { return mouth.parting(x); };
  auto jaw_weight = [&](const Site& s) { return mouth.jaw_weight(s); };
  const Vector3d pivot(0, -2.6, -8.0);
  const double jaw_angle = 0.30;
  const Eigen::Matrix3d jaw_rotation = Eigen::AngleAxisd(jaw_angle, Vector3d::UnitX()).toRotationMatrix();
  auto jaw_motion = [&](const Vector3d& P) -> Vector3d {
    return (jaw_rotation - Eigen::Matrix3d::Identity()) * (P - pivot) + Vector3d(0, -0.3, 0.6);
  };
  // Lip band: 1 at the mouth line fading over ~1.4 cm, within the mouth's width.
  auto lip_band = [&](const Site& s) { return taper(s.x) * (1 - ramp(0, 1.4, std::abs(s.y - ym))); };
  auto lids = [&](int eye, LidState state) {
    LidState both[2] = {kOpen, kOpen};
    both[eye] = state;
    return Positions(human_shape(mean_params, both).V - mean);
  };
  auto eye_pair = [&](const std::string& stem, LidState state, const Field& extra) {
    for (int e = 0; e < 2; ++e) {
      Positions offset = lids(e, state);
      if (extra) offset += B(extra, e == 1);
      add(stem + (e == 0 ? "_L" : "_R"), offset);
    }
  };

  add_pair("browDown", [&](const Site& s) -> Vector3d {
    return bump2(s.x, s.y, 3.0, 1.9, 2.6, 1.5) * Vector3d(-0.15, -0.45, 0.12) +
           bump2(s.x, s.y, 1.2, 1.6, 1.2, 1.0) * Vector3d(-0.15, -0.1, 0.05);
  });
  add_pair("browInnerUp",
           [&](const Site& s) -> Vector3d { return bump2(s.x, s.y, 1.6, 2.2, 1.8, 2.2) * Vector3d(0, 0.65, 0); });
  add_pair("browOuterUp",
           [&](const Site& s) -> Vector3d { return bump2(s.x, s.y, 4.4, 2.0, 2.0, 2.2) * Vector3d(0, 0.6, 0); });
  add_pair("cheekPuff", [&](const Site& s) -> Vector3d { return 1.1 * bump2(s.x, s.y, 4.0, -6.0, 2.6, 2.8) * s.n; });
  add_pair("cheekSquint", [&](const Site& s) -> Vector3d {
    return bump2(s.x, s.y, 3.6, -2.3, 2.0, 1.6) * Vector3d(0.05, 0.35, 0.15);
  });
  eye_pair("eyeBlink", {-0.30, 0.30}, {});  // both margins meet 0.3 below the line
  eye_pair("eyeSquint", {0.35, 0.18},
           [&](const Site& s) -> Vector3d { return bump2(s.x, s.y, 3.2, -1.7, 1.6, 1.0) * Vector3d(0, 0.12, 0.05); });
  eye_pair("eyeWide", {0.82, 0.5},
           [&](const Site& s) -> Vector3d { return bump2(s.x, s.y, 3.1, 1.9, 2.2, 1.5) * Vector3d(0, 0.12, 0); });
  add("jawForward", B([&](const Site& s) -> Vector3d { return jaw_weight(s) * Vector3d(0, 0, 0.6); }));
  add("jawLeft",
      B([&](const Site& s) -> Vector3d { return jaw_weight(s) * ramp(-7, -3, s.P.z()) * Vector3d(0.8, 0, 0); }));
  add("jawOpen", B([&](const Site& s) -> Vector3d { return jaw_weight(s) * jaw_motion(s.P); }));
  add("jawRight",
      B([&](const Site& s) -> Vector3d { return jaw_weight(s) * ramp(-7, -3, s.P.z()) * Vector3d(-0.8, 0, 0); }));
  // Lips meet half way when the jaw is open by as much.
  add("mouthClose", B([&](const Site& s) -> Vector3d { return (0.5 - s.lower) * lip_band(s) * jaw_motion(s.P); }));
  add_pair("mouthDimple", [&](const Site& s) -> Vector3d {
    return bump2(s.x, s.y, corner, ym, 1.5, 1.3) * Vector3d(0.25, -0.05, -0.3);
  });
  add_pair("mouthFrown", [&](const Site& s) -> Vector3d {
    return bump2(s.x, s.y, corner, ym - 0.2, 2.0, 2.0) * Vector3d(0.1, -0.55, -0.05);
  });
  add("mouthFunnel", B([&](const Site& s) -> Vector3d {
        const double region = bump2(s.x, s.y, 0, ym, 3.0, 1.8);
        const double open = bump(s.x / 1.8) * (1 - ramp(0, 1.2, std::abs(s.y - ym)));
        return Vector3d(-0.28 * s.x * region, (0.3 - 0.65 * s.lower) * open, 0.6 * region);
      }));
  add("mouthLeft",
      B([&](const Site& s) -> Vector3d { return bump2(s.x, s.y, 0, ym, 4.0, 2.4) * Vector3d(0.9, 0, 0); }));
  add_pair("mouthLowerDown", [&](const Site& s) -> Vector3d {
    return s.lower * taper(s.x) * bump2(s.x, s.y, 1.1, ym - 0.5, 1.7, 1.3) * Vector3d(0.05, -0.5, 0.05);
  });
  add_pair("mouthPress", [&](const Site& s) -> Vector3d {
    const double b = bump2(s.x, s.y, 1.2, ym, 1.8, 1.4) * taper(s.x);
    return Vector3d(0, -0.25 * (s.y - ym) * b, -0.22 * b);
  });
  add("mouthPucker", B([&](const Site& s) -> Vector3d {
        const double b = bump2(s.x, s.y, 0, ym, 2.9, 1.8);
        return Vector3d(-0.35 * s.x * b, -0.12 * (s.y - ym) * b, 0.75 * b);
      }));
  add("mouthRight",
      B([&](const Site& s) -> Vector3d { return bump2(s.x, s.y, 0, ym, 4.0, 2.4) * Vector3d(-0.9, 0, 0); }));
  add("mouthRollLower", B([&](const Site& s) -> Vector3d {
        return s.lower * taper(s.x) * bump2(s.x, s.y, 0, ym - 0.2, 2.8, 1.0) * Vector3d(0, 0.1, -0.45);
      }));
  add("mouthRollUpper", B([&](const Site& s) -> Vector3d {
        return (1 - s.lower) * taper(s.x) * bump2(s.x, s.y, 0, ym + 0.2, 2.8, 1.0) * Vector3d(0, -0.08, -0.4);
      }));
  add("mouthShrugLower",
      B([&](const Site& s) -> Vector3d { return bump2(s.x, s.y, 0, ym - 1.8, 3.2, 2.6) * Vector3d(0, 0.35, 0.25); }));
  add("mouthShrugUpper",
      B([&](const Site& s) -> Vector3d { return bump2(s.x, s.y, 0, ym + 0.8, 3.0, 1.8) * Vector3d(0, 0.25, 0.2); }));
  add_pair("mouthSmile", [&](const Site& s) -> Vector3d {
    return bump2(s.x, s.y, corner + 0.2, ym + 0.3, 2.5, 2.6) * Vector3d(0.55, 0.72, -0.18) +
           bump2(s.x, s.y, 3.4, -4.6, 2.3, 2.2) * Vector3d(0.1, 0.32, 0.15);
  });
  add_pair("mouthStretch", [&](const Site& s) -> Vector3d {
    Vector3d d = bump2(s.x, s.y, corner, ym, 2.4, 2.2) * Vector3d(0.6, -0.25, -0.2);
    d += s.lower * taper(s.x) * bump2(s.x, s.y, 1.3, ym - 0.6, 1.8, 1.5) * Vector3d(0.2, -0.2, 0);
    return d;
  });
  add_pair("mouthUpperUp", [&](const Site& s) -> Vector3d {
    return (1 - s.lower) * taper(s.x) * bump2(s.x, s.y, 1.1, ym + 0.6, 1.7, 1.4) * Vector3d(0.05, 0.5, 0.1);
  });
  add_pair("noseSneer", [&](const Site& s) -> Vector3d {
    return bump2(s.x, s.y, 1.3, -3.8, 1.3, 1.4) * Vector3d(0.05, 0.35, 0.1) +
           bump2(s.x, s.y, 1.0, 0.2, 1.0, 1.2) * Vector3d(-0.05, -0.15, 0.05);
  });
  std::sort(out.begin(), out.end(), [](const Blendshape& a, const Blendshape& b) { return a.name < b.name; });
  return out;
}

int nearest_surface_vertex(const HumanLayout& L, double x, double y) {
  int best = 0;
  double best_d = 1e300;
  for (int v = 0; v < L.surface_count; ++v) {
    if (L.grid.side[v] < 0) continue;  // prefer the upper copy on slits
    const double d = (L.xc[v] - x) * (L.xc[v] - x) + (L.yc[v] - y) * (L.yc[v] - y);
    if (d < best_d) {
      best_d = d;
      best = v;
    }
  }
  return best;
}

std::map<std::string, int> human_landmarks(const HumanLayout& L) {
  std::map<std::string, int> m;
  const double ye = L.eye_y, ym = L.mouth_y;
  for (int e = 0; e < 2; ++e) {
    const std::string side = e == 0 ? "left" : "right";
    const double s = e == 0 ? 1 : -1;
    const Slit& slit = L.eye_slit[e];
    // The chain runs from -x to +x: the inner corner of the left eye is its first vertex.
    m["eye_inner_" + side] = e == 0 ? slit.chain.front() : slit.chain.back();
    m["eye_outer_" + side] = e == 0 ? slit.chain.back() : slit.chain.front();
    m["eyelid_upper_" + side] = slit.upper[slit.upper.size() / 2];
    m["eyelid_lower_" + side] = slit.lower[slit.lower.size() / 2];
    m["brow_inner_" + side] = nearest_surface_vertex(L, s * 1.6, ye + 1.9);
    m["brow_middle_" + side] = nearest_surface_vertex(L, s * 3.1, ye + 2.2);
    m["brow_outer_" + side] = nearest_surface_vertex(L, s * 4.7, ye + 1.8);
    m["nose_wing_" + side] = nearest_surface_vertex(L, s * 1.45, -4.8);
    m["lip_upper_peak_" + side] = nearest_surface_vertex(L, s * 0.5, ym + 1.0);
    m["jaw_angle_" + side] = nearest_surface_vertex(L, s * 9.4, -8.6);
    m["jaw_" + side] = nearest_surface_vertex(L, s * 5.0, -10.8);
    m["cheekbone_" + side] = nearest_surface_vertex(L, s * 4.4, -2.3);
    m["cheek_" + side] = nearest_surface_vertex(L, s * 3.9, -5.2);
    m["temple_" + side] = nearest_surface_vertex(L, s * 6.4, 2.0);
  }
  m["mouth_left"] = L.mouth.chain.back();
  m["mouth_right"] = L.mouth.chain.front();
  m["lip_upper_center"] = L.mouth.upper[L.mouth.upper.size() / 2];
  m["lip_lower_center"] = L.mouth.lower[L.mouth.lower.size() / 2];
  m["lip_upper_top"] = nearest_surface_vertex(L, 0, ym + 0.98);
  m["lip_lower_bottom"] = nearest_surface_vertex(L, 0, ym - 1.1);
  m["forehead"] = nearest_surface_vertex(L, 0, 5.5);
  m["nose_bridge"] = nearest_surface_vertex(L, 0, 0.6);
  m["nose_tip"] = nearest_surface_vertex(L, 0, -4.35);
  m["nose_base"] = nearest_surface_vertex(L, 0, -5.45);
  m["chin"] = nearest_surface_vertex(L, 0, -10.4);
  m["chin_bottom"] = nearest_surface_vertex(L, 0, -11.8);
  return m;
}

}  // namespace

const std::vector<std::string>& synthetic_expression_names() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> n;
    for (const char* stem : {"browDown", "browInnerUp", "browOuterUp", "cheekPuff", "cheekSquint", "eyeBlink",
                             "eyeSquint", "eyeWide", "mouthDimple", "mouthFrown", "mouthLowerDown", "mouthPress",
                             "mouthSmile", "mouthStretch", "mouthUpperUp", "noseSneer"}) {
      n.push_back(std::string(stem) + "_L");
      n.push_back(std::string(stem) + "_R");
    }
    for (const char* name :
         {"jawForward", "jawLeft", "jawOpen", "jawRight", "mouthClose", "mouthFunnel", "mouthLeft", "mouthPucker",
          "mouthRight", "mouthRollLower", "mouthRollUpper", "mouthShrugLower", "mouthShrugUpper"})
      n.push_back(name);
    std::sort(n.begin(), n.end());
    return n;
  }();
  return names;
}

const std::vector<std::string>& synthetic_landmark_names() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> n;
    for (const auto& entry : human_landmarks(layout())) n.push_back(entry.first);
    return n;
  }();
  return names;
}

FaceModel synthetic_human(uint64_t seed) {
  const HumanLayout& L = layout();
  Random random(seed);
  // The model's mean face: about half a standard deviation away from the nominal face.
  Params mean{};
  for (int k = 0; k < kParamCount; ++k) mean[k] = 0.5 * kParams[k].sigma * random.normal();
  const LidState open[2] = {kOpen, kOpen};
  const Positions neutral = human_shape(mean, open).V;

  FaceModel model;
  model.name = "synthetic-human";
  model.source = "synthetic_human(seed " + std::to_string(seed) + ")";
  model.units = "cm";
  model.neutral = with_positions(L.mesh, neutral);
  model.neutral.source = "";
  for (int k = 0; k < kParamCount; ++k) {
    Params shifted = mean;
    shifted[k] += kParams[k].sigma;
    char name[64];
    std::snprintf(name, sizeof(name), "identity%02d_%s", k, kParams[k].name);
    model.identities.push_back({name, human_shape(shifted, open).V - neutral});
  }
  model.expressions = human_expressions(mean, neutral);
  model.landmarks = human_landmarks(L);
  for (int e = 0; e < 2; ++e) {
    std::vector<int>& set = e == 0 ? model.eyes.left : model.eyes.right;
    set = L.eye_slit[e].chain;
    set.insert(set.end(), L.eye_slit[e].lower.begin(), L.eye_slit[e].lower.end());
  }
  return model;
}

}  // namespace retarget
