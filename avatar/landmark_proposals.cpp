#include "avatar/landmark_proposals.h"

#include <fmt/format.h>

#include <Eigen/Geometry>
#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <functional>
#include <iterator>
#include <map>
#include <utility>

#include "avatar/face_profile.h"
#include "core/error.h"
#include "geometry/metrics.h"

namespace retarget {

const char* part_kind_name(ProposedPart::Kind kind) {
  switch (kind) {
    case ProposedPart::Kind::eye:
      return "eye";
    case ProposedPart::Kind::teeth:
      return "teeth";
    case ProposedPart::Kind::mouth:
      return "mouth";
    default:
      return "other";
  }
}

void LandmarkProposalOptions::validate(const std::string& key_path) const {
  weld.validate(key_path + ".weld");
  mirror.validate(key_path + ".mirror");
  openings.validate(key_path + ".openings");
}

namespace proposal_detail {

using Eigen::Vector3d;

// What the proposal knows about the face while it reads landmarks off the openings.
struct Face {
  const Rig& rig;
  const Positions& V;
  const MirrorPlane& mirror;
  FaceFrame frame;
  std::map<std::pair<int, int>, int> opposite;  // directed head edge (a, b) -> third vertex of its triangle
  std::vector<std::vector<int>> neighbours;     // welded head neighbours

  Vector3d at(int v) const { return V.row(v).transpose(); }
  double lateral_of(const Vector3d& p) const { return mirror.side(p) * (frame.left.dot(mirror.normal) >= 0 ? 1 : -1); }
  double lateral(int v) const { return mirror.side(at(v)) * (frame.left.dot(mirror.normal) >= 0 ? 1 : -1); }
  double upness(int v) const {  // how far above the vertex its neighbours sit, on average
    const std::vector<int>& n = neighbours[static_cast<size_t>(v)];
    if (n.empty()) return 0;
    Vector3d mean = Vector3d::Zero();
    for (int u : n) mean += at(u);
    return frame.up.dot(mean / static_cast<double>(n.size()) - at(v));
  }
};

std::string where_of(const Rig& rig) { return rig.source.empty() ? "avatar " + rig.name : rig.source; }

double clamp01(double x) { return std::min(1.0, std::max(0.0, x)); }

// An opening's rim read as two sides between its corners (the extremes along the left axis).
struct Rim {
  int corner_left = -1, corner_right = -1;
  std::vector<int> upper, lower;            // the sides' vertices, corners excluded
  std::vector<int> upper_path, lower_path;  // hole: each side in rim order, a corner at each end
  std::vector<std::array<int, 2>> pairs;    // slit: (upper, lower) per parting pair
};

Rim read_rim(const Face& face, const FaceOpening& opening) {
  Rim rim;
  const std::vector<int>& v = opening.vertices;
  const auto by_lateral = [&](int a, int b) { return face.lateral(a) < face.lateral(b); };
  rim.corner_left = *std::max_element(v.begin(), v.end(), by_lateral);
  rim.corner_right = *std::min_element(v.begin(), v.end(), by_lateral);
  if (opening.kind == FaceOpening::Kind::hole) {
    const size_t n = v.size();
    const size_t a = static_cast<size_t>(std::find(v.begin(), v.end(), rim.corner_left) - v.begin());
    const size_t b = static_cast<size_t>(std::find(v.begin(), v.end(), rim.corner_right) - v.begin());
    // Two chains: a -> b and b -> a along the loop; each scored by where its edges' triangles lie.
    std::vector<int> chain[2];
    double up[2] = {0, 0};
    int edges[2] = {0, 0};
    for (int side = 0; side < 2; ++side) {
      const size_t from = side == 0 ? a : b, to = side == 0 ? b : a;
      for (size_t i = from; i != to; i = (i + 1) % n) {
        const int p = v[i], q = v[(i + 1) % n];
        if (i != from) chain[side].push_back(p);
        const auto it = face.opposite.find({p, q});
        if (it == face.opposite.end()) continue;
        up[side] += face.frame.up.dot(face.at(it->second) - 0.5 * (face.at(p) + face.at(q)));
        ++edges[side];
      }
    }
    // An open rim: the side that sits higher at rest is the upper one. A closed one (a seam, the
    // sides together at rest): the side whose triangles lie above it.
    double height[2] = {0, 0};
    for (int side = 0; side < 2; ++side) {
      for (int p : chain[side]) height[side] += face.frame.up.dot(face.at(p));
      if (!chain[side].empty()) height[side] /= static_cast<double>(chain[side].size());
    }
    const double width = face.lateral(rim.corner_left) - face.lateral(rim.corner_right);
    const bool open = !chain[0].empty() && !chain[1].empty() && std::abs(height[0] - height[1]) > 0.1 * width;
    const double u0 = open ? height[0] : edges[0] ? up[0] / edges[0] : 0;
    const double u1 = open ? height[1] : edges[1] ? up[1] / edges[1] : 0;
    rim.upper = u0 >= u1 ? chain[0] : chain[1];
    rim.lower = u0 >= u1 ? chain[1] : chain[0];
    const int ends[2][2] = {{rim.corner_left, rim.corner_right}, {rim.corner_right, rim.corner_left}};
    for (int side = 0; side < 2; ++side) {
      std::vector<int> path{ends[side][0]};
      path.insert(path.end(), chain[side].begin(), chain[side].end());
      path.push_back(ends[side][1]);
      ((u0 >= u1) == (side == 0) ? rim.upper_path : rim.lower_path) = std::move(path);
    }
  } else {
    for (const std::array<int, 2>& p : opening.pairs) {
      const bool first_up = face.upness(p[0]) >= face.upness(p[1]);
      const int up = first_up ? p[0] : p[1], down = first_up ? p[1] : p[0];
      rim.pairs.push_back({up, down});
      rim.upper.push_back(up);
      rim.lower.push_back(down);
    }
  }
  return rim;
}

// The side vertex whose left coordinate is nearest `target`.
int nearest_along(const Face& face, const std::vector<int>& side, double target) {
  int best = -1;
  double best_key = std::numeric_limits<double>::infinity();
  for (int v : side) {
    // Ties (a side with an even number of vertices, both middle ones equally near): the one on the
    // face's left.
    const double key = std::abs(face.lateral(v) - target) - 1e-6 * face.lateral(v);
    if (key < best_key) {
      best_key = key;
      best = v;
    }
  }
  return best;
}

// The middle vertex of a rim side: `path` runs between the corners (included at its ends); of
// the vertices between them, the middle one in order from the face's right corner to its left
// (of an even count, the one nearer the left).
int middle_of_side(const Face& face, std::vector<int> path) {
  if (path.size() < 3) return -1;
  if (face.lateral(path.front()) > face.lateral(path.back())) std::reverse(path.begin(), path.end());
  const size_t inner = path.size() - 2;
  return path[1 + inner / 2];
}

// For a slit: the frontmost parting pair whose midpoint is within `band` of `target` along the
// left axis (the nearest pair if none is).
std::array<int, 2> front_pair_at(const Face& face, const Rim& rim, double target, double band) {
  // The frontmost pair in the band; then, among the pairs in the band no more than `band` behind
  // it, the one whose sides touch most closely at rest (where the lips or lids meet, not the
  // outer surface of a snarl's fold).
  std::array<int, 2> best{-1, -1}, nearest{-1, -1};
  double best_front = -std::numeric_limits<double>::infinity(), nearest_d = std::numeric_limits<double>::infinity();
  const auto front_of = [&](const std::array<int, 2>& p) {
    return face.frame.forward.dot(0.5 * (face.at(p[0]) + face.at(p[1])));
  };
  const auto mid_of = [&](const std::array<int, 2>& p) { return 0.5 * (face.lateral(p[0]) + face.lateral(p[1])); };
  for (const std::array<int, 2>& p : rim.pairs) {
    if (std::abs(mid_of(p) - target) <= band) best_front = std::max(best_front, front_of(p));
    if (std::abs(mid_of(p) - target) < nearest_d) {
      nearest_d = std::abs(mid_of(p) - target);
      nearest = p;
    }
  }
  double best_gap = std::numeric_limits<double>::infinity();
  for (const std::array<int, 2>& p : rim.pairs) {
    if (std::abs(mid_of(p) - target) > band || front_of(p) < best_front - band) continue;
    const double gap = (face.at(p[0]) - face.at(p[1])).norm();
    if (gap < best_gap) {
      best_gap = gap;
      best = p;
    }
  }
  return best[0] >= 0 ? best : nearest;
}

// The upper and lower rim vertices at `target` along the left axis.
std::array<int, 2> rim_at(const Face& face, const FaceOpening& opening, const Rim& rim, double target, double width) {
  if (opening.kind == FaceOpening::Kind::slit) return front_pair_at(face, rim, target, 0.1 * width);
  if (target != 0.0) return {middle_of_side(face, rim.upper_path), middle_of_side(face, rim.lower_path)};
  return {nearest_along(face, rim.upper, target), nearest_along(face, rim.lower, target)};
}

double sphere_fit_residual(const Positions& V, const std::vector<int>& vertices, Vector3d& centre, double& radius) {
  // |x|^2 = 2 c . x + k, linear least squares; residual: RMS(|x - c| - r) / r.
  Eigen::MatrixXd A(static_cast<Eigen::Index>(vertices.size()), 4);
  Eigen::VectorXd b(static_cast<Eigen::Index>(vertices.size()));
  for (size_t i = 0; i < vertices.size(); ++i) {
    const Vector3d x = V.row(vertices[i]).transpose();
    A.row(static_cast<Eigen::Index>(i)) << 2 * x.x(), 2 * x.y(), 2 * x.z(), 1;
    b(static_cast<Eigen::Index>(i)) = x.squaredNorm();
  }
  const Eigen::Vector4d s = A.colPivHouseholderQr().solve(b);
  centre = s.head<3>();
  const double r2 = s(3) + centre.squaredNorm();
  if (!(r2 > 0)) return std::numeric_limits<double>::infinity();
  const double r = std::sqrt(r2);
  radius = r;
  double sum = 0;
  for (int v : vertices) {
    const double d = (V.row(v).transpose() - centre).norm() - r;
    sum += d * d;
  }
  return std::sqrt(sum / static_cast<double>(vertices.size())) / r;
}

// A brow as its controllers show it (vertices; -1: not found).
struct BrowReading {
  std::vector<int> controllers;  // what moves it
  int inner = -1, middle = -1, outer = -1;
};

// The region above an eye (its rim's vertices sorted, its centre) and the controllers that move
// it: the brow's.
struct BrowRegion {
  std::vector<int> vertices;     // head vertices above the eye, on its side of the mirror plane
  std::vector<char> inside;      // per rig vertex: one of `vertices`
  std::vector<int> controllers;  // each lifts or lowers the region and leaves the eye's rim mostly still
};

double lift_of(const Face& face, const Positions& D, int v) {
  return std::abs(face.frame.up.dot(D.row(v).transpose()));
}

BrowRegion brow_region(const Face& face, const std::vector<int>& head, const std::vector<int>& rim,
                       const Vector3d& centre, double eye_d) {
  BrowRegion out;
  out.inside.assign(static_cast<size_t>(face.V.rows()), 0);
  for (int v : head) {
    const Vector3d d = face.at(v) - centre;
    const double above = face.frame.up.dot(d), across = std::abs(face.lateral(v) - face.lateral_of(centre));
    if (above <= 0 || above > 0.8 * eye_d || across > 0.5 * eye_d) continue;
    if (face.frame.forward.dot(d) < -0.3 * eye_d) continue;
    if (face.lateral(v) * face.lateral_of(centre) <= 0) continue;  // the other side's brow
    if (std::binary_search(rim.begin(), rim.end(), v)) continue;
    out.vertices.push_back(v);
    out.inside[static_cast<size_t>(v)] = 1;
  }
  for (int c = 0; c < face.rig.controller_count() && !out.vertices.empty(); ++c) {
    const Positions& D = face.rig.controllers[static_cast<size_t>(c)].offset;
    double inside = 0, total = 0, lift = 0, rim_motion = 0;
    for (int v : out.vertices) {
      inside += lift_of(face, D, v);
      lift = std::max(lift, lift_of(face, D, v));
    }
    for (int v : head) total += D.row(v).norm();
    for (int v : rim) rim_motion = std::max(rim_motion, D.row(v).norm());
    if (total <= 0 || inside < 0.2 * total) continue;  // a controller of the whole face, not of a brow
    if (rim_motion > 0.5 * lift) continue;             // a lid's controller
    out.controllers.push_back(c);
  }
  return out;
}

// The crest of the brow ridge at or near `at`: on the cut through `at` parallel to the mirror
// plane, a quarter of an eye distance up and down, `at` itself if the profile bends outwards there
// (over arcs of 5% of the eye distance, so the mesh's density does not matter), else the point
// where it bends outwards most sharply among the vertices `counts` admits. -1 if it bends outwards
// nowhere.
int brow_crest(const Face& face, const Triangles& head_triangles, int at, double eye_d,
               const std::function<bool(int)>& counts) {
  MirrorPlane cut = face.mirror;
  cut.offset = cut.normal.dot(face.at(at));
  const std::vector<ProfilePoint> down = walk_profile(face.V, head_triangles, cut, at, -face.frame.up, 0.25 * eye_d);
  const std::vector<ProfilePoint> up = walk_profile(face.V, head_triangles, cut, at, face.frame.up, 0.25 * eye_d);
  std::vector<ProfilePoint> line(down.rbegin(), down.rend());  // bottom to top
  if (up.size() > 1) line.insert(line.end(), up.begin() + 1, up.end());
  std::vector<double> arc(line.size(), 0);
  for (size_t i = 1; i < line.size(); ++i) arc[i] = arc[i - 1] + (line[i].position - line[i - 1].position).norm();
  const double scale = 0.05 * eye_d;
  const size_t start = down.empty() ? 0 : down.size() - 1;  // `at` in `line`
  int best = -1;
  double sharpest = 0;
  for (size_t i = 1; i + 1 < line.size(); ++i) {
    if (!counts(line[i].vertex) && i != start) continue;
    size_t j = i, k = i;
    while (j > 0 && arc[i] - arc[j] < scale) --j;
    while (k + 1 < line.size() && arc[k] - arc[i] < scale) ++k;
    const Vector3d a = line[i].position - line[j].position, b = line[k].position - line[i].position;
    const double ax = face.frame.forward.dot(a), ay = face.frame.up.dot(a);
    const double bx = face.frame.forward.dot(b), by = face.frame.up.dot(b);
    const double turn = std::atan2(ax * by - ay * bx, ax * bx + ay * by);  // > 0: outwards, going up
    if (i == start && turn > 0) return at;                                 // on the ridge already
    if (turn > sharpest && counts(line[i].vertex)) {
      sharpest = turn;
      best = line[i].vertex;
    }
  }
  return best;
}

// The brow in `region` (see propose_landmarks); `other`: the other eye's, whose own controllers
// (not shared with this side) take the middle of the forehead.
BrowReading read_brow(const Face& face, const Triangles& head_triangles, const BrowRegion& region,
                      const BrowRegion& other, double eye_d) {
  BrowReading out;
  out.controllers = region.controllers;
  if (region.controllers.empty()) return out;
  const auto motion = [&](int c, int v) {
    return lift_of(face, face.rig.controllers[static_cast<size_t>(c)].offset, v);
  };
  std::vector<double> lift(static_cast<size_t>(face.V.rows()), 0);  // the most any of them lifts each vertex
  for (int c : region.controllers)
    for (int v : region.vertices) lift[static_cast<size_t>(v)] = std::max(lift[static_cast<size_t>(v)], motion(c, v));
  std::vector<int> others;  // the other brow's own controllers
  for (int c : other.controllers)
    if (std::find(region.controllers.begin(), region.controllers.end(), c) == region.controllers.end())
      others.push_back(c);
  // Mostly this brow's: its controllers lift it at least three times as much as the other brow's do
  // (three quarters of the motion; not the glabella between the brows, which both move).
  const auto own = [&](int v) {
    double theirs = 0;
    for (int c : others) theirs = std::max(theirs, motion(c, v));
    return lift[static_cast<size_t>(v)] >= 3 * theirs;
  };
  int peak = -1;
  for (int v : region.vertices)
    if (own(v) && (peak < 0 || lift[static_cast<size_t>(v)] > lift[static_cast<size_t>(peak)])) peak = v;
  if (peak < 0 || !(lift[static_cast<size_t>(peak)] > 0)) return out;
  const double top = lift[static_cast<size_t>(peak)];
  const auto on_brow = [&](int v, double share) {
    return region.inside[static_cast<size_t>(v)] && lift[static_cast<size_t>(v)] >= share * top && own(v);
  };
  const int crest = brow_crest(face, head_triangles, peak, eye_d, [&](int v) { return on_brow(v, 0.5); });
  const int middle = crest >= 0 ? crest : peak;
  const double height = face.frame.up.dot(face.at(middle));
  std::vector<int> band;
  for (int v : region.vertices)
    if (on_brow(v, 0.25) && std::abs(face.frame.up.dot(face.at(v)) - height) < 0.1 * eye_d) band.push_back(v);
  if (band.size() < 3) return out;
  // The ends: the band's extremes from the mirror plane (nearest, furthest).
  const auto by_distance = [&](int a, int b) { return std::abs(face.lateral(a)) < std::abs(face.lateral(b)); };
  out.middle = middle;
  out.inner = *std::min_element(band.begin(), band.end(), by_distance);
  out.outer = *std::max_element(band.begin(), band.end(), by_distance);
  return out;
}

void check_rig(const Rig& rig, const std::string& where) {
  if (rig.neutral.vertex_count() < 4 || rig.neutral.triangle_count() == 0)
    throw Error(where, fmt::format("the neutral mesh has {} vertices and {} triangles: too few to be a face to find "
                                   "landmarks on",
                                   rig.neutral.vertex_count(), rig.neutral.triangle_count()));
  if (rig.controller_count() == 0)
    throw Error(where,
                "the rig has no controllers: landmarks are proposed from what the controllers open and close (a "
                "mouth-opening and an eye-closing target at least); add them, or write `landmarks:` and `eyes:` "
                "into rig.yaml by hand");
}

// The head (the neutral mesh's largest connected part) seen through the weld.
struct Head {
  Weld weld;
  HeadAndParts pieces;
  std::vector<int> vertices;  // head vertices, one per welded group
  Positions points;           // #vertices x 3: their rest positions
  double diagonal = 0;        // the points' bounding-box diagonal, rig units
};

Head read_head(const Rig& rig, const LandmarkProposalOptions& options, const std::string& where) {
  Weld weld = weld_rig_vertices(rig, options.weld);
  HeadAndParts pieces = split_head_and_parts(rig, weld);
  Head h{std::move(weld), std::move(pieces), {}, {}, 0};
  for (int v = 0; v < rig.neutral.vertex_count(); ++v)
    if (h.pieces.head[static_cast<size_t>(v)] && h.weld.representative[static_cast<size_t>(v)] == v)
      h.vertices.push_back(v);
  h.points.resize(static_cast<Eigen::Index>(h.vertices.size()), 3);
  for (size_t i = 0; i < h.vertices.size(); ++i)
    h.points.row(static_cast<Eigen::Index>(i)) = rig.neutral.vertices.row(h.vertices[i]);
  h.diagonal = bounding_box_diagonal(h.points);
  if (h.points.rows() < 4)
    throw Error(where, fmt::format("the head (the neutral mesh's largest connected part) has {} vertices: too few to "
                                   "be a face to find landmarks on",
                                   h.points.rows()));
  return h;
}

MirrorPlane read_mirror(const Head& head, const LandmarkProposalOptions& options, const std::string& where) {
  MirrorPlane mirror;
  try {
    mirror = find_mirror_plane(head.points, options.mirror);
  } catch (const Error& e) {
    throw Error(where, e.what());
  }
  if (mirror.error > 0.01)
    throw Error(where, fmt::format("the head is not mirror-symmetric (a mirrored point lies {:.1f}% of the head's size "
                                   "from the surface, at best): the left-right axis cannot be found; write "
                                   "`landmarks:` and `eyes:` into rig.yaml by hand",
                                   100 * mirror.error));
  return mirror;
}

// Eyes: the mirrored pair of openings that the rig opens or closes most (open holes before
// closed slits: an eye open at rest shows as a hole). Mouth: the opening on the plane, away
// from the eyes, that the rig opens most. A pair whose two openings are opened by the mouth's
// own controller is the mouth's two sides, not eyes: the next pair is tried.
struct EyePair {
  int left = -1, right = -1;  // indices into openings (sides decided later)
  double score = 0;
  bool hole = false;
};

struct EyeCandidates {
  std::vector<EyePair> pairs;  // best first
  double best_hole_score = 0;
};

EyeCandidates eye_candidates(const std::vector<FaceOpening>& openings, const MirrorPlane& mirror, double diagonal,
                             const std::string& where) {
  EyeCandidates out;
  std::vector<EyePair>& pairs = out.pairs;
  double best_slit_score = 0;
  for (size_t a = 0; a < openings.size(); ++a)
    for (size_t b = a + 1; b < openings.size(); ++b) {
      const FaceOpening &A = openings[a], &B = openings[b];
      if (A.kind != B.kind || A.opening <= 0 || B.opening <= 0) continue;
      const double sa = mirror.side(A.centre), sb = mirror.side(B.centre);
      if (sa * sb >= 0 || std::min(std::abs(sa), std::abs(sb)) < 0.02 * diagonal) continue;
      if ((mirror.reflect(A.centre) - B.centre).norm() > 0.25 * std::max(A.size, B.size) + 0.02 * diagonal) continue;
      if (std::max(A.size, B.size) > 1.5 * std::min(A.size, B.size) + 0.01 * diagonal) continue;
      const bool hole = A.kind == FaceOpening::Kind::hole;
      pairs.push_back({static_cast<int>(a), static_cast<int>(b), std::min(A.opening, B.opening), hole});
      (hole ? out.best_hole_score : best_slit_score) =
          std::max(hole ? out.best_hole_score : best_slit_score, pairs.back().score);
    }
  const bool holes = out.best_hole_score > 0 && out.best_hole_score >= 0.1 * best_slit_score;
  std::sort(pairs.begin(), pairs.end(), [&](const EyePair& x, const EyePair& y) {
    if (x.hole != y.hole) return x.hole == holes;
    return x.score > y.score;
  });
  if (pairs.empty())
    throw Error(where,
                "no eyes found: no mirrored pair of openings (eye sockets, lid slits) that a controller opens or "
                "closes; give the rig eye-closing targets, or write `eyes:` (the vertices around each eye) and the "
                "eye landmarks into rig.yaml by hand");
  return out;
}

// The chosen eye pair and the mouth openings that go with it.
struct EyesAndMouths {
  EyePair eyes;
  std::vector<size_t> mouths;  // indices into openings: on the plane, away from the eyes
  FaceOpening::Kind mouth_kind = FaceOpening::Kind::hole;
  double mouth_best = 0;                     // the most any of `mouths` of mouth_kind opens
  const FaceOpening* first_mouth = nullptr;  // the last of `mouths` that opens by mouth_best
};

// The mouth openings for the eye pair `candidate` (empty if none).
std::vector<size_t> mouths_for(const std::vector<FaceOpening>& openings, const MirrorPlane& mirror,
                               const EyePair& candidate) {
  const FaceOpening &A = openings[static_cast<size_t>(candidate.left)],
                    &B = openings[static_cast<size_t>(candidate.right)];
  const Vector3d middle = 0.5 * (A.centre + B.centre);
  const double distance = (A.centre - B.centre).norm();
  std::vector<size_t> mouths;
  for (size_t k = 0; k < openings.size(); ++k) {
    const FaceOpening& o = openings[k];
    if (o.opening <= 0 || static_cast<int>(k) == candidate.left || static_cast<int>(k) == candidate.right) continue;
    if (std::abs(mirror.side(o.centre)) > 0.1 * distance) continue;
    Vector3d along = o.centre - middle;
    along -= mirror.normal * mirror.normal.dot(along);
    if (along.norm() < 0.2 * distance) continue;
    mouths.push_back(k);
  }
  return mouths;
}

EyesAndMouths choose_eyes(const std::vector<FaceOpening>& openings, const MirrorPlane& mirror,
                          const std::vector<EyePair>& pairs, const std::string& where) {
  EyesAndMouths out;
  bool mouth_seen = false;
  for (const EyePair& candidate : pairs) {
    out.mouths = mouths_for(openings, mirror, candidate);
    if (out.mouths.empty()) continue;
    mouth_seen = true;
    double best_mouth_hole = 0, best_mouth_slit = 0;
    for (size_t k : out.mouths) {
      double& best = openings[k].kind == FaceOpening::Kind::hole ? best_mouth_hole : best_mouth_slit;
      best = std::max(best, openings[k].opening);
    }
    const bool mouth_hole = best_mouth_hole > 0 && best_mouth_hole >= 0.1 * best_mouth_slit;
    out.mouth_kind = mouth_hole ? FaceOpening::Kind::hole : FaceOpening::Kind::slit;
    out.mouth_best = mouth_hole ? best_mouth_hole : best_mouth_slit;
    for (size_t k : out.mouths)
      if (openings[k].kind == out.mouth_kind && openings[k].opening == out.mouth_best) out.first_mouth = &openings[k];
    const int mouth_controller = out.first_mouth->controller;
    if (openings[static_cast<size_t>(candidate.left)].controller == mouth_controller &&
        openings[static_cast<size_t>(candidate.right)].controller == mouth_controller)
      continue;
    out.eyes = candidate;
    break;
  }
  if (out.eyes.left < 0 && !mouth_seen)
    throw Error(
        where,
        "no mouth found: no opening on the face's mirror plane below the eyes that a controller opens (lips cut "
        "open, a seam or folded lips that part); give the rig a mouth-opening target, or write the mouth "
        "landmarks (mouth_left, mouth_right, lip_upper_center, lip_lower_center) into rig.yaml by hand");
  if (out.eyes.left < 0)
    throw Error(where,
                "no eyes found: every mirrored pair of openings is opened by the mouth's controller (the two sides of "
                "the mouth, not eyes); give the rig eye-closing targets, or write `eyes:` (the vertices around each "
                "eye) and the eye landmarks into rig.yaml by hand");
  return out;
}

// The frame: up from the mouth to the eyes, forward to the side of the head the eyes are on.
FaceFrame face_frame(const MirrorPlane& mirror, const Vector3d& eye_mid, const Vector3d& mouth_centre,
                     const Vector3d& head_centre) {
  FaceFrame frame;
  Vector3d up = eye_mid - mouth_centre;
  up -= mirror.normal * mirror.normal.dot(up);
  frame.up = up.normalized();
  Vector3d forward = mirror.normal.cross(frame.up).normalized();
  if (forward.dot(eye_mid - head_centre) < 0) forward = -forward;
  frame.forward = forward;
  frame.left = frame.up.cross(forward);
  return frame;
}

// Among mouths of the chosen kind that open at least half as much as the best, the frontmost
// (a mouth pocket or the inside of the lips sits behind the lips' line).
const FaceOpening* choose_mouth(const std::vector<FaceOpening>& openings, const EyesAndMouths& found,
                                const Vector3d& forward, double diagonal, double eye_distance) {
  const FaceOpening* mouth = found.first_mouth;
  for (size_t k : found.mouths) {
    const FaceOpening& o = openings[k];
    if (o.kind == found.mouth_kind && o.opening >= 0.5 * found.mouth_best &&
        forward.dot(o.centre) > forward.dot(mouth->centre) + 1e-9 * diagonal)
      mouth = &o;
  }
  // Lips that touch in front of a hole (a mouth opening deep inside, behind closed lips, as on a
  // scanned human head): the lips' line is the slit, the frontmost of those opening at least half
  // as much as the best slit.
  if (mouth->kind == FaceOpening::Kind::hole) {
    double best_slit = 0;
    for (size_t k : found.mouths)
      if (openings[k].kind == FaceOpening::Kind::slit) best_slit = std::max(best_slit, openings[k].opening);
    const FaceOpening* lips = nullptr;
    for (size_t k : found.mouths) {
      const FaceOpening& o = openings[k];
      if (o.kind != FaceOpening::Kind::slit || o.opening < 0.5 * best_slit) continue;
      if (forward.dot(o.centre) < forward.dot(mouth->centre) + 0.05 * eye_distance) continue;
      if (!lips || forward.dot(o.centre) > forward.dot(lips->centre)) lips = &o;
    }
    if (lips) mouth = lips;
  }
  return mouth;
}

// A slit mouth: the pairs of every slit that shares a vertex with it (the lips part under
// several controllers; together they trace the whole line).
FaceOpening merged_slit(const std::vector<FaceOpening>& openings, const FaceOpening& mouth) {
  FaceOpening merged = mouth;
  for (const FaceOpening& o : openings) {
    if (o.kind != FaceOpening::Kind::slit || &o == &mouth) continue;
    std::vector<int> shared;
    std::set_intersection(o.vertices.begin(), o.vertices.end(), mouth.vertices.begin(), mouth.vertices.end(),
                          std::back_inserter(shared));
    if (shared.empty()) continue;
    merged.pairs.insert(merged.pairs.end(), o.pairs.begin(), o.pairs.end());
    merged.vertices.insert(merged.vertices.end(), o.vertices.begin(), o.vertices.end());
  }
  std::sort(merged.pairs.begin(), merged.pairs.end());
  merged.pairs.erase(std::unique(merged.pairs.begin(), merged.pairs.end()), merged.pairs.end());
  std::sort(merged.vertices.begin(), merged.vertices.end());
  merged.vertices.erase(std::unique(merged.vertices.begin(), merged.vertices.end()), merged.vertices.end());
  return merged;
}

// 0..1: how clearly `mouth` opens more than the next mouth opening of its kind elsewhere.
double mouth_clarity(const std::vector<FaceOpening>& openings, const EyesAndMouths& found, const FaceOpening& mouth) {
  double runner_up = 0;
  for (size_t k : found.mouths)
    if (&openings[k] != &mouth && openings[k].kind == found.mouth_kind && openings[k].size > 0 &&
        (openings[k].centre - mouth.centre).norm() > 0.5 * mouth.size)
      runner_up = std::max(runner_up, openings[k].opening);
  return clamp01(runner_up > 0 ? mouth.opening / (2 * runner_up) : 1.0);
}

// Head connectivity for the rim sides.
void connect_head(Face& face, const Head& head) {
  const Triangles& T = head.weld.triangles;
  face.neighbours.assign(static_cast<size_t>(face.rig.neutral.vertex_count()), {});
  for (Eigen::Index t = 0; t < T.rows(); ++t) {
    if (!head.pieces.head[static_cast<size_t>(T(t, 0))]) continue;
    for (int k = 0; k < 3; ++k) {
      const int a = T(t, k), b = T(t, (k + 1) % 3), c = T(t, (k + 2) % 3);
      face.opposite[{a, b}] = c;
      face.neighbours[static_cast<size_t>(a)].push_back(b);
      face.neighbours[static_cast<size_t>(b)].push_back(a);
    }
  }
  for (std::vector<int>& n : face.neighbours) {
    std::sort(n.begin(), n.end());
    n.erase(std::unique(n.begin(), n.end()), n.end());
  }
}

// The head's welded triangles: the profiles (brows, chin) cut them.
Triangles head_triangles_of(const Head& head) {
  const Triangles& T = head.weld.triangles;
  Triangles out(T.rows(), 3);
  Eigen::Index count = 0;
  for (Eigen::Index t = 0; t < T.rows(); ++t)
    if (head.pieces.head[static_cast<size_t>(T(t, 0))]) out.row(count++) = T.row(t);
  out.conservativeResize(count, 3);
  return out;
}

// Confidence of a landmark on the mirror plane: 1 on it, 0 a twentieth of the eye distance off.
double centre_confidence(const Face& face, double eye_d, int v, double clarity) {
  return clamp01(1 - std::abs(face.mirror.side(face.at(v))) / (0.05 * eye_d)) * clarity;
}

// Confidence of a mirrored pair: 1 if `left` mirrors onto `right`, 0 a tenth of the eye distance off.
double pair_confidence(const Face& face, double eye_d, int left, int right, double clarity) {
  return clamp01(1 - (face.mirror.reflect(face.at(left)) - face.at(right)).norm() / (0.1 * eye_d)) * clarity;
}

// Mouth landmarks. Corners from the mouth's own slit (other controllers part the cheeks beyond
// them too); the lips' centres from every slit of the mouth (`line`). Returns the mouth's width
// along the left axis.
double add_mouth_landmarks(const Face& face, const FaceOpening& mouth, const FaceOpening& line, double clarity,
                           double eye_d, LandmarkProposal& out) {
  const std::string how = fmt::format("{} of the mouth, which {} opens by {:.3g} {}",
                                      mouth.kind == FaceOpening::Kind::hole ? "rim" : "slit", out.mouth_controller,
                                      mouth.opening, face.rig.units);
  const Rim mouth_rim = read_rim(face, mouth);
  const Rim line_rim = read_rim(face, line);
  const double width = face.lateral(mouth_rim.corner_left) - face.lateral(mouth_rim.corner_right);
  const std::array<int, 2> lips = rim_at(face, line, line_rim, 0.0, width);
  const double corners = pair_confidence(face, eye_d, mouth_rim.corner_left, mouth_rim.corner_right, clarity);
  out.landmarks["mouth_left"] = {mouth_rim.corner_left, corners, "left end of the " + how};
  out.landmarks["mouth_right"] = {mouth_rim.corner_right, corners, "right end of the " + how};
  if (lips[0] >= 0)
    out.landmarks["lip_upper_center"] = {lips[0], centre_confidence(face, eye_d, lips[0], clarity),
                                         "upper side of the " + how + ", on the mirror plane"};
  if (lips[1] >= 0)
    out.landmarks["lip_lower_center"] = {lips[1], centre_confidence(face, eye_d, lips[1], clarity),
                                         "lower side of the " + how + ", on the mirror plane"};
  return width;
}

// Eye landmarks (corners and lids) and the eyes' rim vertices; `eyes`: the left eye's opening,
// then the right's.
void add_eye_landmarks(const Face& face, const FaceOpening* const eyes[2], double clarity, double eye_d,
                       LandmarkProposal& out) {
  const Rig& rig = face.rig;
  const Rim rims[2] = {read_rim(face, *eyes[0]), read_rim(face, *eyes[1])};
  for (int e = 0; e < 2; ++e) {
    const std::string side = e == 0 ? "left" : "right";
    const Rim& rim = rims[e];
    const FaceOpening& o = *eyes[e];
    const std::string controller = rig.controllers[static_cast<size_t>(o.controller)].name;
    out.eye_controllers.push_back(controller);
    const std::string how =
        fmt::format("{} of the {} eye, which {} {} by {:.3g} {}", o.kind == FaceOpening::Kind::hole ? "rim" : "slit",
                    side, controller, o.kind == FaceOpening::Kind::hole ? "closes" : "opens", o.opening, rig.units);
    // Inner: the corner nearer the mirror plane.
    const int inner = e == 0 ? rim.corner_right : rim.corner_left, outer = e == 0 ? rim.corner_left : rim.corner_right;
    const Rim& other = rims[1 - e];
    const int other_inner = e == 0 ? other.corner_left : other.corner_right;
    const int other_outer = e == 0 ? other.corner_right : other.corner_left;
    out.landmarks["eye_inner_" + side] = {
        inner, pair_confidence(face, eye_d, e == 0 ? inner : other_inner, e == 0 ? other_inner : inner, clarity),
        "inner end of the " + how};
    out.landmarks["eye_outer_" + side] = {
        outer, pair_confidence(face, eye_d, e == 0 ? outer : other_outer, e == 0 ? other_outer : outer, clarity),
        "outer end of the " + how};
    const double middle = 0.5 * (face.lateral(rim.corner_left) + face.lateral(rim.corner_right));
    const double width = face.lateral(rim.corner_left) - face.lateral(rim.corner_right);
    const std::array<int, 2> lids = rim_at(face, o, rim, middle, width);
    const double lid_confidence = 0.8 * clarity;
    if (lids[0] >= 0)
      out.landmarks["eyelid_upper_" + side] = {lids[0], lid_confidence, "upper side of the " + how + ", midway"};
    if (lids[1] >= 0)
      out.landmarks["eyelid_lower_" + side] = {lids[1], lid_confidence, "lower side of the " + how + ", midway"};
    (e == 0 ? out.eyes.left : out.eyes.right) = o.vertices;
  }
  std::sort(out.eyes.left.begin(), out.eyes.left.end());
  std::sort(out.eyes.right.begin(), out.eyes.right.end());
}

// Nose tip: the frontmost head vertex near the plane between the mouth and the eyes.
void add_nose_tip(const Face& face, const std::vector<int>& head, const Vector3d& mouth_centre, const Vector3d& eye_mid,
                  double eye_d, LandmarkProposal& out) {
  const Vector3d& forward = face.frame.forward;
  const double lo = face.frame.up.dot(mouth_centre), hi = face.frame.up.dot(eye_mid);
  int tip = -1;
  double front = -std::numeric_limits<double>::infinity();
  for (int v : head) {
    const double h = face.frame.up.dot(face.at(v));
    if (h < lo + 0.05 * (hi - lo) || h > lo + 0.7 * (hi - lo)) continue;
    if (std::abs(face.mirror.side(face.at(v))) > 0.08 * eye_d) continue;
    if (forward.dot(face.at(v)) > front) {
      front = forward.dot(face.at(v));
      tip = v;
    }
  }
  if (tip >= 0)
    out.landmarks["nose_tip"] = {tip, 0.5 * centre_confidence(face, eye_d, tip, 1.0),
                                 "frontmost point near the mirror plane between the mouth and the eyes"};
}

// Brows: above each eye, the controllers that move that region (a brow raiser, a brow lowerer)
// while leaving the eye's rim (the lids) mostly still. The brow's middle is the crest of the
// brow ridge (where the cut through it, parallel to the mirror plane, bends most sharply
// outwards) above where they lift the brow most; its inner and outer ends are the extremes along
// the left axis of what they lift by at least a quarter of that, at about the middle's height.
void add_brow_landmarks(const Face& face, const std::vector<int>& head, const Triangles& head_triangles,
                        const Vector3d eye_centres[2], double eye_d, LandmarkProposal& out) {
  const BrowRegion brow_regions[2] = {brow_region(face, head, out.eyes.left, eye_centres[0], eye_d),
                                      brow_region(face, head, out.eyes.right, eye_centres[1], eye_d)};
  for (int e = 0; e < 2; ++e) {
    const std::string side = e == 0 ? "left" : "right";
    const BrowReading brow = read_brow(face, head_triangles, brow_regions[e], brow_regions[1 - e], eye_d);
    if (brow.middle < 0) continue;
    std::string movers;
    for (int c : brow.controllers)
      movers += (movers.empty() ? "" : " and ") + face.rig.controllers[static_cast<size_t>(c)].name;
    const std::string how = "the brow above the " + side + " eye, as " + movers + " move it";
    out.landmarks["brow_inner_" + side] = {brow.inner, 0.4, "inner end of " + how};
    out.landmarks["brow_middle_" + side] = {brow.middle, 0.5, "crest of " + how + ", where they lift it most"};
    out.landmarks["brow_outer_" + side] = {brow.outer, 0.4, "outer end of " + how};
  }
}

// The chin on the mirror plane's profile below the lower lip `lip` (-1 if none; `how` says which
// kind it found).
int chin_on_profile(const Face& face, const Triangles& head_triangles, int lip, double eye_d, std::string& how) {
  const Vector3d& forward = face.frame.forward;
  // First down the lip's front (towards the front and below), not into the mouth.
  const std::vector<ProfilePoint> profile =
      walk_profile(face.V, head_triangles, face.mirror, lip, forward - face.frame.up, 2 * eye_d);
  const auto height = [&](size_t i) { return face.frame.up.dot(profile[i].position); };
  const auto reach = [&](size_t i) { return forward.dot(profile[i].position) - height(i); };
  size_t n = 0;  // the points at most an eye distance below the lip
  while (n < profile.size() && height(0) - height(n) <= eye_d) ++n;
  size_t best = 0;
  for (size_t i = 1; i < n; ++i)
    if (reach(i) > reach(best)) best = i;
  if (best > 0 && best + 1 < n) {
    how = "the chin's furthest point towards the front and below, on the mirror plane (gnathion)";
    return profile[best].vertex;
  }
  int chin = -1;
  for (size_t i = 1; i + 1 < n; ++i) {
    if (height(i + 1) <= height(i) + 1e-6 * eye_d) continue;
    if (height(i) < height(0)) chin = profile[i].vertex;
    how = "the receding jaw's lowest point on the mirror plane, before the throat (menton)";
    break;
  }
  return chin;
}

// Chin: on the mirror plane's profile below the lower lip, where the jaw turns under: the
// furthest point towards the front and below (the gnathion, where the surface faces forward and
// down alike), when the chin reaches further that way than the lower lip; a receding chin (a
// snout's jaw, facing more down than forward from the lip on) has no such point, and its chin is
// the jaw's lowest point before the profile rises towards the throat (the menton).
void add_chin(const Face& face, const std::vector<int>& head, const Triangles& head_triangles,
              const Vector3d& mouth_centre, double eye_d, LandmarkProposal& out) {
  int chin = -1;
  std::string how;
  const auto lower = out.landmarks.find("lip_lower_center");
  if (lower != out.landmarks.end()) chin = chin_on_profile(face, head_triangles, lower->second.vertex, eye_d, how);
  if (chin < 0) {  // no lower lip or no profile: the head's extreme point to the front and below
    const double mouth_height = face.frame.up.dot(mouth_centre);  // at most an eye distance below it
    const Vector3d direction = (face.frame.forward - face.frame.up).normalized();
    double reach = -std::numeric_limits<double>::infinity();
    for (int v : head) {
      const double below = mouth_height - face.frame.up.dot(face.at(v));
      if (below < 0.1 * eye_d || below > eye_d) continue;  // not the neck or a bust's front
      if (std::abs(face.mirror.side(face.at(v))) > 0.08 * eye_d) continue;
      if (direction.dot(face.at(v)) > reach) {
        reach = direction.dot(face.at(v));
        chin = v;
      }
    }
    how = "the head's extreme point towards the front and below, under the mouth";
  }
  if (chin >= 0) out.landmarks["chin"] = {chin, 0.5 * centre_confidence(face, eye_d, chin, 1.0), how};
}

// A part's sphere fit: relative residual (1e9: too few vertices to fit), radius and coverage.
struct ProposedSphere {
  double residual = 1e9;
  double radius = 0;
  double coverage = 0;  // the part's area over the sphere's
};

// The area of the triangles of the neutral whose vertices are all in `piece`.
double surface_area(const Face& face, const std::vector<int>& piece) {
  std::vector<char> in(static_cast<size_t>(face.V.rows()), 0);
  for (int v : piece) in[static_cast<size_t>(v)] = 1;
  const Triangles& T = face.rig.neutral.triangles;
  double area = 0;
  for (Eigen::Index t = 0; t < T.rows(); ++t)
    if (in[static_cast<size_t>(T(t, 0))] && in[static_cast<size_t>(T(t, 1))] && in[static_cast<size_t>(T(t, 2))])
      area += 0.5 * (face.at(T(t, 1)) - face.at(T(t, 0))).cross(face.at(T(t, 2)) - face.at(T(t, 0))).norm();
  return area;
}

// Eyeballs: of the parts whose centre lies near an eye and that are balls of their own (a sphere
// smaller than half the eye distance, covered over at least 15% of its area, as a cap of 45
// degrees is; a strip lying on the head, a brow or a lash line, covers ~1% of any sphere it
// fits, a flat iris ~8%), the most spherical.
void mark_eyeballs(const Vector3d eye_centres[2], const std::vector<ProposedSphere>& spheres, double eye_d,
                   std::vector<ProposedPart>& parts) {
  for (int e = 0; e < 2; ++e) {
    int best = -1;
    for (size_t p = 0; p < parts.size(); ++p) {
      const ProposedSphere& s = spheres[p];
      if (parts[p].kind != ProposedPart::Kind::other || s.residual >= 1e9) continue;
      if ((parts[p].centre - eye_centres[e]).norm() > 0.35 * eye_d) continue;
      if (s.radius > 0.5 * eye_d || s.coverage < 0.15) continue;
      if (best < 0 || s.residual < spheres[static_cast<size_t>(best)].residual) best = static_cast<int>(p);
    }
    if (best >= 0) {
      parts[static_cast<size_t>(best)].kind = ProposedPart::Kind::eye;
      parts[static_cast<size_t>(best)].name = e == 0 ? "eye_left" : "eye_right";
    }
  }
}

// Parts within `mouth_reach` of the mouth: teeth (a mirrored pair), else pieces inside the mouth.
void mark_mouth_parts(const Face& face, const Vector3d& mouth_centre, double mouth_reach, double eye_d,
                      std::vector<ProposedPart>& parts) {
  int mouth_parts = 0;
  for (size_t p = 0; p < parts.size(); ++p) {
    if (parts[p].kind != ProposedPart::Kind::other) continue;
    if ((parts[p].centre - mouth_centre).norm() > mouth_reach) continue;
    // A mirrored twin near the mouth: teeth.
    for (size_t q = 0; q < parts.size(); ++q) {
      if (q == p || parts[q].kind != ProposedPart::Kind::other) continue;
      if (std::abs(face.mirror.side(parts[p].centre)) < 0.02 * eye_d) continue;
      if ((face.mirror.reflect(parts[p].centre) - parts[q].centre).norm() > 0.03 * eye_d) continue;
      if (parts[p].vertices.size() != parts[q].vertices.size()) continue;
      const bool p_left = face.lateral(parts[p].vertices.front()) > 0;
      parts[p].kind = parts[q].kind = ProposedPart::Kind::teeth;
      parts[p].name = p_left ? "teeth_left" : "teeth_right";
      parts[q].name = p_left ? "teeth_right" : "teeth_left";
      break;
    }
    if (parts[p].kind == ProposedPart::Kind::other) {
      parts[p].kind = ProposedPart::Kind::mouth;
      parts[p].name = "mouth_" + std::to_string(++mouth_parts);
    }
  }
}

// Parts: eyeballs, teeth, pieces inside the mouth, others.
std::vector<ProposedPart> propose_parts(const Face& face, const std::vector<std::vector<int>>& pieces,
                                        const Vector3d eye_centres[2], const Vector3d& mouth_centre, double mouth_reach,
                                        double eye_d) {
  std::vector<ProposedPart> parts;
  std::vector<ProposedSphere> spheres;
  for (const std::vector<int>& piece : pieces) {
    ProposedPart part;
    part.vertices = piece;
    for (int v : piece) part.centre += face.at(v);
    part.centre /= static_cast<double>(piece.size());
    ProposedSphere sphere;
    Vector3d centre;
    sphere.residual = piece.size() >= 8 ? sphere_fit_residual(face.V, piece, centre, sphere.radius) : 1e9;
    sphere.coverage = sphere.radius > 0 ? surface_area(face, piece) / (4 * M_PI * sphere.radius * sphere.radius) : 0;
    spheres.push_back(sphere);
    parts.push_back(std::move(part));
  }
  mark_eyeballs(eye_centres, spheres, eye_d, parts);
  mark_mouth_parts(face, mouth_centre, mouth_reach, eye_d, parts);
  int other_parts = 0;
  for (ProposedPart& part : parts)
    if (part.name.empty()) part.name = "part_" + std::to_string(++other_parts);
  return parts;
}

void add_notes(const Rig& rig, const FaceOpening& mouth, bool eye_holes, LandmarkProposal& out) {
  const MirrorPlane& mirror = out.mirror;
  out.notes.push_back(
      fmt::format("mirror plane: normal ({:.3f}, {:.3f}, {:.3f}), mirrored points within {:.2f}% of the head's size",
                  mirror.normal.x(), mirror.normal.y(), mirror.normal.z(), 100 * mirror.error));
  out.notes.push_back(fmt::format("mouth: {} ({} vertices), opened by {}",
                                  mouth.kind == FaceOpening::Kind::hole ? "a hole" : "a slit", mouth.vertices.size(),
                                  out.mouth_controller));
  out.notes.push_back(fmt::format("eyes: {} (left {} vertices, right {}), by {} and {}; eye centres {:.4g} {} apart",
                                  eye_holes ? "holes" : "slits", out.eyes.left.size(), out.eyes.right.size(),
                                  out.eye_controllers[0], out.eye_controllers[1], out.eye_distance, rig.units));
  if (out.welded > 0)
    out.notes.push_back(
        fmt::format("{} vertices coincide with another and move with it: welded for the analysis only", out.welded));
  const std::vector<std::string> still = rig.still_controllers();
  if (!still.empty())
    out.notes.push_back(
        fmt::format("{} of {} controllers move no vertex (target = neutral), so nothing was read from "
                    "them: {}; give them their shapes, or remove them if they are placeholders",
                    still.size(), rig.controller_count(), fmt::join(still, ", ")));
}

}  // namespace proposal_detail

LandmarkProposal propose_landmarks(const Rig& rig, const LandmarkProposalOptions& options) {
  using namespace proposal_detail;
  options.validate();
  const std::string where = where_of(rig);
  check_rig(rig, where);

  LandmarkProposal out;
  const Head head = read_head(rig, options, where);
  out.welded = head.weld.merged;
  out.mirror = read_mirror(head, options, where);
  const MirrorPlane& mirror = out.mirror;
  const std::vector<FaceOpening> openings = find_face_openings(rig, head.weld, head.pieces.head, options.openings);

  const EyeCandidates candidates = eye_candidates(openings, mirror, head.diagonal, where);
  const EyesAndMouths found = choose_eyes(openings, mirror, candidates.pairs, where);
  const FaceOpening *eye_a = &openings[static_cast<size_t>(found.eyes.left)],
                    *eye_b = &openings[static_cast<size_t>(found.eyes.right)];
  const Vector3d eye_mid = 0.5 * (eye_a->centre + eye_b->centre);
  out.eye_distance = (eye_a->centre - eye_b->centre).norm();
  const double eye_d = out.eye_distance;

  const Vector3d head_centre = head.points.colwise().mean().transpose();
  Face face{rig, rig.neutral.vertices, mirror, face_frame(mirror, eye_mid, found.first_mouth->centre, head_centre), {},
            {}};
  out.frame = face.frame;
  const FaceOpening* mouth = choose_mouth(openings, found, face.frame.forward, head.diagonal, eye_d);
  const FaceOpening merged_mouth =
      mouth->kind == FaceOpening::Kind::slit ? merged_slit(openings, *mouth) : FaceOpening{};
  const double clarity = mouth_clarity(openings, found, *mouth);
  out.mouth_controller = rig.controllers[static_cast<size_t>(mouth->controller)].name;
  connect_head(face, head);

  const FaceOpening& mouth_line = mouth->kind == FaceOpening::Kind::slit ? merged_mouth : *mouth;
  const double mouth_width = add_mouth_landmarks(face, *mouth, mouth_line, clarity, eye_d, out);
  // The opening on the left side is the left eye.
  if (face.lateral(eye_a->vertices.front()) < face.lateral(eye_b->vertices.front())) std::swap(eye_a, eye_b);
  const FaceOpening* const eyes[2] = {eye_a, eye_b};
  const Vector3d eye_centres[2] = {eye_a->centre, eye_b->centre};  // the rims' centroids: left, right
  const double eye_clarity = clamp01(found.eyes.hole || candidates.best_hole_score <= 0 ? 1.0 : 0.75);
  add_eye_landmarks(face, eyes, eye_clarity, eye_d, out);
  add_nose_tip(face, head.vertices, mouth->centre, eye_mid, eye_d, out);
  const Triangles head_triangles = head_triangles_of(head);
  add_brow_landmarks(face, head.vertices, head_triangles, eye_centres, eye_d, out);
  add_chin(face, head.vertices, head_triangles, mouth->centre, eye_d, out);

  const double mouth_reach = std::max(mouth_width, 0.3 * eye_d);
  out.parts = propose_parts(face, head.pieces.parts, eye_centres, mouth->centre, mouth_reach, eye_d);
  add_notes(rig, *mouth, found.eyes.hole, out);
  return out;
}

}  // namespace retarget
