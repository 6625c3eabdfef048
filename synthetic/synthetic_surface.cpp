#include "synthetic/synthetic_surface.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cassert>
#include <cmath>
#include <unordered_map>

namespace retarget::synth {

double bump(double r) {
  const double s = 1 - r * r;
  return s > 0 ? s * s * s : 0.0;
}

double bump2(double x, double y, double cx, double cy, double rx, double ry) {
  const double dx = (x - cx) / rx, dy = (y - cy) / ry;
  return bump(std::sqrt(dx * dx + dy * dy));
}

double plateau(double x, double y, double cx, double cy, double rx, double ry, double inner) {
  const double dx = (x - cx) / rx, dy = (y - cy) / ry;
  return 1 - ramp(inner, 1.0, std::sqrt(dx * dx + dy * dy));
}

double ramp(double a, double b, double x) {
  double t = (x - a) / (b - a);
  t = std::clamp(t, 0.0, 1.0);
  return t * t * (3 - 2 * t);
}

double smooth_max(double a, double b, double k) {
  const double d = a - b;
  return 0.5 * (a + b + std::sqrt(d * d + k * k));
}

Profile::Profile(std::vector<double> x, std::vector<double> y) : x_(std::move(x)), y_(std::move(y)) {
  assert(x_.size() == y_.size() && x_.size() >= 2);
}

double Profile::operator()(double x) const {
  const size_t n = x_.size();
  if (x <= x_.front()) return y_.front();
  if (x >= x_.back()) return y_.back();
  const size_t k = static_cast<size_t>(std::upper_bound(x_.begin(), x_.end(), x) - x_.begin()) - 1;
  const double h = x_[k + 1] - x_[k], t = (x - x_[k]) / h;
  // Tangents from the neighbours (finite differences scaled to this interval).
  auto slope = [&](size_t i) {
    const size_t a = i == 0 ? 0 : i - 1, b = std::min(i + 1, n - 1);
    return (y_[b] - y_[a]) / (x_[b] - x_[a]);
  };
  const double m0 = slope(k) * h, m1 = slope(k + 1) * h;
  const double t2 = t * t, t3 = t2 * t;
  return (2 * t3 - 3 * t2 + 1) * y_[k] + (t3 - 2 * t2 + t) * m0 + (-2 * t3 + 3 * t2) * y_[k + 1] + (t3 - t2) * m1;
}

std::vector<double> graded_samples(double lo, double hi, int n, const std::function<double(double)>& density) {
  const int fine = 4096;
  std::vector<double> cdf(fine + 1, 0.0);
  for (int k = 0; k < fine; ++k) {
    const double t = lo + (hi - lo) * (k + 0.5) / fine;
    cdf[k + 1] = cdf[k] + density(t);
  }
  std::vector<double> out(n);
  for (int s = 0; s < n; ++s) {
    const double target = cdf[fine] * s / (n - 1);
    const size_t k =
        std::min<size_t>(static_cast<size_t>(std::lower_bound(cdf.begin(), cdf.end(), target) - cdf.begin()), fine);
    const size_t k0 = k == 0 ? 0 : k - 1;
    const double span = cdf[k] - cdf[k0];
    const double f = span > 0 ? (target - cdf[k0]) / span : 0.0;
    out[s] = lo + (hi - lo) * (k0 + f) / fine;
  }
  out.front() = lo;
  out.back() = hi;
  return out;
}

namespace {

void init_vertex_arrays(GridMesh& g, int count) {
  g.mesh.vertices = Positions::Zero(count, 3);
  g.gi.assign(count, 0);
  g.gj.assign(count, 0);
  g.slit.assign(count, -1);
  g.side.assign(count, 0);
  g.twin.assign(count, -1);
}

}  // namespace

GridMesh open_grid(int ni, int nj) {
  GridMesh g;
  g.ni = ni;
  g.nj = nj;
  init_vertex_arrays(g, ni * nj);
  g.index.resize(static_cast<size_t>(ni) * nj);
  for (int j = 0; j < nj; ++j)
    for (int i = 0; i < ni; ++i) {
      const int v = j * ni + i;
      g.gi[v] = i;
      g.gj[v] = j;
      g.index[v] = v;
    }
  for (int j = 0; j + 1 < nj; ++j)
    for (int i = 0; i + 1 < ni; ++i) {
      const int a = j * ni + i;
      const int quad[4] = {a, a + 1, a + ni + 1, a + ni};
      g.mesh.faces.add(quad, 4);
    }
  return g;
}

GridMesh latlong_grid(int around, int rings) {
  GridMesh g;
  g.ni = around;
  g.nj = rings + 1;
  const int count = 2 + (rings - 1) * around;
  init_vertex_arrays(g, count);
  g.index.assign(static_cast<size_t>(around) * (rings + 1), -1);
  const int south = 0, north = count - 1;
  g.gi[south] = g.gi[north] = -1;
  g.gj[south] = 0;
  g.gj[north] = rings;
  for (int i = 0; i < around; ++i) {
    g.index[i] = south;
    g.index[static_cast<size_t>(rings) * around + i] = north;
  }
  for (int j = 1; j < rings; ++j)
    for (int i = 0; i < around; ++i) {
      const int v = 1 + (j - 1) * around + i;
      g.gi[v] = i;
      g.gj[v] = j;
      g.index[static_cast<size_t>(j) * around + i] = v;
    }
  auto at = [&](int i, int j) { return g.vertex(i % around, j); };
  for (int i = 0; i < around; ++i) {
    const int tri[3] = {south, at(i + 1, 1), at(i, 1)};
    g.mesh.faces.add(tri, 3);
  }
  for (int j = 1; j + 1 < rings; ++j)
    for (int i = 0; i < around; ++i) {
      const int quad[4] = {at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)};
      g.mesh.faces.add(quad, 4);
    }
  for (int i = 0; i < around; ++i) {
    const int tri[3] = {at(i, rings - 1), at(i + 1, rings - 1), north};
    g.mesh.faces.add(tri, 3);
  }
  return g;
}

Slit cut_slit(GridMesh& grid, const std::vector<int>& chain, int id, const std::function<bool(int face)>& is_lower) {
  assert(chain.size() >= 3);
  Slit slit;
  slit.chain = chain;
  std::unordered_map<int, int> copy;
  int next = grid.vertex_count();
  for (size_t k = 1; k + 1 < chain.size(); ++k) {
    slit.upper.push_back(chain[k]);
    slit.lower.push_back(next);
    copy[chain[k]] = next++;
  }
  Polygons& faces = grid.mesh.faces;
  for (int f = 0; f < faces.size(); ++f) {
    bool touches = false;
    for (int k = faces.offsets[f]; k < faces.offsets[f + 1]; ++k) touches |= copy.count(faces.indices[k]) > 0;
    if (!touches || !is_lower(f)) continue;
    for (int k = faces.offsets[f]; k < faces.offsets[f + 1]; ++k) {
      const auto it = copy.find(faces.indices[k]);
      if (it != copy.end()) faces.indices[k] = it->second;
    }
  }
  const int old_count = grid.vertex_count();
  Positions grown = Positions::Zero(next, 3);
  grown.topRows(old_count) = grid.mesh.vertices;
  grid.mesh.vertices = grown;
  grid.gi.resize(next);
  grid.gj.resize(next);
  grid.slit.resize(next, -1);
  grid.side.resize(next, 0);
  grid.twin.resize(next, -1);
  for (size_t k = 0; k < slit.upper.size(); ++k) {
    const int u = slit.upper[k], l = slit.lower[k];
    grid.gi[l] = grid.gi[u];
    grid.gj[l] = grid.gj[u];
    grid.slit[u] = grid.slit[l] = id;
    grid.side[u] = 1;
    grid.side[l] = -1;
    grid.twin[u] = l;
    grid.twin[l] = u;
  }
  return slit;
}

Slit cut_row_slit(GridMesh& grid, int j, int i0, int i1, int id) {
  std::vector<int> chain;
  for (int i = i0; i <= i1; ++i) chain.push_back(grid.vertex(i, j));
  const Polygons& faces = grid.mesh.faces;
  return cut_slit(grid, chain, id, [&](int f) {
    for (int k = faces.offsets[f]; k < faces.offsets[f + 1]; ++k)
      if (grid.gj[faces.indices[k]] < j) return true;
    return false;
  });
}

void reverse_faces(Mesh& mesh) {
  Polygons& faces = mesh.faces;
  for (int f = 0; f < faces.size(); ++f)
    std::reverse(faces.indices.begin() + faces.offsets[f], faces.indices.begin() + faces.offsets[f + 1]);
}

int append_part(Mesh& mesh, const Mesh& part) {
  const int first = mesh.vertex_count();
  Positions grown(first + part.vertex_count(), 3);
  grown.topRows(first) = mesh.vertices;
  grown.bottomRows(part.vertex_count()) = part.vertices;
  mesh.vertices = grown;
  std::vector<int> face;
  for (int f = 0; f < part.faces.size(); ++f) {
    face.assign(part.faces.begin(f), part.faces.begin(f) + part.faces.degree(f));
    for (int& v : face) v += first;
    mesh.faces.add(face.data(), static_cast<int>(face.size()));
  }
  return first;
}

Mesh unit_cap(int rings, int segments, double max_angle) {
  Mesh cap;
  cap.vertices.resize(1 + rings * segments, 3);
  cap.vertices.row(0) << 0, 0, 1;
  for (int r = 1; r <= rings; ++r) {
    const double theta = max_angle * r / rings;
    for (int s = 0; s < segments; ++s) {
      const double phi = 2 * M_PI * s / segments;
      cap.vertices.row(1 + (r - 1) * segments + s) << std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi),
          std::cos(theta);
    }
  }
  auto at = [&](int r, int s) { return 1 + (r - 1) * segments + (s % segments); };
  for (int s = 0; s < segments; ++s) {
    const int tri[3] = {0, at(1, s), at(1, s + 1)};
    cap.faces.add(tri, 3);
  }
  for (int r = 1; r < rings; ++r)
    for (int s = 0; s < segments; ++s) {
      const int quad[4] = {at(r, s), at(r + 1, s), at(r + 1, s + 1), at(r, s + 1)};
      cap.faces.add(quad, 4);
    }
  return cap;
}

Mesh cone_part(int rings, int segments) {
  Mesh cone;
  cone.vertices = Positions::Zero(rings * segments + 1, 3);
  auto at = [&](int r, int s) { return r * segments + (s % segments); };
  for (int r = 0; r + 1 < rings; ++r)
    for (int s = 0; s < segments; ++s) {
      const int quad[4] = {at(r, s), at(r, s + 1), at(r + 1, s + 1), at(r + 1, s)};
      cone.faces.add(quad, 4);
    }
  const int tip = rings * segments;
  for (int s = 0; s < segments; ++s) {
    const int tri[3] = {at(rings - 1, s), at(rings - 1, s + 1), tip};
    cone.faces.add(tri, 3);
  }
  return cone;
}

Positions vertex_normals(const Mesh& mesh, const Positions& V) {
  Positions n = Positions::Zero(V.rows(), 3);
  for (int t = 0; t < mesh.triangle_count(); ++t) {
    const int a = mesh.triangles(t, 0), b = mesh.triangles(t, 1), c = mesh.triangles(t, 2);
    const Eigen::RowVector3d area = (V.row(b) - V.row(a)).cross(V.row(c) - V.row(a));
    n.row(a) += area;
    n.row(b) += area;
    n.row(c) += area;
  }
  for (int v = 0; v < n.rows(); ++v) {
    const double len = n.row(v).norm();
    if (len > 0) n.row(v) /= len;
  }
  return n;
}

double EyeLayout::almond(double x) const {
  const double mid = 0.5 * (x_in + x_out), half = 0.5 * std::abs(x_out - x_in);
  const double t = (x - mid) / half;
  if (std::abs(t) >= 1) return 0.0;
  return std::pow(1 - t * t, 0.75);
}

double EyeLayout::lid_shift(double x, double y_vertex, int side, const LidState& lids) const {
  const double a = almond(x);
  if (a == 0) return 0.0;
  if (side > 0) return lids.upper * a * (1 - ramp(0, upper_fall, y_vertex - y));
  return -lids.lower * a * (1 - ramp(0, lower_fall, y - y_vertex));
}

double EyeLayout::lid_thickness(double x, double middle, double corner) const {
  return corner + (middle - corner) * almond(x);
}

Eigen::Vector3d Eyeball::push(const Eigen::Vector3d& P, const Eigen::Vector3d& n, double lid) const {
  const Eigen::Vector3d d = P - centre;
  const double along = d.dot(n), outer = radius + lid;
  const double off_axis = std::sqrt(std::max(0.0, d.squaredNorm() - along * along));
  // How far along n the outer sphere's far side lies from P.
  const double gap =
      off_axis < outer ? std::sqrt(outer * outer - off_axis * off_axis) - along : -along - 4 * (off_axis - outer);
  return P + n * smooth_max(0.0, gap, 0.15);
}

Positions place_eyeball(const Positions& cap_directions, const Eyeball& ball, double cornea,
                        const Eigen::Vector3d& axis, const Eigen::Vector3d& liner_axis, const EyeLiner& liner) {
  const Eigen::Matrix3d R = Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), axis).toRotationMatrix();
  const Eigen::Matrix3d RL =
      Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), liner_axis).toRotationMatrix();
  const double rim = kEyeballRim;
  double last = rim;
  for (int v = 0; v < cap_directions.rows(); ++v)
    last = std::max(last, std::acos(std::clamp(cap_directions(v, 2), -1.0, 1.0)));
  Positions P(cap_directions.rows(), 3);
  for (int v = 0; v < P.rows(); ++v) {
    const Eigen::Vector3d d = cap_directions.row(v).transpose();
    const double angle = std::acos(std::clamp(d.z(), -1.0, 1.0));
    if (angle <= rim + 1e-9) {
      const double bulge = cornea * bump(angle / 0.5);
      P.row(v) = (ball.centre + R * d * (ball.radius + bulge)).transpose();
      continue;
    }
    // The liner: from the rim outwards and a little forwards, towards the skin's underside, in
    // the frame of liner_axis.
    const double t = (angle - rim) / (last - rim);
    const Eigen::Vector2d around = Eigen::Vector2d(d.x(), d.y()).normalized();
    const double radial = ball.radius * std::sin(rim) + liner.reach * t;
    const double height = ball.radius * (std::cos(rim) + liner.rise * t);
    P.row(v) = (ball.centre + RL * Eigen::Vector3d(radial * around.x(), radial * around.y(), height)).transpose();
  }
  return P;
}

FieldEvaluator::FieldEvaluator(const std::vector<double>& lower, const std::vector<double>& xc,
                               const std::vector<double>& yc, int skin_count, const Mesh& mesh, const Positions& rest)
    : vertex_count_(static_cast<int>(rest.rows())) {
  const Positions normals = vertex_normals(mesh, rest);
  sites_.resize(xc.size());
  for (size_t v = 0; v < xc.size(); ++v) {
    Site& s = sites_[v];
    s.x = xc[v];
    s.y = yc[v];
    s.lower = lower[v];
    s.P = rest.row(static_cast<int>(v)).transpose();
    int from = static_cast<int>(v);
    if (from >= skin_count) {
      double best = 1e300;
      for (int k = 0; k < skin_count; ++k) {
        const double d = (xc[k] - s.x) * (xc[k] - s.x) + (yc[k] - s.y) * (yc[k] - s.y);
        if (d < best) {
          best = d;
          from = k;
        }
      }
    }
    s.n = normals.row(from).transpose();
  }
}

Mesh pocket_grid(int ns, int nt) {
  Mesh pocket = open_grid(ns, nt).mesh;
  reverse_faces(pocket);
  return pocket;
}

double pocket_depth(double s, double t) { return (1 - s * s) * (1 - t * t); }

double pocket_lower(double t) { return ramp(0.8, -0.8, t); }

Positions FieldEvaluator::operator()(const Field& f, bool mirror) const {
  Positions offset = Positions::Zero(vertex_count_, 3);
  for (size_t v = 0; v < sites_.size(); ++v) {
    Site s = sites_[v];
    if (mirror) {
      s.x = -s.x;
      s.P.x() = -s.P.x();
      s.n.x() = -s.n.x();
    }
    Eigen::Vector3d d = f(s);
    if (mirror) d.x() = -d.x();
    offset.row(static_cast<int>(v)) = d.transpose();
  }
  return offset;
}

double MouthLayout::parting(double x) const { return 1 - ramp(corner - taper, corner, std::abs(x)); }

double MouthLayout::jaw_weight(const Site& s) const {
  const double beyond = std::max(0.0, std::abs(s.x) - corner);
  const double line = y + rise * beyond, half = band + band_growth * beyond;
  const double outer = ramp(line + half, line - half, s.y);
  const double inner = s.lower;
  const double t = parting(s.x);
  return (t * inner + (1 - t) * outer) * (1 - ramp(reach, reach + 2, std::abs(s.x))) *
         ramp(floor, floor + floor_fade, s.y);
}

}  // namespace retarget::synth
