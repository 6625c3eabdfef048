// build_avatar(): an AvatarSpec (avatar_spec.h) made into a "toon": a parameter grid of the
// spec's kind laid out in canonical (x, y) cm, a base surface, relief along the base normal,
// eyelids cut and open over eyeball caps, a mouth cut along a grid line with a pocket behind it,
// and the spec's parts (ears, antennae). Controllers are displacement fields over the canonical
// layout, lid states evaluated through the shape itself, or motions of the parts.
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <set>

#include "core/error.h"
#include "synthetic/avatar_spec.h"

namespace retarget::synth {

namespace {

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

// Landmarks at canonical positions; "_left" names are mirrored to "_right".
void add_landmarks(const Toon& t, std::map<std::string, int>& m, const std::vector<LandmarkSpec>& points) {
  for (const LandmarkSpec& p : points) {
    const size_t cut = p.name.rfind("_left");
    m[p.name] = nearest_vertex(t, p.x, p.y);
    if (cut != std::string::npos && cut + 5 == p.name.size())
      m[p.name.substr(0, cut) + "_right"] = nearest_vertex(t, -p.x, p.y);
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

// The offsets of a pose of the lids and eyeballs; the parts (not in toon_positions) stay.
Positions pose_offset(const Toon& t, const Positions& rest, const ToonPose& pose) {
  Positions V = toon_positions(t, pose);
  const Eigen::Index parts = V.rows() - t.ball_first[1] - t.cap.rows();
  V.bottomRows(parts) = rest.bottomRows(parts);
  return V - rest;
}

// The jaw: rotation by `angle` (radians, opening) about the x axis through `pivot`.
Vector3d jaw_motion(const Vector3d& P, const Vector3d& pivot, double angle, const Vector3d& shift = Vector3d::Zero()) {
  const Eigen::Matrix3d R = Eigen::AngleAxisd(angle, Vector3d::UnitX()).toRotationMatrix();
  return (R - Eigen::Matrix3d::Identity()) * (P - pivot) + shift;
}

Vector3d vec(const Vec3& v) { return Vector3d(v.x, v.y, v.z); }

// ---- the grid ---------------------------------------------------------------------------------

// The canonical coordinates (cm) of one family of grid lines.
std::vector<double> sample_lines(const Samples& s) {
  std::vector<double> t(s.count);
  if (s.density.peak == 0) {
    for (int k = 0; k < s.count; ++k) t[k] = s.lo + (s.hi - s.lo) * k / (s.count - 1);
  } else {
    const Density d = s.density;
    t = graded_samples(s.lo, s.hi, s.count, [d](double v) {
      if (d.squared) {
        const double w = v - d.centre;
        return 1 + d.peak * std::exp(-w * w / d.width);
      }
      const double u = (v - d.centre) / d.width;
      return 1 + d.peak * std::exp(-u * u);
    });
  }
  if (s.symmetric) symmetrize(t, s.centre);
  if (s.periodic) t.pop_back();
  for (double& v : t) v = s.mapping == Mapping::kCosine ? -s.scale * std::cos(v) : s.scale * v;
  return t;
}

// The slit along grid line `line` (canonical y) from x line `from` to `to` (from < to).
Slit cut_line(Toon& t, GridKind kind, int line, int from, int to, int id) {
  if (kind != GridKind::kSideways) return cut_row_slit(t.grid, line, from, to, id);
  // i runs around the x axis, j along x: the line is i = line, the lower side i < line.
  std::vector<int> chain;
  for (int j = from; j <= to; ++j) chain.push_back(t.grid.vertex(line, j));
  const Polygons& faces = t.grid.mesh.faces;
  return cut_slit(t.grid, chain, id, [&](int f) {
    for (int k = faces.offsets[f]; k < faces.offsets[f + 1]; ++k) {
      const int v = faces.indices[k];
      if (t.grid.gi[v] >= 0 && t.grid.gi[v] < line) return true;
    }
    return false;
  });
}

// Grid, cuts, pocket and eyeball caps, and the eye and mouth layouts.
void lay_out(Toon& t, const AvatarSpec& spec) {
  const GridKind kind = spec.grid.kind;
  const std::vector<double> xs = sample_lines(spec.grid.x), ys = sample_lines(spec.grid.y);
  const int nx = static_cast<int>(xs.size()), ny = static_cast<int>(ys.size());
  if (kind == GridKind::kSphere) t.grid = latlong_grid(nx, ny - 1);
  if (kind == GridKind::kOpen) t.grid = open_grid(nx, ny);
  if (kind == GridKind::kSideways) {
    t.grid = latlong_grid(ny, nx - 1);
    reverse_faces(t.grid.mesh);  // seen from +x, the angle about the x axis turns clockwise
  }
  const int mirror = 2 * (nx / 2);  // x line k and mirror - k are mirror images
  const EyeSpec& eyes = spec.eyes;
  const int eye_line = nearest_index(ys, eyes.y);
  const int eye_in = nearest_index(xs, eyes.x - eyes.half_width), eye_out = nearest_index(xs, eyes.x + eyes.half_width);
  t.eye_slit[0] = cut_line(t, kind, eye_line, eye_in, eye_out, 0);
  t.eye_slit[1] = cut_line(t, kind, eye_line, mirror - eye_out, mirror - eye_in, 1);
  const MouthSpec& mouth = spec.mouth;
  const int mouth_line = nearest_index(ys, mouth.y), mouth_corner = nearest_index(xs, mouth.corner);
  t.mouth = cut_line(t, kind, mouth_line, mirror - mouth_corner, mouth_corner, 2);
  t.pocket_columns = mouth.pocket_columns;
  t.pocket_rows = mouth.pocket_rows;
  t.pocket_width = mouth.pocket_width;
  t.pocket_height = mouth.pocket_height;
  t.pocket_depth = mouth.pocket_depth;
  t.pocket_inset = mouth.pocket_inset;
  finish_layout(
      t,
      [&](int v) -> Vector2d {
        const int i = t.grid.gi[v], j = t.grid.gj[v];
        switch (kind) {
          case GridKind::kSphere:
            return i < 0 ? Vector2d(0, ys[j]) : Vector2d(xs[i], ys[j]);
          case GridKind::kOpen:
            return Vector2d(xs[i], ys[j]);
          case GridKind::kSideways:
            break;
        }
        return i < 0 ? Vector2d(xs[j], 0) : Vector2d(xs[j], ys[i]);
      },
      eyes.cap_rings, eyes.cap_segments);
  for (EyeLayout& e : t.eye) {
    e.upper_fall = eyes.upper_fall;
    e.lower_fall = eyes.lower_fall;
  }
  t.open = eyes.open;
  t.eye_centre[0] = {eyes.x, t.eye[0].y};
  t.eye_centre[1] = {-eyes.x, t.eye[1].y};
  t.ball_radius = eyes.ball_radius;
  t.ball_recess = eyes.ball_recess;
  t.liner = eyes.liner;
  t.cornea = eyes.cornea;
  t.lid = eyes.lid;
  MouthLayout& m = t.mouth_layout;
  m.corner = xs[mouth_corner];
  m.taper = mouth.taper;
  m.rise = mouth.rise;
  m.band = mouth.band;
  m.band_growth = mouth.band_growth;
  m.reach = mouth.reach;
  m.floor = mouth.floor;
  m.floor_fade = mouth.floor_fade;
}

// ---- surface and relief -----------------------------------------------------------------------

std::function<Vector3d(double, double)> base_surface(const SurfaceSpec& sf) {
  switch (sf.kind) {
    case SurfaceKind::kEllipsoid:
      return [sf](double x, double y) {
        const double l = x / sf.a, b = std::clamp(y / sf.b, -M_PI / 2, M_PI / 2);
        return Vector3d(sf.a * std::cos(b) * std::sin(l), sf.b * std::sin(b), sf.c * std::cos(b) * std::cos(l));
      };
    case SurfaceKind::kDomedDisc:
      return [sf](double x, double y) {
        const double u = std::clamp(x / sf.extent_x, -1.0, 1.0), v = std::clamp(y / sf.extent_y, -1.0, 1.0);
        const double px = sf.a * u * std::sqrt(1 - 0.5 * v * v), py = sf.b * v * std::sqrt(1 - 0.5 * u * u);
        const double q = (px / sf.a) * (px / sf.a) + (py / sf.b) * (py / sf.b);
        return Vector3d(px, py, sf.c * (std::sqrt(std::max(0.0, sf.crown - q)) - sf.drop));
      };
    case SurfaceKind::kSidewaysEllipsoid:
      break;
  }
  return [sf](double x, double y) {
    const double u = std::clamp(x / sf.a, -1.0, 1.0);
    const double r = std::pow(std::max(0.0, 1 - u * u), sf.exponent);
    const double th = y / sf.b;
    return Vector3d(x, sf.b * r * std::sin(th), sf.c * r * std::cos(th));
  };
}

double bump_at(const Bump& b, double x, double y, const MouthLayout& m) {
  double cx = b.cx, cy = b.cy;
  if (b.anchor == Anchor::kMouthLine) cy = m.y + b.cy;
  if (b.anchor == Anchor::kMouthCorner) {
    cx = m.corner + b.cx;
    cy = m.y + b.cy;
  }
  return bump2(b.symmetric ? std::abs(x) : x, y, cx, cy, b.rx, b.ry);
}

double band_at(double weight, const Band& b, double x, double y, const MouthLayout& m) {
  return weight * bump((y - m.y) / b.half_height) * (1 - ramp(b.fade_from, b.fade_to, std::abs(x)));
}

// The relief's terms summed in order (cm).
struct Relief {
  std::vector<ReliefTerm> terms;
  std::vector<Profile> profiles;  // height and width of each RidgeRelief, in order
  MouthLayout mouth;

  Relief(const std::vector<ReliefTerm>& spec, const MouthLayout& m) : terms(spec), mouth(m) {
    for (const ReliefTerm& term : terms)
      if (const auto* r = std::get_if<RidgeRelief>(&term)) {
        profiles.emplace_back(r->height_at, r->height);
        profiles.emplace_back(r->width_at, r->width);
      }
  }
  double operator()(double x, double y) const {
    double sum = 0;
    size_t ridge = 0;
    for (size_t k = 0; k < terms.size(); ++k) {
      double value = 0;
      if (const auto* b = std::get_if<BumpRelief>(&terms[k])) value = b->weight * bump_at(b->bump, x, y, mouth);
      if (const auto* b = std::get_if<BandRelief>(&terms[k])) value = band_at(b->weight, b->band, x, y, mouth);
      if (const auto* r = std::get_if<RidgeRelief>(&terms[k])) {
        value = profiles[ridge](y) * bump(x / (r->width_scale * profiles[ridge + 1](y)));
        ridge += 2;
      }
      sum = k == 0 ? value : sum + value;
    }
    return sum;
  }
};

// ---- parts ------------------------------------------------------------------------------------

struct PartPose {
  double swing[2] = {0, 0};  // ears: sideways tilt; antennae: bend (radians)
  double back = 0;           // ears: tilt backwards (radians)
};

// Ear e about its front axis (swing) and its lateral axis (back, tips backwards), into V.
void place_ears(const Toon& t, const EarsSpec& ears, const int first[2], const PartPose& pose, Positions& V) {
  for (int e = 0; e < 2; ++e) {
    const double s = e == 0 ? 1 : -1;
    const Vector3d base = skin_point(t, s * ears.anchor.x, ears.anchor.y) - Vector3d(0, 0, ears.sink);
    Vector3d d = Vector3d(s * ears.axis.x, ears.axis.y, ears.axis.z).normalized();
    Vector3d l = (Vector3d(s, 0, 0) - d * d.x() * s).normalized();
    Vector3d f = d.cross(l).normalized();
    const Eigen::Matrix3d R =
        (Eigen::AngleAxisd(-pose.back * s, l) * Eigen::AngleAxisd(-s * pose.swing[e], f)).toRotationMatrix();
    d = R * d;
    l = R * l;
    f = R * f;
    for (int r = 0; r < ears.rings; ++r) {
      const double u = static_cast<double>(r) / ears.rings;
      const double width = ears.width * std::pow(1 - u, ears.taper), depth = ears.depth * std::pow(1 - u, ears.taper);
      for (int k = 0; k < ears.segments; ++k) {
        const double phi = 2 * M_PI * k / ears.segments;
        V.row(first[e] + r * ears.segments + k) =
            (base + ears.length * u * d + width * std::cos(phi) * l + depth * std::sin(phi) * f).transpose();
      }
    }
    V.row(first[e] + ears.rings * ears.segments) = (base + ears.length * d).transpose();
  }
}

// Antenna e bent by its swing (an arc: more towards the tip), into V.
void place_antennae(const Toon& t, const AntennaeSpec& a, const int first[2], const PartPose& pose, Positions& V) {
  for (int e = 0; e < 2; ++e) {
    const double s = e == 0 ? 1 : -1;
    const Vector2d c = warped(t, s * a.anchor.x, a.anchor.y);
    const Vector3d n = base_normal(t, c.x(), c.y());
    const Vector3d base = skin_point(t, s * a.anchor.x, a.anchor.y) - a.sink * n;
    const Vector3d d = (n + Vector3d(s * a.lean.x, a.lean.y, a.lean.z)).normalized();
    const Vector3d l = (Vector3d(s, 0, 0) - d * d.x() * s).normalized();
    const Vector3d f = d.cross(l).normalized();
    const Vector3d axis = (f - a.bend_inwards * l).normalized();
    auto point = [&](double u, const Vector3d& local) {
      const Eigen::Matrix3d R = Eigen::AngleAxisd(-s * pose.swing[e] * u, axis).toRotationMatrix();
      return Vector3d(base + R * local);
    };
    for (int r = 0; r < a.rings; ++r) {
      const double u = static_cast<double>(r) / a.rings;
      const double radius = a.radius * (1 - a.taper * u) + a.bulb * bump((u - a.bulb_at) / a.bulb_width);
      for (int k = 0; k < a.segments; ++k) {
        const double phi = 2 * M_PI * k / a.segments;
        V.row(first[e] + r * a.segments + k) =
            point(u, a.length * u * d + radius * (std::cos(phi) * l + std::sin(phi) * f)).transpose();
      }
    }
    V.row(first[e] + a.rings * a.segments) = point(1.0, a.length * d).transpose();
  }
}

void place_parts(const Toon& t, const PartsSpec& parts, const int first[2], const PartPose& pose, Positions& V) {
  if (const auto* ears = std::get_if<EarsSpec>(&parts)) place_ears(t, *ears, first, pose, V);
  if (const auto* antennae = std::get_if<AntennaeSpec>(&parts)) place_antennae(t, *antennae, first, pose, V);
}

// ---- controllers ------------------------------------------------------------------------------

Vector3d term_value(const FieldTerm& term, const Site& s, const MouthLayout& m) {
  double w = term.weight * bump_at(term.bump, s.x, s.y, m);
  switch (term.motion) {
    case Motion::kAlong:
      break;
    case Motion::kNormal:
      return w * s.n;
    case Motion::kUpperLip:
      w = (1 - s.lower) * m.parting(s.x) * w;
      break;
  }
  return w * vec(term.direction);
}

// The field of a Displacement, Pucker, Stretch or Jaw (empty for the others).
Field field_of(const Deformation& deformation, const Toon& t) {
  const MouthLayout& m = t.mouth_layout;
  if (const auto* d = std::get_if<Displacement>(&deformation))
    return [d, &m](const Site& s) -> Vector3d {
      Vector3d sum = Vector3d::Zero();
      for (size_t k = 0; k < d->terms.size(); ++k) {
        const Vector3d v = term_value(d->terms[k], s, m);
        if (k == 0)
          sum = v;
        else
          sum += v;
      }
      return sum;
    };
  if (const auto* p = std::get_if<Pucker>(&deformation))
    return [p, &m](const Site& s) -> Vector3d {
      const double r = bump_at(p->in, s.x, s.y, m);
      return Vector3d(-p->pinch * s.x * r, 0, p->forward * bump_at(p->out, s.x, s.y, m));
    };
  if (const auto* st = std::get_if<Stretch>(&deformation))
    return [st, &m](const Site& s) -> Vector3d {
      const double r = band_at(1, st->band, s.x, s.y, m);
      return Vector3d(st->out * s.x * r, -st->down * r * ramp(st->down_from, st->down_to, std::abs(s.x)), 0);
    };
  if (const auto* j = std::get_if<Jaw>(&deformation))
    return [j, &m](const Site& s) -> Vector3d {
      return m.jaw_weight(s) * jaw_motion(s.P, vec(j->pivot), j->angle, Vector3d::Zero());
    };
  return {};
}

// Everything one avatar's controllers need.
struct Stage {
  const Toon& t;
  const PartsSpec& parts;
  const int* part_first;
  const Positions& rest;
  const FieldEvaluator& F;
};

// The offsets (#V x 3) of `deformation` on side e (0: as given, 1: the mirror image; the
// right eye or part).
Positions offset_of(const Stage& st, const Deformation& deformation, int e) {
  if (const Field f = field_of(deformation, st.t)) return st.F(f, e == 1);
  if (const auto* lids = std::get_if<Lids>(&deformation)) {
    ToonPose pose;
    pose.lids[0] = pose.lids[1] = st.t.open;
    pose.lids[e] = lids->state;
    return pose_offset(st.t, st.rest, pose);
  }
  if (const auto* pop = std::get_if<EyePop>(&deformation)) {
    ToonPose pose;
    pose.lids[0] = pose.lids[1] = st.t.open;
    pose.ball_scale = pop->ball_scale;
    return pose_offset(st.t, st.rest, pose);
  }
  if (const auto* squash = std::get_if<Squash>(&deformation)) {
    Positions offset(st.rest.rows(), 3);
    const Eigen::RowVector3d base = vec(squash->base).transpose(), scale = vec(squash->scale).transpose();
    for (int v = 0; v < st.rest.rows(); ++v) offset.row(v) = (st.rest.row(v) - base).cwiseProduct(scale);
    return offset;
  }
  PartPose pose;
  if (const auto* swing = std::get_if<PartSwing>(&deformation)) pose.swing[e] = swing->amount;
  if (const auto* back = std::get_if<PartsBack>(&deformation)) pose.back = back->amount;
  Positions moved = st.rest;
  place_parts(st.t, st.parts, st.part_first, pose, moved);
  return Positions(moved - st.rest);
}

// The right twin of a left name: a trailing "_L" or "Left" becomes "_R" or "Right".
std::string right_name(const std::string& left) {
  const auto ends = [&](const std::string& tail) {
    return left.size() >= tail.size() && left.compare(left.size() - tail.size(), tail.size(), tail) == 0;
  };
  if (ends("_L")) return left.substr(0, left.size() - 2) + "_R";
  if (ends("Left")) return left.substr(0, left.size() - 4) + "Right";
  return left;
}

void add_controllers(const Stage& st, const std::vector<ControllerSpec>& controllers, SyntheticAvatar& avatar) {
  auto add = [&](const std::string& name, Positions offset, const std::vector<std::string>& human, bool right) {
    avatar.rig.controllers.push_back({name, std::move(offset), 0.0, 1.0});
    std::map<std::string, double>& row = avatar.correspondence[name];
    for (const std::string& h : human) row[right ? right_name(h) : h] = 1.0;
  };
  for (const ControllerSpec& c : controllers) {
    switch (c.sides) {
      case Sides::kOne:
        add(c.name, offset_of(st, c.deformation, 0), c.human, false);
        break;
      case Sides::kPair:
        add(c.name + "Left", offset_of(st, c.deformation, 0), c.human, false);
        add(c.name + "Right", offset_of(st, c.deformation, 1), c.human, true);
        break;
      case Sides::kSummed:
        add(c.name, Positions(offset_of(st, c.deformation, 0) + offset_of(st, c.deformation, 1)), c.human, false);
        break;
    }
  }
}

}  // namespace

SyntheticAvatar build_avatar(const AvatarSpec& spec) {
  spec.validate();
  Toon t;
  lay_out(t, spec);
  t.surface = base_surface(spec.surface);
  if (spec.grin.lift != 0) {
    const GrinSpec g = spec.grin;
    const double ym = t.mouth_layout.y;
    t.warp = [g, ym](double x, double y) {
      return Vector2d(x, y + g.lift * (x / g.corner_x) * (x / g.corner_x) * bump((y - ym) / g.half_height) *
                                 (1 - ramp(g.fade_from, g.fade_to, std::abs(x))));
    };
  }
  t.relief = Relief(spec.relief, t.mouth_layout);

  int part_first[2] = {0, 0};
  auto append_pair = [&](int rings, int segments) {
    const Mesh part = cone_part(rings, segments);
    part_first[0] = append_part(t.mesh, part);
    part_first[1] = append_part(t.mesh, part);
  };
  if (const auto* ears = std::get_if<EarsSpec>(&spec.parts)) append_pair(ears->rings, ears->segments);
  if (const auto* antennae = std::get_if<AntennaeSpec>(&spec.parts)) append_pair(antennae->rings, antennae->segments);
  triangulate(t.mesh);

  ToonPose rest_pose;
  rest_pose.lids[0] = rest_pose.lids[1] = t.open;
  Positions rest = toon_positions(t, rest_pose);
  place_parts(t, spec.parts, part_first, PartPose{}, rest);
  const FieldEvaluator F(t.lower, t.xc, t.yc, t.surface_count, t.mesh, rest);

  SyntheticAvatar avatar;
  avatar.description = spec.description;
  add_controllers({t, spec.parts, part_first, rest, F}, spec.controllers, avatar);
  Rig& rig = avatar.rig;
  rig.name = spec.name;
  rig.units = "cm";
  rig.neutral = with_positions(t.mesh, rest);
  rig.landmarks = slit_landmarks(t);
  add_landmarks(t, rig.landmarks, spec.landmarks);
  rig.eyes = eye_sets(t);
  return avatar;
}

// ---- validation -------------------------------------------------------------------------------

namespace {

std::string at(const std::string& base, const char* field, size_t index) {
  return base + "." + field + "[" + std::to_string(index) + "]";
}

void check(bool ok, const std::string& where, const std::string& what) {
  if (!ok) throw Error(where, what);
}

void check_samples(const Samples& s, const std::string& where) {
  check(s.count >= (s.periodic ? 4 : 3), where + ".count", "expected at least 3 grid lines (4 when periodic)");
  check(s.lo < s.hi, where + ".lo", "expected lo < hi");
  check(s.density.peak == 0 || s.density.width > 0, where + ".density.width", "expected a positive width");
  check(s.scale > 0, where + ".scale", "expected a positive scale");
}

void check_bump(const Bump& b, const std::string& where) {
  check(b.rx > 0 && b.ry > 0, where, "expected positive radii (rx, ry)");
}

void check_band(const Band& b, const std::string& where) {
  check(b.half_height > 0, where + ".half_height", "expected a positive half height");
  check(b.fade_from != b.fade_to, where + ".fade_to", "expected fade_from != fade_to");
}

void check_profile(const std::vector<double>& at, const std::vector<double>& value, const std::string& where) {
  check(at.size() >= 2 && at.size() == value.size(), where, "expected as many values as knots, at least 2");
  for (size_t k = 1; k < at.size(); ++k) check(at[k - 1] < at[k], where, "expected increasing knots");
}

}  // namespace

void AvatarSpec::validate() const {
  check(!name.empty(), "avatar.name", "expected a name");
  const std::string& w = name;
  check_samples(grid.x, w + ".grid.x");
  check_samples(grid.y, w + ".grid.y");
  check(eyes.half_width > 0, w + ".eyes.half_width", "expected a positive half width");
  check(eyes.ball_radius > 0, w + ".eyes.ball_radius", "expected a positive radius");
  check(eyes.cap_rings >= 1 && eyes.cap_segments >= 3, w + ".eyes.cap_rings", "expected at least 1 ring of 3 segments");
  check(mouth.corner > 0, w + ".mouth.corner", "expected a positive corner x");
  check(mouth.pocket_columns >= 2 && mouth.pocket_rows >= 2, w + ".mouth.pocket_columns",
        "expected at least 2 pocket columns and rows");
  check(surface.a > 0 && surface.b > 0 && surface.c > 0, w + ".surface", "expected positive semi-axes a, b, c");
  check(surface.extent_x > 0 && surface.extent_y > 0, w + ".surface.extent_x", "expected positive extents");
  check(grin.lift == 0 || (grin.corner_x > 0 && grin.half_height > 0), w + ".grin",
        "expected a positive corner_x and half_height");
  for (size_t k = 0; k < relief.size(); ++k) {
    const std::string where = at(w, "relief", k);
    if (const auto* b = std::get_if<BumpRelief>(&relief[k])) check_bump(b->bump, where + ".bump");
    if (const auto* b = std::get_if<BandRelief>(&relief[k])) check_band(b->band, where + ".band");
    if (const auto* r = std::get_if<RidgeRelief>(&relief[k])) {
      check_profile(r->height_at, r->height, where + ".height");
      check_profile(r->width_at, r->width, where + ".width");
    }
  }
  if (const auto* ears = std::get_if<EarsSpec>(&parts))
    check(ears->rings >= 1 && ears->segments >= 3, w + ".parts.rings", "expected at least 1 ring of 3 segments");
  if (const auto* a = std::get_if<AntennaeSpec>(&parts)) {
    check(a->rings >= 1 && a->segments >= 3, w + ".parts.rings", "expected at least 1 ring of 3 segments");
    check(a->bulb_width > 0, w + ".parts.bulb_width", "expected a positive bulb width");
  }
  std::set<std::string> names;
  for (size_t k = 0; k < controllers.size(); ++k) {
    const ControllerSpec& c = controllers[k];
    const std::string where = at(w, "controllers", k);
    check(!c.name.empty(), where + ".name", "expected a name");
    const std::vector<std::string> expanded = c.sides == Sides::kPair
                                                  ? std::vector<std::string>{c.name + "Left", c.name + "Right"}
                                                  : std::vector<std::string>{c.name};
    for (const std::string& n : expanded)
      check(names.insert(n).second, where + ".name", "controller \"" + n + "\" appears twice");
    const Deformation& d = c.deformation;
    if (std::holds_alternative<PartSwing>(d) || std::holds_alternative<PartsBack>(d))
      check(!std::holds_alternative<std::monostate>(parts), where + ".deformation",
            "a part motion needs parts (ears or antennae)");
    if (std::holds_alternative<PartsBack>(d))
      check(std::holds_alternative<EarsSpec>(parts), where + ".deformation", "only ears tilt back");
    if (const auto* disp = std::get_if<Displacement>(&d)) {
      check(!disp->terms.empty(), where + ".deformation", "expected at least one term");
      for (size_t j = 0; j < disp->terms.size(); ++j)
        check_bump(disp->terms[j].bump, at(where + ".deformation", "terms", j) + ".bump");
    }
    if (const auto* p = std::get_if<Pucker>(&d)) {
      check_bump(p->in, where + ".deformation.in");
      check_bump(p->out, where + ".deformation.out");
    }
    if (const auto* s = std::get_if<Stretch>(&d)) check_band(s->band, where + ".deformation.band");
    if (c.sides == Sides::kPair)
      for (const std::string& h : c.human)
        check(right_name(h) != h, where + ".human", "\"" + h + "\": a pair's names end in _L or Left");
    if (c.sides == Sides::kSummed)
      check(std::holds_alternative<Displacement>(d), where + ".sides", "kSummed is for a Displacement only");
  }
  for (size_t k = 0; k < landmarks.size(); ++k)
    check(!landmarks[k].name.empty(), at(w, "landmarks", k) + ".name", "expected a name");
}

}  // namespace retarget::synth
