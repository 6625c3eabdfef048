// with_many_parts(): the skin split at a seam, then pieces built one by one (rest positions,
// polygons, and how each vertex moves), appended with their offsets per controller.
#include "synthetic/avatar_trim.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "geometry/mesh_topology.h"

namespace retarget {

namespace {

using Eigen::Vector3d;

// A piece being built. Each vertex either follows one avatar vertex (takes its offsets) or,
// when `follow` is empty, the whole piece moves by the mean offset of `driver`.
struct Piece {
  std::vector<Vector3d> rest;
  std::vector<std::vector<int>> faces;  // local indices, counter-clockwise seen from outside
  std::vector<int> follow;              // per vertex, or empty
  std::vector<int> driver;              // when follow is empty
  int only = -2;                        // with a driver: -2 every controller, -1 none (still), else that one
};

struct Trim {
  const Rig& base;
  std::vector<int> skin;  // the base's largest piece, ascending
  double eye_width = 1;   // the left eye set's extent in x (cm): the pieces' scale
};

Vector3d at(const Rig& rig, int v) { return rig.neutral.vertices.row(v).transpose(); }

int landmark(const Rig& rig, const std::string& name) {
  const auto it = rig.landmarks.find(name);
  if (it == rig.landmarks.end()) throw Error(rig.name, "many parts: no landmark \"" + name + "\" to hang a piece from");
  return it->second;
}

std::vector<std::vector<int>> pieces_of(const Rig& rig) {
  const int n = rig.neutral.vertex_count();
  const Components c = connected_components(edge_topology(rig.neutral.triangles), n);
  std::vector<std::vector<int>> members(static_cast<size_t>(c.count()));
  for (int v = 0; v < n; ++v) members[static_cast<size_t>(c.component[static_cast<size_t>(v)])].push_back(v);
  return members;
}

// The skin vertex nearest p.
int nearest_skin(const Trim& t, const Vector3d& p) {
  int best = t.skin.front();
  double best_d = 1e300;
  for (int v : t.skin)
    if (const double d = (at(t.base, v) - p).squaredNorm(); d < best_d) best_d = d, best = v;
  return best;
}

// Area-weighted normal of the base at vertex v (over the triangles that hold it).
Vector3d normal_at(const Rig& rig, int v) {
  Vector3d n = Vector3d::Zero();
  const Triangles& T = rig.neutral.triangles;
  for (Eigen::Index f = 0; f < T.rows(); ++f)
    if (T(f, 0) == v || T(f, 1) == v || T(f, 2) == v)
      n += (at(rig, T(f, 1)) - at(rig, T(f, 0))).cross(at(rig, T(f, 2)) - at(rig, T(f, 0)));
  return n.norm() > 0 ? Vector3d(n.normalized()) : Vector3d::UnitZ();
}

// A strip of quads between two rows of k vertices (row a first), each column following `follow`.
Piece strip(const std::vector<Vector3d>& a, const std::vector<Vector3d>& b, const std::vector<int>& follow) {
  Piece p;
  const int k = static_cast<int>(a.size());
  p.rest = a;
  p.rest.insert(p.rest.end(), b.begin(), b.end());
  p.follow = follow;
  p.follow.insert(p.follow.end(), follow.begin(), follow.end());
  for (int i = 0; i + 1 < k; ++i) p.faces.push_back({i, i + 1, k + i + 1, k + i});
  return p;
}

// Lashes on one lid margin: `margin` sorted along +x, standing out along `out` (cm).
Piece lashes(const Trim& t, std::vector<int> margin, const Vector3d& out) {
  std::sort(margin.begin(), margin.end(),
            [&](int a, int b) { return t.base.neutral.vertices(a, 0) < t.base.neutral.vertices(b, 0); });
  std::vector<Vector3d> root, tip;
  for (int m : margin) {
    root.push_back(at(t.base, m) + 0.25 * out);
    tip.push_back(at(t.base, m) + out);
  }
  const bool upward = out.y() > 0;
  return upward ? strip(root, tip, margin) : strip(tip, root, margin);
}

// Both lashes of one eye set: the margin above the set's centroid and the one below.
std::vector<Piece> eye_lashes(const Trim& t, const std::vector<int>& eye) {
  if (eye.size() < 4) throw Error(t.base.name, "many parts: an eye set has fewer than 4 vertices");
  double cy = 0;
  for (int v : eye) cy += t.base.neutral.vertices(v, 1);
  cy /= static_cast<double>(eye.size());
  std::vector<int> upper, lower;
  for (int v : eye) (t.base.neutral.vertices(v, 1) >= cy ? upper : lower).push_back(v);
  const double s = t.eye_width;
  return {lashes(t, upper, Vector3d(0, 0.12 * s, 0.1 * s)), lashes(t, lower, Vector3d(0, -0.07 * s, 0.06 * s))};
}

// A brow strip through the side's three brow landmarks, floating over the skin.
Piece brow(const Trim& t, const std::string& side) {
  const Vector3d p[3] = {at(t.base, landmark(t.base, "brow_inner_" + side)),
                         at(t.base, landmark(t.base, "brow_middle_" + side)),
                         at(t.base, landmark(t.base, "brow_outer_" + side))};
  std::vector<Vector3d> lower, upper;
  std::vector<int> follow;
  const int samples = 12;
  for (int k = 0; k < samples; ++k) {
    const double s = 2.0 * k / (samples - 1);
    const int seg = std::min(1, static_cast<int>(s));
    const Vector3d q = p[seg] + (s - seg) * (p[seg + 1] - p[seg]);
    const int v = nearest_skin(t, q);
    const Vector3d n = normal_at(t.base, v);
    const Vector3d up = (Vector3d::UnitY() - Vector3d::UnitY().dot(n) * n).normalized();
    const Vector3d base = q + 0.05 * t.eye_width * n;  // q, not v: no two columns coincide
    lower.push_back(base - 0.05 * t.eye_width * up);
    upper.push_back(base + 0.05 * t.eye_width * up);
    follow.push_back(v);
  }
  if (p[2].x() < p[0].x()) {  // the right brow: columns along +x, as the left one's
    std::reverse(lower.begin(), lower.end());
    std::reverse(upper.begin(), upper.end());
    std::reverse(follow.begin(), follow.end());
  }
  return strip(lower, upper, follow);
}

// An iris: a fan of 12 triangles in front of the eyeball's vertex nearest the eye opening's
// centre (`opening`: the lid margins' centroid).
Piece iris(const Trim& t, const std::vector<int>& ball, const Vector3d& opening) {
  int front = ball.front();
  for (int v : ball)
    if ((at(t.base, v) - opening).squaredNorm() < (at(t.base, front) - opening).squaredNorm()) front = v;
  const Vector3d c = at(t.base, front) + Vector3d(0, 0, 0.01 * t.eye_width);
  const double r = 0.12 * t.eye_width;
  Piece p;
  p.rest.push_back(c);
  const int ring = 12;
  for (int k = 0; k < ring; ++k) {
    const double a = 2 * M_PI * k / ring;
    p.rest.push_back(c + Vector3d(r * std::cos(a), r * std::sin(a), -0.3 * r));
    p.faces.push_back({0, 1 + k, 1 + (k + 1) % ring});
  }
  p.driver = ball;
  return p;
}

// A curved slab of `columns` columns from x = -half to +half, its front at z_front(x), between
// heights y0 and y1, `depth` thick.
Piece slab(double half, double y0, double y1, double z_front, double bend, double depth, int columns) {
  Piece p;
  for (int i = 0; i < columns; ++i) {
    const double x = -half + 2 * half * i / (columns - 1);
    const double z = z_front - bend * (x / half) * (x / half);
    for (const double dz : {0.0, -depth})
      for (const double y : {y0, y1}) p.rest.emplace_back(x, y, z + dz);
  }
  // Column i: 4i front-bottom, 4i+1 front-top, 4i+2 back-bottom, 4i+3 back-top.
  for (int i = 0; i + 1 < columns; ++i) {
    const int a = 4 * i, b = 4 * (i + 1);
    p.faces.push_back({a, b, b + 1, a + 1});          // front
    p.faces.push_back({a + 2, a + 3, b + 3, b + 2});  // back
    p.faces.push_back({a + 1, b + 1, b + 3, a + 3});  // top
    p.faces.push_back({a, a + 2, b + 2, b});          // bottom
  }
  const int e = 4 * (columns - 1);
  p.faces.push_back({0, 1, 3, 2});
  p.faces.push_back({e, e + 2, e + 3, e + 1});
  return p;
}

// The skin vertices within `radius` of p (at least the nearest one).
std::vector<int> skin_near(const Trim& t, const Vector3d& p, double radius) {
  std::vector<int> near;
  for (int v : t.skin)
    if ((at(t.base, v) - p).norm() <= radius) near.push_back(v);
  if (near.empty()) near.push_back(nearest_skin(t, p));
  return near;
}

struct MouthPieces {
  Piece upper_teeth, lower_teeth, tongue;
};

// The jaw: the controller that moves the lower lip's middle furthest down.
int jaw_controller(const Rig& rig, const std::vector<int>& lower_lip) {
  int jaw = -1;
  double deepest = 0;
  for (int c = 0; c < rig.controller_count(); ++c) {
    double down = 0;
    for (int v : lower_lip) down -= rig.controllers[static_cast<size_t>(c)].offset(v, 1);
    if (down > deepest) deepest = down, jaw = c;
  }
  if (jaw < 0)
    throw Error(rig.name, "many parts: no controller moves the lower lip down (no jaw to hang the teeth on)");
  return jaw;
}

// As the teeth are in a head: the upper row on the skull (still), the lower row and the tongue
// on the jaw (the lower lip's mean offset under the jaw controller, no other).
MouthPieces mouth_pieces(const Trim& t) {
  const Vector3d up = at(t.base, landmark(t.base, "lip_upper_center"));
  const Vector3d down = at(t.base, landmark(t.base, "lip_lower_center"));
  const double w =
      0.5 * std::abs(at(t.base, landmark(t.base, "mouth_left")).x() - at(t.base, landmark(t.base, "mouth_right")).x());
  const double y0 = 0.5 * (up.y() + down.y()), z = std::min(up.z(), down.z()) - 0.3 * w;
  MouthPieces m;
  m.upper_teeth = slab(0.7 * w, y0 + 0.03 * w, y0 + 0.28 * w, z, 0.35 * w, 0.12 * w, 12);
  m.upper_teeth.driver = skin_near(t, up, 0.35 * w);
  m.upper_teeth.only = -1;
  m.lower_teeth = slab(0.65 * w, y0 - 0.26 * w, y0 - 0.03 * w, z - 0.04 * w, 0.35 * w, 0.12 * w, 12);
  m.lower_teeth.driver = skin_near(t, down, 0.35 * w);
  m.lower_teeth.only = jaw_controller(t.base, m.lower_teeth.driver);
  m.tongue = slab(0.45 * w, y0 - 0.3 * w, y0 - 0.18 * w, z - 0.25 * w, 0.1 * w, 0.5 * w, 6);
  m.tongue.driver = m.lower_teeth.driver;
  m.tongue.only = m.lower_teeth.only;
  return m;
}

// The base's pieces apart from the skin whose centroid is nearest p.
std::vector<int> piece_nearest(const std::vector<std::vector<int>>& pieces, size_t skin, const Rig& rig,
                               const Vector3d& p) {
  size_t best = skin;
  double best_d = 1e300;
  for (size_t c = 0; c < pieces.size(); ++c) {
    if (c == skin) continue;
    Vector3d centroid = Vector3d::Zero();
    for (int v : pieces[c]) centroid += at(rig, v);
    centroid /= static_cast<double>(pieces[c].size());
    if (const double d = (centroid - p).squaredNorm(); d < best_d) best_d = d, best = c;
  }
  if (best == skin) throw Error(rig.name, "many parts: no eyeball beside the skin");
  return pieces[best];
}

Vector3d centroid_of(const Rig& rig, const std::vector<int>& set) {
  Vector3d c = Vector3d::Zero();
  for (int v : set) c += at(rig, v);
  return c / static_cast<double>(set.size());
}

// Splits the skin at x = 0: faces whose centroid has x < 0 take duplicates of the vertices they
// share with the others. Appends the duplicates (their offsets the originals') to the rig.
void split_skin(Rig& rig, const std::vector<int>& skin) {
  const int n = rig.neutral.vertex_count();
  std::vector<char> in_skin(static_cast<size_t>(n), 0);
  for (int v : skin) in_skin[static_cast<size_t>(v)] = 1;
  Polygons& faces = rig.neutral.faces;
  std::vector<int> side(static_cast<size_t>(faces.size()), 0);  // +1 left (kept), -1 right, 0 not skin
  std::vector<char> used_left(static_cast<size_t>(n), 0), used_right(static_cast<size_t>(n), 0);
  for (int f = 0; f < faces.size(); ++f) {
    double x = 0;
    for (int k = 0; k < faces.degree(f); ++k) x += rig.neutral.vertices(faces.begin(f)[k], 0);
    if (!in_skin[static_cast<size_t>(faces.begin(f)[0])]) continue;
    side[static_cast<size_t>(f)] = x < 0 ? -1 : 1;
    for (int k = 0; k < faces.degree(f); ++k)
      (x < 0 ? used_right : used_left)[static_cast<size_t>(faces.begin(f)[k])] = 1;
  }
  std::vector<int> twin(static_cast<size_t>(n), -1);
  std::vector<int> originals;
  for (int v = 0; v < n; ++v)
    if (used_left[static_cast<size_t>(v)] && used_right[static_cast<size_t>(v)]) {
      twin[static_cast<size_t>(v)] = n + static_cast<int>(originals.size());
      originals.push_back(v);
    }
  for (int f = 0; f < faces.size(); ++f)
    if (side[static_cast<size_t>(f)] < 0)
      for (int k = faces.offsets[static_cast<size_t>(f)]; k < faces.offsets[static_cast<size_t>(f) + 1]; ++k)
        if (const int d = twin[static_cast<size_t>(faces.indices[static_cast<size_t>(k)])]; d >= 0)
          faces.indices[static_cast<size_t>(k)] = d;
  const Eigen::Index m = static_cast<Eigen::Index>(originals.size());
  Positions& V = rig.neutral.vertices;
  V.conservativeResize(n + m, 3);
  for (Eigen::Index i = 0; i < m; ++i) V.row(n + i) = V.row(originals[static_cast<size_t>(i)]);
  for (Controller& c : rig.controllers) {
    c.offset.conservativeResize(n + m, 3);
    for (Eigen::Index i = 0; i < m; ++i) c.offset.row(n + i) = c.offset.row(originals[static_cast<size_t>(i)]);
  }
}

// Appends a piece to the rig (positions, polygons, offsets from the base); returns its vertices.
std::vector<int> append(Rig& rig, const Rig& base, const Piece& p) {
  const int first = rig.neutral.vertex_count();
  const Eigen::Index k = static_cast<Eigen::Index>(p.rest.size());
  rig.neutral.vertices.conservativeResize(first + k, 3);
  for (Eigen::Index i = 0; i < k; ++i) rig.neutral.vertices.row(first + i) = p.rest[static_cast<size_t>(i)].transpose();
  for (const std::vector<int>& face : p.faces) {
    std::vector<int> global;
    for (int v : face) global.push_back(first + v);
    rig.neutral.faces.add(global.data(), static_cast<int>(global.size()));
  }
  for (size_t c = 0; c < rig.controllers.size(); ++c) {
    Positions& offset = rig.controllers[c].offset;
    const Positions& from = base.controllers[c].offset;
    offset.conservativeResize(first + k, 3);
    Eigen::RowVector3d mean = Eigen::RowVector3d::Zero();
    const bool moves = p.only == -2 || p.only == static_cast<int>(c);
    for (int v : p.driver) mean += from.row(v);
    if (!p.driver.empty()) mean /= static_cast<double>(p.driver.size());
    if (!moves) mean.setZero();
    for (Eigen::Index i = 0; i < k; ++i)
      offset.row(first + i) = p.follow.empty() ? mean : Eigen::RowVector3d(from.row(p.follow[static_cast<size_t>(i)]));
  }
  std::vector<int> vertices(static_cast<size_t>(k));
  for (Eigen::Index i = 0; i < k; ++i) vertices[static_cast<size_t>(i)] = first + static_cast<int>(i);
  return vertices;
}

}  // namespace

SyntheticAvatar with_many_parts(const SyntheticAvatar& base, const std::string& name) {
  const Rig& b = base.rig;
  const std::vector<std::vector<int>> pieces = pieces_of(b);
  size_t skin = 0;
  for (size_t c = 1; c < pieces.size(); ++c)
    if (pieces[c].size() > pieces[skin].size()) skin = c;
  Trim t{b, pieces[skin]};
  if (b.eyes.left.size() < 4 || b.eyes.right.size() < 4) throw Error(b.name, "many parts: the rig has no eye sets");
  double lo = 1e300, hi = -1e300;
  for (int v : b.eyes.left) lo = std::min(lo, b.neutral.vertices(v, 0)), hi = std::max(hi, b.neutral.vertices(v, 0));
  t.eye_width = hi - lo;

  std::vector<Piece> added;
  for (const std::vector<int>* eye : {&b.eyes.left, &b.eyes.right})
    for (Piece& p : eye_lashes(t, *eye)) added.push_back(std::move(p));
  added.push_back(brow(t, "left"));
  added.push_back(brow(t, "right"));
  const std::vector<int> balls[2] = {piece_nearest(pieces, skin, b, centroid_of(b, b.eyes.left)),
                                     piece_nearest(pieces, skin, b, centroid_of(b, b.eyes.right))};
  added.push_back(iris(t, balls[0], centroid_of(b, b.eyes.left)));
  added.push_back(iris(t, balls[1], centroid_of(b, b.eyes.right)));
  MouthPieces mouth = mouth_pieces(t);

  SyntheticAvatar out = base;
  Rig& rig = out.rig;
  rig.name = name;
  split_skin(rig, t.skin);
  for (const Piece& p : added) append(rig, b, p);
  std::vector<int> teeth = append(rig, b, mouth.upper_teeth);
  const std::vector<int> lower = append(rig, b, mouth.lower_teeth);
  teeth.insert(teeth.end(), lower.begin(), lower.end());
  const std::vector<int> tongue = append(rig, b, mouth.tongue);
  triangulate(rig.neutral);
  rig.parts = {{"EyeLeft", PartKind::eye_left, "", balls[0]},
               {"EyeRight", PartKind::eye_right, "", balls[1]},
               {"Teeth", PartKind::teeth, "", teeth},
               {"Tongue", PartKind::tongue, "", tongue}};
  out.description =
      base.description + ", dressed with many parts (lashes, brows, irises, teeth, tongue; the skin in two islands)";
  return out;
}

}  // namespace retarget
