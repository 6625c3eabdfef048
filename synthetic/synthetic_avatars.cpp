// The stylized avatars of synthetic_faces.h. Each is a "toon": a parameter grid of its own
// kind (a latitude-longitude sphere, an open height-field grid, an ellipsoid with side poles)
// laid out in canonical (x, y) cm, a base surface, relief along the base normal, eyelids cut
// and open over eyeball caps, a mouth cut along a grid line, and extra parts (ears, antennae).
// Controllers are displacement fields over the canonical layout, lid states evaluated through
// the shape itself, or motions of the parts.
#include <Eigen/Geometry>
#include <cmath>

#include "synthetic/synthetic_faces.h"
#include "synthetic/synthetic_surface.h"

namespace retarget {

namespace {

using namespace synth;
using Eigen::Vector2d;
using Eigen::Vector3d;

struct Toon {
  GridMesh grid;
  Mesh mesh;  // grid + eyeball caps + parts, triangulated
  int surface_count = 0;
  std::vector<double> xc, yc;
  EyeLayout eye[2];  // 0: left (+x), 1: right
  Slit eye_slit[2];
  LidState open;
  Slit mouth;
  MouthLayout mouth_layout;
  std::function<Vector3d(double, double)> surface;  // canonical (x, y) -> base point
  std::function<double(double, double)> relief;     // along the base normal at canonical (x, y), cm
  std::function<Vector2d(double, double)> warp;     // optional fixed canonical warp
  Vector2d eye_centre[2];
  double ball_radius = 1, ball_recess = 0, lid = 0.2, cornea = 0.1;  // lid: thickness in the middle
  int ball_first[2] = {0, 0};
  Positions cap;
  EyeLiner liner;  // under the skin around the eye (see EyeLiner)
  // The mouth pocket (see pocket_grid): its vertices follow the skin's, with canonical
  // coordinates; half height and depth in cm, half width a fraction of the mouth's.
  int pocket_first = 0, pocket_columns = 13, pocket_rows = 8;
  double pocket_width = 1.08, pocket_height = 0.6, pocket_depth = 1.5, pocket_inset = 0.25;
  std::vector<double> lower;  // per skin and pocket vertex: share of the lower lip side
};

Vector3d base_normal(const Toon& t, double x, double y) {
  const double h = 1e-3;
  const Vector3d dx = t.surface(x + h, y) - t.surface(x - h, y), dy = t.surface(x, y + h) - t.surface(x, y - h);
  const Vector3d n = dx.cross(dy);
  return n.norm() > 0 ? Vector3d(n.normalized()) : Vector3d::UnitZ();
}

Vector2d warped(const Toon& t, double x, double y) { return t.warp ? t.warp(x, y) : Vector2d(x, y); }

// A point on the skin at canonical (x, y): base surface plus relief (no eyeball push).
Vector3d skin_point(const Toon& t, double x, double y) {
  const Vector2d w = warped(t, x, y);
  Vector3d P = t.surface(w.x(), w.y());
  const double r = t.relief(x, y);
  if (r != 0) P += r * base_normal(t, w.x(), w.y());
  return P;
}

struct ToonPose {
  LidState lids[2];
  double ball_scale = 1;  // eyeball radius factor (the centre stays)
};

// Surface and eyeball positions (#V x 3; parts left at zero).
Positions toon_positions(const Toon& t, const ToonPose& pose) {
  Positions V = Positions::Zero(t.mesh.vertex_count(), 3);
  Eyeball balls[2];
  Vector3d axes[2];
  for (int e = 0; e < 2; ++e) {
    const Vector2d c = warped(t, t.eye_centre[e].x(), t.eye_centre[e].y());
    const Vector3d n = base_normal(t, c.x(), c.y());
    balls[e].centre = t.surface(c.x(), c.y()) - n * (t.ball_recess + t.ball_radius);
    balls[e].radius = t.ball_radius * pose.ball_scale;
    axes[e] = n;
  }
  for (int v = 0; v < t.surface_count; ++v) {
    const double x = t.xc[v], y = t.yc[v];
    double dy = 0;
    for (int e = 0; e < 2; ++e)
      dy += t.eye[e].lid_shift(x, y, slit_side(t.grid, v, t.eye[e].slit, y, t.eye[e].y), pose.lids[e]);
    const Vector2d w = warped(t, x, y + dy);
    Vector3d P = t.surface(w.x(), w.y());
    const double r = t.relief(x, y);
    if (r != 0) P += r * base_normal(t, w.x(), w.y());
    for (int e = 0; e < 2; ++e) {
      const Eyeball& ball = balls[e];
      if ((P - ball.centre).norm() > ball.radius + 1.5) continue;
      const double lid =
          t.eye[e].lid_thickness(x, t.lid * (slit_side(t.grid, v, e, y, t.eye[e].y) > 0 ? 1.2 : 1.0), 0.3 * t.lid);
      P = ball.push(P, base_normal(t, w.x(), w.y()), lid);
    }
    V.row(v) = P.transpose();
  }
  for (int k = 0; k < t.pocket_columns * t.pocket_rows; ++k) {
    const int v = t.pocket_first + k;
    const double s = -1 + 2.0 * (k % t.pocket_columns) / (t.pocket_columns - 1);
    const double u = -1 + 2.0 * (k / t.pocket_columns) / (t.pocket_rows - 1);
    const Vector2d w = warped(t, t.xc[v], t.yc[v]);
    const Vector3d n = base_normal(t, w.x(), w.y());
    V.row(v) =
        (skin_point(t, t.xc[v], t.yc[v]) - n * (t.pocket_inset + t.pocket_depth * pocket_depth(s, u))).transpose();
  }
  for (int e = 0; e < 2; ++e)
    V.middleRows(t.ball_first[e], t.cap.rows()) = place_eyeball(t.cap, balls[e], t.cornea, axes[e], axes[e], t.liner);
  return V;
}

// Canonical coordinates of the grid vertices and the eye layouts, once the grid is cut.
void finish_layout(Toon& t, const std::function<Vector2d(int v)>& canonical, int cap_rings, int cap_segments) {
  t.surface_count = t.grid.vertex_count();
  t.xc.resize(t.surface_count);
  t.yc.resize(t.surface_count);
  for (int v = 0; v < t.surface_count; ++v) {
    const Vector2d c = canonical(v);
    t.xc[v] = c.x();
    t.yc[v] = c.y();
  }
  for (int e = 0; e < 2; ++e) {
    const Slit& s = t.eye_slit[e];
    t.eye[e].x_in = t.xc[s.chain.front()];
    t.eye[e].x_out = t.xc[s.chain.back()];
    t.eye[e].y = t.yc[s.chain.front()];
    t.eye[e].slit = e;
  }
  t.mouth_layout.y = t.yc[t.mouth.chain.front()];
  t.mouth_layout.corner = t.xc[t.mouth.chain.back()];
  t.mesh = t.grid.mesh;
  for (int v = 0; v < t.surface_count; ++v)
    t.lower.push_back(slit_side(t.grid, v, 2, t.yc[v], t.mouth_layout.y) < 0 ? 1.0 : 0.0);
  t.pocket_first = append_part(t.mesh, pocket_grid(t.pocket_columns, t.pocket_rows));
  for (int j = 0; j < t.pocket_rows; ++j)
    for (int i = 0; i < t.pocket_columns; ++i) {
      const double s = -1 + 2.0 * i / (t.pocket_columns - 1), u = -1 + 2.0 * j / (t.pocket_rows - 1);
      t.xc.push_back(s * t.pocket_width * t.mouth_layout.corner);
      t.yc.push_back(t.mouth_layout.y + u * t.pocket_height);
      t.lower.push_back(pocket_lower(u));
    }
  const Mesh cap = unit_cap(cap_rings + 2, cap_segments, kEyeballRim * (cap_rings + 2) / cap_rings);
  t.cap = cap.vertices;
  t.ball_first[0] = append_part(t.mesh, cap);
  t.ball_first[1] = append_part(t.mesh, cap);
}

int nearest_index(const std::vector<double>& values, double target) {
  int best = 0;
  for (int k = 1; k < static_cast<int>(values.size()); ++k)
    if (std::abs(values[k] - target) < std::abs(values[best] - target)) best = k;
  return best;
}

// Makes values[k] = -values[n - 1 - k] (the grid's left-right symmetry).
void symmetrize(std::vector<double>& values, double centre = 0) {
  const size_t n = values.size();
  for (size_t k = 0; k < n / 2; ++k) {
    const double half = 0.5 * ((values[n - 1 - k] - centre) - (values[k] - centre));
    values[k] = centre - half;
    values[n - 1 - k] = centre + half;
  }
  if (n % 2) values[n / 2] = centre;
}

int nearest_vertex(const Toon& t, double x, double y) {
  int best = 0;
  double best_d = 1e300;
  for (int v = 0; v < t.surface_count; ++v) {
    if (t.grid.side[v] < 0) continue;
    const double d = (t.xc[v] - x) * (t.xc[v] - x) + (t.yc[v] - y) * (t.yc[v] - y);
    if (d < best_d) {
      best_d = d;
      best = v;
    }
  }
  return best;
}

// Landmarks every toon has: eye corners and lid midpoints, mouth corners and lip midpoints.
std::map<std::string, int> slit_landmarks(const Toon& t) {
  std::map<std::string, int> m;
  for (int e = 0; e < 2; ++e) {
    const std::string side = e == 0 ? "left" : "right";
    const Slit& s = t.eye_slit[e];
    // Chains run from -x to +x.
    m["eye_inner_" + side] = e == 0 ? s.chain.front() : s.chain.back();
    m["eye_outer_" + side] = e == 0 ? s.chain.back() : s.chain.front();
    m["eyelid_upper_" + side] = s.upper[s.upper.size() / 2];
    m["eyelid_lower_" + side] = s.lower[s.lower.size() / 2];
  }
  m["mouth_left"] = t.mouth.chain.back();
  m["mouth_right"] = t.mouth.chain.front();
  m["lip_upper_center"] = t.mouth.upper[t.mouth.upper.size() / 2];
  m["lip_lower_center"] = t.mouth.lower[t.mouth.lower.size() / 2];
  return m;
}

// Landmarks at canonical positions: name -> (x, y); "_left" names are mirrored to "_right".
void add_landmarks(const Toon& t, std::map<std::string, int>& m,
                   const std::vector<std::pair<std::string, Vector2d>>& points) {
  for (const auto& [name, p] : points) {
    const size_t cut = name.rfind("_left");
    if (cut != std::string::npos && cut + 5 == name.size()) {
      m[name] = nearest_vertex(t, p.x(), p.y());
      m[name.substr(0, cut) + "_right"] = nearest_vertex(t, -p.x(), p.y());
    } else {
      m[name] = nearest_vertex(t, p.x(), p.y());
    }
  }
}

EyeLandmarks eye_sets(const Toon& t) {
  EyeLandmarks eyes;
  for (int e = 0; e < 2; ++e) {
    std::vector<int>& set = e == 0 ? eyes.left : eyes.right;
    set = t.eye_slit[e].chain;
    set.insert(set.end(), t.eye_slit[e].lower.begin(), t.eye_slit[e].lower.end());
  }
  return eyes;
}

// Collects controllers and their correspondence rows.
struct RigBuilder {
  SyntheticAvatar avatar;
  void add(const std::string& name, const Positions& offset, std::map<std::string, double> human) {
    avatar.rig.controllers.push_back({name, offset, 0.0, 1.0});
    avatar.correspondence[name] = std::move(human);
  }
};

Positions lid_offset(const Toon& t, const Positions& rest, int eye, LidState state) {
  ToonPose pose;
  pose.lids[0] = pose.lids[1] = t.open;
  pose.lids[eye] = state;
  Positions V = toon_positions(t, pose);
  // Parts are not part of toon_positions: keep their rows unchanged.
  V.bottomRows(V.rows() - t.ball_first[1] - t.cap.rows()) = rest.bottomRows(V.rows() - t.ball_first[1] - t.cap.rows());
  return V - rest;
}

// The jaw: rotation by `angle` (radians, opening) about the x axis through `pivot`.
Vector3d jaw_motion(const Vector3d& P, const Vector3d& pivot, double angle, const Vector3d& shift = Vector3d::Zero()) {
  const Eigen::Matrix3d R = Eigen::AngleAxisd(angle, Vector3d::UnitX()).toRotationMatrix();
  return (R - Eigen::Matrix3d::Identity()) * (P - pivot) + shift;
}

// Controllers every toon shares in form: blinks, squints or wide eyes, brows, smiles, frowns,
// jaw. Sizes come from the toon's own proportions.
struct CommonSizes {
  LidState blink, squint, wide;
  bool with_squint = true, with_wide = false;
  Vector3d brow_up_centre, brow_up_radii;  // (x, y) centre, (rx, ry) radii; z of the vector unused
  double brow_up = 0.6;
  Vector3d brow_down_centre, brow_down_radii;
  double brow_down = 0.45;
  bool brows_down_together = false;
  Vector2d smile_radii;
  Vector3d smile;  // corner motion (x out, y up, z)
  Vector2d frown_radii;
  double frown = 0.5;
  Vector3d jaw_pivot;
  double jaw_angle = 0.3;
};

void add_common(RigBuilder& b, const Toon& t, const Positions& rest, const FieldEvaluator& F, const CommonSizes& c) {
  const double corner = t.mouth_layout.corner, ym = t.mouth_layout.y;
  for (int e = 0; e < 2; ++e) {
    const std::string side = e == 0 ? "Left" : "Right", human = e == 0 ? "_L" : "_R";
    b.add("blink" + side, lid_offset(t, rest, e, c.blink), {{"eyeBlink" + human, 1.0}});
  }
  if (c.with_squint)
    for (int e = 0; e < 2; ++e) {
      const std::string side = e == 0 ? "Left" : "Right", human = e == 0 ? "_L" : "_R";
      b.add("squint" + side, lid_offset(t, rest, e, c.squint), {{"eyeSquint" + human, 1.0}});
    }
  if (c.with_wide)
    for (int e = 0; e < 2; ++e) {
      const std::string side = e == 0 ? "Left" : "Right", human = e == 0 ? "_L" : "_R";
      b.add("eyeWide" + side, lid_offset(t, rest, e, c.wide), {{"eyeWide" + human, 1.0}});
    }
  const Field brow_up = [&](const Site& s) -> Vector3d {
    return c.brow_up *
           bump2(s.x, s.y, c.brow_up_centre.x(), c.brow_up_centre.y(), c.brow_up_radii.x(), c.brow_up_radii.y()) *
           Vector3d(0, 1, 0.05);
  };
  b.add("browUpLeft", F(brow_up), {{"browInnerUp_L", 1.0}, {"browOuterUp_L", 1.0}});
  b.add("browUpRight", F(brow_up, true), {{"browInnerUp_R", 1.0}, {"browOuterUp_R", 1.0}});
  const Field brow_down = [&](const Site& s) -> Vector3d {
    return c.brow_down *
           bump2(s.x, s.y, c.brow_down_centre.x(), c.brow_down_centre.y(), c.brow_down_radii.x(),
                 c.brow_down_radii.y()) *
           Vector3d(-0.35, -1, 0.2);
  };
  if (c.brows_down_together) {
    b.add("browsDown", Positions(F(brow_down) + F(brow_down, true)), {{"browDown_L", 1.0}, {"browDown_R", 1.0}});
  } else {
    b.add("browDownLeft", F(brow_down), {{"browDown_L", 1.0}});
    b.add("browDownRight", F(brow_down, true), {{"browDown_R", 1.0}});
  }
  const Field smile = [&](const Site& s) -> Vector3d {
    return bump2(s.x, s.y, corner + 0.15 * c.smile_radii.x(), ym + 0.1 * c.smile_radii.y(), c.smile_radii.x(),
                 c.smile_radii.y()) *
           c.smile;
  };
  b.add("smileLeft", F(smile), {{"mouthSmile_L", 1.0}});
  b.add("smileRight", F(smile, true), {{"mouthSmile_R", 1.0}});
  const Field frown = [&](const Site& s) -> Vector3d {
    return c.frown * bump2(s.x, s.y, corner, ym - 0.1 * c.frown_radii.y(), c.frown_radii.x(), c.frown_radii.y()) *
           Vector3d(0.1, -1, 0);
  };
  b.add("frownLeft", F(frown), {{"mouthFrown_L", 1.0}});
  b.add("frownRight", F(frown, true), {{"mouthFrown_R", 1.0}});
}

Positions jaw_open(const Toon& t, const FieldEvaluator& F, const Vector3d& pivot, double angle, const Vector3d& shift) {
  return F(
      [&](const Site& s) -> Vector3d { return t.mouth_layout.jaw_weight(s) * jaw_motion(s.P, pivot, angle, shift); });
}

// ------------------------------------------------------------------------------------------
// moppet: a round chibi head on a latitude-longitude sphere, huge eyes, a tiny mouth.

SyntheticAvatar moppet() {
  const double A = 9.0, B = 8.4, C = 8.6;  // head semi-axes (cm)
  const int around = 64, rings = 44;
  Toon t;
  std::vector<double> lon =
      graded_samples(-M_PI, M_PI, around + 1, [](double l) { return 1 + 4.0 * std::exp(-l * l / 0.64); });
  symmetrize(lon);
  lon.pop_back();  // -pi and pi are one column
  const std::vector<double> lat = graded_samples(-M_PI / 2, M_PI / 2, rings + 1, [](double b) {
    const double u = (b + 0.2) / 0.6;
    return 1 + 2.5 * std::exp(-u * u);
  });
  std::vector<double> xs(around), ys(rings + 1);
  for (int i = 0; i < around; ++i) xs[i] = A * lon[i];
  for (int j = 0; j <= rings; ++j) ys[j] = B * lat[j];
  const int front = around / 2;  // lon = 0

  t.grid = latlong_grid(around, rings);
  const double eye_x = 4.1, eye_y = -0.8, eye_half = 2.5;
  const int eye_row = nearest_index(ys, eye_y);
  const int eye_in = nearest_index(xs, eye_x - eye_half), eye_out = nearest_index(xs, eye_x + eye_half);
  t.eye_slit[0] = cut_row_slit(t.grid, eye_row, eye_in, eye_out, 0);
  t.eye_slit[1] = cut_row_slit(t.grid, eye_row, 2 * front - eye_out, 2 * front - eye_in, 1);
  const int mouth_row = nearest_index(ys, -4.6), mouth_corner = nearest_index(xs, 1.0);
  t.mouth = cut_row_slit(t.grid, mouth_row, 2 * front - mouth_corner, mouth_corner, 2);
  t.pocket_columns = 9;
  t.pocket_height = 0.55;
  t.pocket_depth = 1.3;
  finish_layout(
      t,
      [&](int v) {
        return t.grid.gi[v] < 0 ? Vector2d(0, ys[t.grid.gj[v]]) : Vector2d(xs[t.grid.gi[v]], ys[t.grid.gj[v]]);
      },
      8, 22);
  for (EyeLayout& e : t.eye) {
    e.upper_fall = 3.4;
    e.lower_fall = 2.7;
  }
  t.open = {1.6, 1.3};
  t.eye_centre[0] = {eye_x, t.eye[0].y};
  t.eye_centre[1] = {-eye_x, t.eye[1].y};
  t.ball_radius = 3.05;
  t.ball_recess = -0.1;
  t.liner = {0.8, -0.1};
  t.cornea = 0.18;
  t.lid = 0.3;
  t.mouth_layout.corner = xs[mouth_corner];
  t.mouth_layout.taper = 0.75;
  t.mouth_layout.rise = 0.3;
  t.mouth_layout.band = 0.8;
  t.mouth_layout.band_growth = 0.3;
  t.mouth_layout.reach = 3.0;
  t.mouth_layout.floor = -9.5;
  t.mouth_layout.floor_fade = 3.5;
  const double ym = t.mouth_layout.y;
  t.surface = [=](double x, double y) {
    const double l = x / A, b = std::clamp(y / B, -M_PI / 2, M_PI / 2);
    return Vector3d(A * std::cos(b) * std::sin(l), B * std::sin(b), C * std::cos(b) * std::cos(l));
  };
  t.relief = [=](double x, double y) {
    const double ax = std::abs(x);
    return 0.55 * bump2(ax, y, 4.6, -3.9, 2.0, 1.6) + 0.35 * bump2(x, y, 0, -3.0, 0.55, 0.45) +
           0.3 * bump2(ax, y, 4.1, 3.5, 1.9, 0.45) + 2.2 * bump2(ax, y, A * M_PI / 2, -0.8, 1.7, 2.4) +
           0.18 * bump2(x, y, 0, ym, 1.5, 0.6) + 0.2 * bump2(x, y, 0, -6.3, 2.0, 1.0) +
           0.9 * bump2(x, y, 0, B * 1.2, 3.0, 1.6);
  };
  t.mesh.source = "";
  triangulate(t.mesh);

  ToonPose rest_pose;
  rest_pose.lids[0] = rest_pose.lids[1] = t.open;
  const Positions rest = toon_positions(t, rest_pose);
  const FieldEvaluator F(t.lower, t.xc, t.yc, t.surface_count, t.mesh, rest);
  RigBuilder b;
  b.avatar.description = "round chibi head (latitude-longitude sphere), huge eyes, tiny mouth";
  CommonSizes c;
  c.blink = {-0.9, 0.9};
  c.squint = {0.95, 0.75};
  c.wide = {2.1, 1.5};
  c.with_wide = true;
  c.brow_up_centre = {4.1, 3.5, 0};
  c.brow_up_radii = {2.8, 1.8, 0};
  c.brow_up = 0.8;
  c.brow_down_centre = {3.9, 3.3, 0};
  c.brow_down_radii = {2.6, 1.2, 0};
  c.brow_down = 0.5;
  c.smile_radii = {1.6, 1.5};
  c.smile = {0.35, 0.5, -0.1};
  c.frown_radii = {1.5, 1.5};
  c.frown = 0.4;
  add_common(b, t, rest, F, c);
  b.add("mouthOpen", jaw_open(t, F, {0, -3.0, 2.0}, 0.25, Vector3d::Zero()), {{"jawOpen", 1.0}});
  b.add("pucker", F([&](const Site& s) -> Vector3d {
          const double r = bump2(s.x, s.y, 0, ym, 1.6, 1.1);
          return Vector3d(-0.3 * s.x * r, 0, 0.5 * r);
        }),
        {{"mouthPucker", 1.0}});
  const Field shift = [&](const Site& s) -> Vector3d { return bump2(s.x, s.y, 0, ym, 2.2, 1.5) * Vector3d(0.6, 0, 0); };
  b.add("mouthLeft", F(shift), {{"mouthLeft", 1.0}});
  b.add("mouthRight", F(shift, true), {{"mouthRight", 1.0}});
  b.add("cheeksPuff", F([&](const Site& s) -> Vector3d {
          return 0.9 * (bump2(s.x, s.y, 4.4, -4.0, 2.3, 1.9) + bump2(s.x, s.y, -4.4, -4.0, 2.3, 1.9)) * s.n;
        }),
        {{"cheekPuff_L", 1.0}, {"cheekPuff_R", 1.0}});
  // Without human counterparts: a cartoon squash of the whole head, and eyes that pop.
  {
    Positions squash(rest.rows(), 3);
    const Eigen::RowVector3d base(0, -B, 0), scale(0.08, -0.14, 0.08);
    for (int v = 0; v < rest.rows(); ++v) squash.row(v) = (rest.row(v) - base).cwiseProduct(scale);
    b.add("headSquash", squash, {});
  }
  {
    ToonPose pop = rest_pose;
    pop.ball_scale = 1.25;
    b.add("eyePop", Positions(toon_positions(t, pop) - rest), {});
  }

  Rig& rig = b.avatar.rig;
  rig.name = "moppet";
  rig.units = "cm";
  rig.neutral = with_positions(t.mesh, rest);
  rig.landmarks = slit_landmarks(t);
  add_landmarks(t, rig.landmarks,
                {{"brow_inner_left", {2.6, 3.4}},
                 {"brow_middle_left", {4.1, 3.6}},
                 {"brow_outer_left", {5.6, 3.3}},
                 {"nose_tip", {0, -3.0}},
                 {"cheek_left", {4.6, -3.9}},
                 {"chin", {0, -6.4}},
                 {"forehead", {0, 5.8}},
                 {"temple_left", {7.2, 1.8}},
                 {"jaw_left", {4.0, -6.6}}});
  rig.eyes = eye_sets(t);
  return b.avatar;
}

// ------------------------------------------------------------------------------------------
// fox: an open front-facing height-field grid with a long snout and two cone ears.

SyntheticAvatar fox() {
  const int ni = 61, nj = 57;
  Toon t;
  std::vector<double> xs(ni), ys(nj);
  for (int i = 0; i < ni; ++i) xs[i] = -8.5 + 17.0 * i / (ni - 1);
  for (int j = 0; j < nj; ++j) ys[j] = -9.0 + 18.0 * j / (nj - 1);
  symmetrize(xs);
  t.grid = open_grid(ni, nj);
  const int centre = ni / 2;
  const double eye_x = 3.5, eye_half = 1.4;
  const int eye_row = nearest_index(ys, 1.8);
  const int eye_in = nearest_index(xs, eye_x - eye_half), eye_out = nearest_index(xs, eye_x + eye_half);
  t.eye_slit[0] = cut_row_slit(t.grid, eye_row, eye_in, eye_out, 0);
  t.eye_slit[1] = cut_row_slit(t.grid, eye_row, 2 * centre - eye_out, 2 * centre - eye_in, 1);
  const int mouth_row = nearest_index(ys, -5.0), mouth_corner = nearest_index(xs, 2.0);
  t.mouth = cut_row_slit(t.grid, mouth_row, 2 * centre - mouth_corner, mouth_corner, 2);
  t.pocket_height = 1.2;
  t.pocket_depth = 2.2;
  t.pocket_inset = 0.35;
  finish_layout(
      t, [&](int v) { return Vector2d(xs[t.grid.gi[v]], ys[t.grid.gj[v]]); }, 6, 16);
  for (EyeLayout& e : t.eye) {
    e.upper_fall = 2.0;
    e.lower_fall = 1.3;
  }
  t.open = {0.75, 0.55};
  t.eye_centre[0] = {eye_x, t.eye[0].y};
  t.eye_centre[1] = {-eye_x, t.eye[1].y};
  t.ball_radius = 1.75;
  t.ball_recess = 0.2;
  t.liner = {1.6, 0.3};
  t.cornea = 0.15;
  t.mouth_layout.corner = xs[mouth_corner];
  t.mouth_layout.taper = 1.1;
  t.mouth_layout.rise = 0.3;
  t.mouth_layout.band = 0.9;
  t.mouth_layout.band_growth = 0.3;
  t.mouth_layout.reach = 4.5;
  const double ym = t.mouth_layout.y;
  // The square grid is mapped onto an elliptical disc (half axes 9.5 x 10 cm) domed forwards.
  t.surface = [](double x, double y) {
    const double u = std::clamp(x / 8.5, -1.0, 1.0), v = std::clamp(y / 9.0, -1.0, 1.0);
    const double px = 9.5 * u * std::sqrt(1 - 0.5 * v * v), py = 10.0 * v * std::sqrt(1 - 0.5 * u * u);
    const double q = (px / 9.5) * (px / 9.5) + (py / 10.0) * (py / 10.0);
    return Vector3d(px, py, 7.0 * (std::sqrt(std::max(0.0, 1.04 - q)) - 0.2));
  };
  // A long snout: a ridge from the forehead to the nose at its tip, then down to the chin.
  static const Profile snout_height({-8.5, -7.5, -6.2, -5.0, -4.1, -3.3, -2.0, 0.0, 1.6},
                                    {0, 0.3, 1.6, 3.1, 4.6, 5.4, 4.0, 1.6, 0});
  static const Profile snout_width({-7.0, -5.0, -3.3, -1.0, 1.5}, {2.6, 1.8, 1.3, 2.2, 2.6});
  t.relief = [=](double x, double y) {
    const double ax = std::abs(x);
    return snout_height(y) * bump(x / (1.6 * snout_width(y))) + 0.7 * bump2(x, y, 0, -3.3, 0.9, 0.7) +
           0.4 * bump2(ax, y, 1.3, -4.4, 1.1, 0.9) + 0.7 * bump2(ax, y, 5.2, -2.2, 2.6, 2.6) +
           0.45 * bump2(ax, y, 3.3, 3.5, 1.9, 0.6) - 0.7 * bump2(ax, y, 3.5, 1.8, 2.3, 1.9) +
           0.2 * bump2(x, y, 0, ym, 2.2, 0.5) + 0.4 * bump2(x, y, 0, -6.6, 1.8, 1.0);
  };

  // Ears: flattened cones standing on the top corners of the face.
  const int ear_rings = 7, ear_segments = 14;
  const Mesh ear = cone_part(ear_rings, ear_segments);
  const int ear_first[2] = {append_part(t.mesh, ear), append_part(t.mesh, ear)};
  triangulate(t.mesh);
  // Ear e at the pose (wiggle: sideways tilt about the ear's front axis; back: about its
  // lateral axis, tips backwards), written into V.
  auto place_ears = [&](Positions& V, const double wiggle[2], double back) {
    for (int e = 0; e < 2; ++e) {
      const double s = e == 0 ? 1 : -1;
      const Vector3d base = skin_point(t, s * 5.3, 7.2) - Vector3d(0, 0, 0.5);
      Vector3d d = Vector3d(s * 0.35, 1.0, -0.15).normalized();
      Vector3d l = (Vector3d(s, 0, 0) - d * d.x() * s).normalized();
      Vector3d f = d.cross(l).normalized();
      const Eigen::Matrix3d R =
          (Eigen::AngleAxisd(-back * s, l) * Eigen::AngleAxisd(-s * wiggle[e], f)).toRotationMatrix();
      d = R * d;
      l = R * l;
      f = R * f;
      for (int r = 0; r < ear_rings; ++r) {
        const double u = static_cast<double>(r) / ear_rings;
        const double width = 1.9 * std::pow(1 - u, 0.8), depth = 0.6 * std::pow(1 - u, 0.8);
        for (int k = 0; k < ear_segments; ++k) {
          const double phi = 2 * M_PI * k / ear_segments;
          V.row(ear_first[e] + r * ear_segments + k) =
              (base + 5.8 * u * d + width * std::cos(phi) * l + depth * std::sin(phi) * f).transpose();
        }
      }
      V.row(ear_first[e] + ear_rings * ear_segments) = (base + 5.8 * d).transpose();
    }
  };

  ToonPose rest_pose;
  rest_pose.lids[0] = rest_pose.lids[1] = t.open;
  Positions rest = toon_positions(t, rest_pose);
  const double still[2] = {0, 0};
  place_ears(rest, still, 0);
  const FieldEvaluator F(t.lower, t.xc, t.yc, t.surface_count, t.mesh, rest);
  RigBuilder b;
  b.avatar.description = "open grid on a domed disc, long snout, cone ears";
  CommonSizes c;
  c.blink = {-0.4, 0.4};
  c.squint = {0.4, 0.3};
  c.brow_up_centre = {3.3, 3.6, 0};
  c.brow_up_radii = {2.4, 1.6, 0};
  c.brow_down_centre = {3.0, 3.7, 0};
  c.brow_down_radii = {2.2, 1.1, 0};
  c.smile_radii = {2.0, 1.8};
  c.smile = {0.35, 0.55, -0.15};
  c.frown_radii = {1.8, 1.6};
  add_common(b, t, rest, F, c);
  const Field snarl = [&](const Site& s) -> Vector3d {
    Vector3d d = bump2(s.x, s.y, 1.0, -2.0, 1.4, 1.3) * Vector3d(0, 0.3, 0.1);
    d += (1 - s.lower) * t.mouth_layout.parting(s.x) * bump2(s.x, s.y, 1.3, ym + 0.5, 1.6, 1.3) *
         Vector3d(0, 0.45, 0.05);
    return d;
  };
  b.add("snarlLeft", F(snarl), {{"noseSneer_L", 1.0}, {"mouthUpperUp_L", 1.0}});
  b.add("snarlRight", F(snarl, true), {{"noseSneer_R", 1.0}, {"mouthUpperUp_R", 1.0}});
  b.add("jawOpen", jaw_open(t, F, {0, -3.5, 2.5}, 0.35, Vector3d::Zero()), {{"jawOpen", 1.0}});
  b.add("pucker", F([&](const Site& s) -> Vector3d {
          const double r = bump2(s.x, s.y, 0, ym, 2.6, 1.4);
          return Vector3d(-0.3 * s.x * r, 0, 0.5 * r);
        }),
        {{"mouthPucker", 1.0}});
  const Field puff = [&](const Site& s) -> Vector3d { return 0.9 * bump2(s.x, s.y, 4.0, -4.5, 2.2, 2.0) * s.n; };
  b.add("cheekPuffLeft", F(puff), {{"cheekPuff_L", 1.0}});
  b.add("cheekPuffRight", F(puff, true), {{"cheekPuff_R", 1.0}});
  // Without human counterparts: ears and a snout twitch.
  for (int e = 0; e < 2; ++e) {
    Positions moved = rest;
    const double wiggle[2] = {e == 0 ? 0.45 : 0.0, e == 1 ? 0.45 : 0.0};
    place_ears(moved, wiggle, 0);
    b.add(e == 0 ? "earWiggleLeft" : "earWiggleRight", Positions(moved - rest), {});
  }
  {
    Positions moved = rest;
    place_ears(moved, still, 0.6);
    b.add("earsBack", Positions(moved - rest), {});
  }
  b.add("snoutTwitch",
        F([&](const Site& s) -> Vector3d { return bump2(s.x, s.y, 0, -3.3, 1.8, 1.5) * Vector3d(0.5, 0.2, 0); }), {});

  Rig& rig = b.avatar.rig;
  rig.name = "fox";
  rig.units = "cm";
  rig.neutral = with_positions(t.mesh, rest);
  rig.landmarks = slit_landmarks(t);
  add_landmarks(t, rig.landmarks,
                {{"brow_inner_left", {2.2, 3.4}},
                 {"brow_middle_left", {3.3, 3.6}},
                 {"brow_outer_left", {4.5, 3.4}},
                 {"nose_tip", {0, -3.3}},
                 {"nose_bridge", {0, 1.2}},
                 {"cheek_left", {5.2, -2.2}},
                 {"chin", {0, -6.6}},
                 {"forehead", {0, 5.5}},
                 {"temple_left", {6.2, 3.0}},
                 {"jaw_left", {4.5, -6.5}}});
  rig.eyes = eye_sets(t);
  return b.avatar;
}

// ------------------------------------------------------------------------------------------
// glorp: a wide, flat ellipsoid whose poles are its left and right ends (rings about the x
// axis), a wide grinning mouth, small protruding eyes far apart, two antennae.

SyntheticAvatar glorp() {
  const double A = 12.0, B = 5.5, C = 6.5;
  const int around = 52, rings = 70;
  Toon t;
  std::vector<double> theta = graded_samples(-M_PI, M_PI, around + 1, [](double a) {
    const double u = (a - 0.2) / 0.7;
    return 1 + 2.5 * std::exp(-u * u);
  });
  theta.pop_back();
  std::vector<double> psi = graded_samples(0, M_PI, rings + 1, [](double p) {
    const double u = (p - M_PI / 2) / 0.7;
    return 1 + 1.2 * std::exp(-u * u);
  });
  symmetrize(psi, M_PI / 2);
  std::vector<double> xs(rings + 1), ys(around);
  for (int j = 0; j <= rings; ++j) xs[j] = -A * std::cos(psi[j]);
  for (int i = 0; i < around; ++i) ys[i] = B * theta[i];

  // i runs around the x axis (theta, the vertical direction at the front), j along x.
  t.grid = latlong_grid(around, rings);
  reverse_faces(t.grid.mesh);  // seen from +x, theta turns clockwise
  auto line_slit = [&](int i, int j0, int j1, int id) {
    std::vector<int> chain;
    for (int j = j0; j <= j1; ++j) chain.push_back(t.grid.vertex(i, j));
    const Polygons& faces = t.grid.mesh.faces;
    return cut_slit(t.grid, chain, id, [&](int f) {
      for (int k = faces.offsets[f]; k < faces.offsets[f + 1]; ++k) {
        const int v = faces.indices[k];
        if (t.grid.gi[v] >= 0 && t.grid.gi[v] < i) return true;
      }
      return false;
    });
  };
  const double eye_x = 6.0, eye_y = 3.6, eye_half = 1.45;
  const int eye_line = nearest_index(ys, eye_y);
  const int eye_in = nearest_index(xs, eye_x - eye_half), eye_out = nearest_index(xs, eye_x + eye_half);
  t.eye_slit[0] = line_slit(eye_line, eye_in, eye_out, 0);
  t.eye_slit[1] = line_slit(eye_line, rings - eye_out, rings - eye_in, 1);
  const int mouth_line = nearest_index(ys, -0.9), mouth_corner = nearest_index(xs, 7.0);
  t.mouth = line_slit(mouth_line, rings - mouth_corner, mouth_corner, 2);
  t.pocket_columns = 21;
  t.pocket_height = 0.9;
  t.pocket_depth = 2.0;
  finish_layout(
      t,
      [&](int v) {
        const int j = t.grid.gj[v];
        return t.grid.gi[v] < 0 ? Vector2d(xs[j], 0) : Vector2d(xs[j], ys[t.grid.gi[v]]);
      },
      7, 18);
  for (EyeLayout& e : t.eye) {
    e.upper_fall = 1.7;
    e.lower_fall = 1.2;
  }
  t.open = {0.9, 0.7};
  t.eye_centre[0] = {eye_x, t.eye[0].y};
  t.eye_centre[1] = {-eye_x, t.eye[1].y};
  t.ball_radius = 1.8;
  t.ball_recess = -0.6;
  t.liner = {0.6, -0.3};
  t.cornea = 0.12;
  t.lid = 0.28;
  t.mouth_layout.corner = xs[mouth_corner];
  t.mouth_layout.taper = 3.0;
  t.mouth_layout.rise = 0.2;
  t.mouth_layout.band = 1.0;
  t.mouth_layout.band_growth = 0.3;
  t.mouth_layout.reach = 9.5;
  t.mouth_layout.floor = -8.5;
  const double ym = t.mouth_layout.y;
  t.surface = [=](double x, double y) {
    const double u = std::clamp(x / A, -1.0, 1.0);
    const double r = std::pow(std::max(0.0, 1 - u * u), 0.35);
    const double th = y / B;
    return Vector3d(x, B * r * std::sin(th), C * r * std::cos(th));
  };
  // The grin: the mouth line rises towards the corners.
  t.warp = [=](double x, double y) {
    return Vector2d(x, y + 0.9 * (x / 7.0) * (x / 7.0) * bump((y - ym) / 4.5) * (1 - ramp(8, 11, std::abs(x))));
  };
  t.relief = [=](double x, double y) {
    const double ax = std::abs(x);
    return 0.3 * bump((y - ym) / 0.7) * (1 - ramp(5.5, 7.5, ax)) + 0.5 * bump2(x, y, 0, -3.6, 5.5, 1.8) -
           0.18 * bump2(ax, y, 0.9, 1.5, 0.35, 0.25) + 0.3 * bump2(ax, y, 6.0, 5.7, 1.8, 0.5) +
           0.35 * bump2(ax, y, 8.5, -0.5, 2.0, 2.0);
  };

  // Antennae: thin stalks with a bulb, bending about the base.
  const int stalk_rings = 10, stalk_segments = 8;
  const Mesh stalk = cone_part(stalk_rings, stalk_segments);
  const int stalk_first[2] = {append_part(t.mesh, stalk), append_part(t.mesh, stalk)};
  triangulate(t.mesh);
  auto place_antennae = [&](Positions& V, const double bend[2]) {
    for (int e = 0; e < 2; ++e) {
      const double s = e == 0 ? 1 : -1;
      const Vector2d c = warped(t, s * 2.4, 1.2 * B);
      const Vector3d n = base_normal(t, c.x(), c.y());
      const Vector3d base = skin_point(t, s * 2.4, 1.2 * B) - 0.2 * n;
      const Vector3d d = (n + Vector3d(s * 0.35, 0.5, 0)).normalized();
      const Vector3d l = (Vector3d(s, 0, 0) - d * d.x() * s).normalized();
      const Vector3d f = d.cross(l).normalized();
      // Bends outwards and forwards, more towards the tip (an arc).
      const Vector3d axis = (f - 0.5 * l).normalized();
      auto point = [&](double u, const Vector3d& local) {
        const Eigen::Matrix3d R = Eigen::AngleAxisd(-s * bend[e] * u, axis).toRotationMatrix();
        return Vector3d(base + R * local);
      };
      for (int r = 0; r < stalk_rings; ++r) {
        const double u = static_cast<double>(r) / stalk_rings;
        const double radius = 0.3 * (1 - 0.5 * u) + 0.5 * bump((u - 0.86) / 0.16);
        for (int k = 0; k < stalk_segments; ++k) {
          const double phi = 2 * M_PI * k / stalk_segments;
          V.row(stalk_first[e] + r * stalk_segments + k) =
              point(u, 5.5 * u * d + radius * (std::cos(phi) * l + std::sin(phi) * f)).transpose();
        }
      }
      V.row(stalk_first[e] + stalk_rings * stalk_segments) = point(1.0, 5.5 * d).transpose();
    }
  };

  ToonPose rest_pose;
  rest_pose.lids[0] = rest_pose.lids[1] = t.open;
  Positions rest = toon_positions(t, rest_pose);
  const double straight[2] = {0, 0};
  place_antennae(rest, straight);
  const FieldEvaluator F(t.lower, t.xc, t.yc, t.surface_count, t.mesh, rest);
  RigBuilder b;
  b.avatar.description = "wide flat ellipsoid (poles at its sides), wide grin, protruding far-apart eyes, antennae";
  CommonSizes c;
  c.blink = {-0.5, 0.5};
  c.with_squint = false;
  c.brow_up_centre = {6.0, 5.6, 0};
  c.brow_up_radii = {2.4, 1.5, 0};
  c.brow_up = 0.5;
  c.brow_down_centre = {5.8, 5.5, 0};
  c.brow_down_radii = {2.4, 1.2, 0};
  c.brow_down = 0.4;
  c.brows_down_together = true;
  c.smile_radii = {2.8, 2.8};
  c.smile = {0.4, 0.6, -0.1};
  c.frown_radii = {2.4, 2.0};
  c.frown = 0.55;
  add_common(b, t, rest, F, c);
  b.add("mouthOpen", jaw_open(t, F, {0, -1.0, -3.5}, 0.35, Vector3d::Zero()), {{"jawOpen", 1.0}});
  b.add("mouthWide", F([&](const Site& s) -> Vector3d {
          const double r = bump((s.y - ym) / 2.0) * (1 - ramp(7.5, 10.5, std::abs(s.x)));
          return Vector3d(0.12 * s.x * r, -0.1 * r * ramp(0, 7, std::abs(s.x)), 0);
        }),
        {{"mouthStretch_L", 1.0}, {"mouthStretch_R", 1.0}});
  b.add("pucker", F([&](const Site& s) -> Vector3d {
          const double r = bump2(s.x, s.y, 0, ym, 7.5, 1.6);
          return Vector3d(-0.25 * s.x * r, 0, 0.6 * bump2(s.x, s.y, 0, ym, 3.0, 1.4));
        }),
        {{"mouthPucker", 1.0}});
  const Field puff = [&](const Site& s) -> Vector3d { return 0.9 * bump2(s.x, s.y, 7.5, -2.2, 2.5, 2.2) * s.n; };
  b.add("cheekPuffLeft", F(puff), {{"cheekPuff_L", 1.0}});
  b.add("cheekPuffRight", F(puff, true), {{"cheekPuff_R", 1.0}});
  // Without human counterparts: the throat sac and the antennae.
  b.add("throatPuff", F([&](const Site& s) -> Vector3d { return 1.2 * bump2(s.x, s.y, 0, -3.8, 5.0, 2.0) * s.n; }), {});
  for (int e = 0; e < 2; ++e) {
    Positions moved = rest;
    const double bend[2] = {e == 0 ? 0.9 : 0.0, e == 1 ? 0.9 : 0.0};
    place_antennae(moved, bend);
    b.add(e == 0 ? "antennaBendLeft" : "antennaBendRight", Positions(moved - rest), {});
  }

  Rig& rig = b.avatar.rig;
  rig.name = "glorp";
  rig.units = "cm";
  rig.neutral = with_positions(t.mesh, rest);
  rig.landmarks = slit_landmarks(t);
  add_landmarks(t, rig.landmarks,
                {{"brow_inner_left", {4.6, 5.5}},
                 {"brow_middle_left", {6.0, 5.7}},
                 {"brow_outer_left", {7.4, 5.5}},
                 {"cheek_left", {8.5, -0.5}},
                 {"chin", {0, -3.6}},
                 {"forehead", {0, 5.0}},
                 {"jaw_left", {6.0, -3.5}}});
  rig.eyes = eye_sets(t);
  return b.avatar;
}

}  // namespace

std::vector<SyntheticAvatar> synthetic_avatars() { return {moppet(), fox(), glorp()}; }

}  // namespace retarget
