#include "correspond/controller_meaning.h"

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <chrono>
#include <cmath>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <tuple>

#include "core/atomic_file.h"
#include "core/error.h"
#include "geometry/closest_point.h"
#include "geometry/rig_parts.h"
#include "geometry/rig_weight_fit.h"

namespace retarget {

namespace meaning_detail {

std::string joined_names(const std::vector<std::string>& names) {
  std::string text;
  for (const std::string& name : names) text += (text.empty() ? "" : ", ") + name;
  return text.empty() ? "none" : text;
}

std::string where_of(const Rig& rig) { return rig.source.empty() ? "rig " + rig.name : rig.source; }
std::string where_of(const FaceModel& face) { return face.source.empty() ? "face model " + face.name : face.source; }

// A controller offset restricted to `moving` vertices, or zero elsewhere: the pseudo-rigs below
// fit only where the avatar's rig moves.
Positions restricted(const Positions& offset, const std::vector<int>& moving) {
  Positions out = Positions::Zero(offset.rows(), 3);
  for (int v : moving) out.row(v) = offset.row(v);
  return out;
}

double squared_norm_over(const Positions& offset, const std::vector<int>& moving) {
  double sum = 0;
  for (int v : moving) sum += offset.row(v).squaredNorm();
  return sum;
}

// A non-negative (or bounded) combination of `shapes` (#V x 3 offsets each) fitted to a target
// (#V x 3 offset on the avatar) over `moving` vertices by the bounded rig fit, on a rig whose
// controllers are the shapes.
struct ShapeFit {
  Eigen::VectorXd weights;       // one per shape, within its range
  Eigen::VectorXd contribution;  // weight_k <shape_k, target> / |target|^2: sums to `explained`
  double explained = 0;          // 1 - |residual|^2 / |target|^2, in [0, 1]
};

// The fit above, prefactored once for `shapes` (kept by pointer: they must outlive it) and asked
// for many targets.
class ShapeFitter {
 public:
  ShapeFitter(const Mesh& neutral, std::vector<const Positions*> shapes,
              const std::vector<std::pair<double, double>>& ranges, std::vector<int> moving)
      : shapes_(std::move(shapes)), moving_(std::move(moving)), pseudo_(std::make_unique<Rig>()) {
    pseudo_->name = "human transfers";
    pseudo_->neutral = neutral;
    for (size_t k = 0; k < shapes_.size(); ++k) {
      Controller c;
      c.name = fmt::format("shape{}", k);
      c.offset = restricted(*shapes_[k], moving_);
      c.min = ranges[k].first;
      c.max = ranges[k].second;
      pseudo_->controllers.push_back(std::move(c));
    }
    RigWeightFitOptions fit_options;
    fit_options.sweeps = 5000;
    fit_options.tolerance = 1e-10;
    if (!shapes_.empty()) fit_ = std::make_unique<RigWeightFit>(*pseudo_, fit_options);
  }

  ShapeFit fit(const Positions& target) const {
    ShapeFit out;
    const int k_count = static_cast<int>(shapes_.size());
    out.weights = Eigen::VectorXd::Zero(k_count);
    out.contribution = Eigen::VectorXd::Zero(k_count);
    const double total = squared_norm_over(target, moving_);
    if (total <= 0 || !fit_) return out;
    out.weights = fit_->fit(pseudo_->neutral.vertices + restricted(target, moving_));
    double residual = 0;
    for (int v : moving_) {
      Eigen::RowVector3d r = target.row(v);
      for (int k = 0; k < k_count; ++k) r -= out.weights(k) * shapes_[k]->row(v);
      residual += r.squaredNorm();
    }
    for (int k = 0; k < k_count; ++k) {
      double dot = 0;
      for (int v : moving_) dot += shapes_[k]->row(v).dot(target.row(v));
      out.contribution(k) = out.weights(k) * dot / total;
    }
    out.explained = std::clamp(1.0 - residual / total, 0.0, 1.0);
    return out;
  }

 private:
  std::vector<const Positions*> shapes_;
  std::vector<int> moving_;
  std::unique_ptr<Rig> pseudo_;  // RigWeightFit keeps a reference: it must not move
  std::unique_ptr<RigWeightFit> fit_;
};

// The name of the other side's shape: a _L/_R/Left/Right/left/right suffix swapped
// (mouthSmile_L <-> mouthSmile_R, eyeBlinkLeft <-> eyeBlinkRight); other names stay.
std::string mirror_name(const std::string& name) {
  static const std::vector<std::pair<std::string, std::string>> swaps = {
      {"_L", "_R"}, {"_l", "_r"}, {"Left", "Right"}, {"left", "right"}, {".L", ".R"}, {".l", ".r"}};
  for (const auto& [a, b] : swaps) {
    for (int turn = 0; turn < 2; ++turn) {
      const std::string& from = turn ? b : a;
      const std::string& to = turn ? a : b;
      if (name.size() > from.size() && name.compare(name.size() - from.size(), from.size(), from) == 0)
        return name.substr(0, name.size() - from.size()) + to;
    }
  }
  return name;
}

// The avatar's own mirror symmetry, read off its landmarks: the plane that swaps each
// `<name>_left` with its `<name>_right` (normal: the mean of left - right; through the pairs'
// midpoints), and each vertex's mirror image (the vertex nearest its reflection, within a tenth
// of the pairs' mean left-right distance; -1 if none is). Empty `partner` when the rig names no
// such pair.
struct AvatarMirror {
  Eigen::Matrix3d reflection = Eigen::Matrix3d::Identity();  // of directions: I - 2 n n^T
  std::vector<int> partner;                                  // per rig vertex
};

AvatarMirror avatar_mirror(const Rig& rig) {
  AvatarMirror out;
  const Positions& V = rig.neutral.vertices;
  Eigen::Vector3d across = Eigen::Vector3d::Zero(), middle = Eigen::Vector3d::Zero();
  double spread = 0;
  int pairs = 0;
  const std::string suffix = "_left";
  for (const auto& [name, left] : rig.landmarks) {
    if (name.size() <= suffix.size() || name.compare(name.size() - suffix.size(), suffix.size(), suffix) != 0) continue;
    const auto right = rig.landmarks.find(name.substr(0, name.size() - suffix.size()) + "_right");
    if (right == rig.landmarks.end()) continue;
    const Eigen::Vector3d a = V.row(left).transpose(), b = V.row(right->second).transpose();
    across += a - b;
    middle += 0.5 * (a + b);
    spread += (a - b).norm();
    ++pairs;
  }
  if (pairs == 0 || !(across.norm() > 0)) return out;
  const Eigen::Vector3d n = across.normalized();
  middle /= pairs;
  spread /= pairs;
  out.reflection = Eigen::Matrix3d::Identity() - 2 * n * n.transpose();
  const NearestPoints nearest(V);
  out.partner.assign(static_cast<size_t>(V.rows()), -1);
  for (Eigen::Index v = 0; v < V.rows(); ++v) {
    const Eigen::Vector3d x = V.row(v).transpose();
    out.partner[static_cast<size_t>(v)] = nearest.nearest(
        x - 2 * n.dot(x - middle) * n, [](int) { return true; }, 0.1 * spread);
  }
  return out;
}

// How alike controller offset `b` is to the mirror image of offset `a`, as a cosine over the
// vertices `over` that have a mirror image: 1 for a left blink and the right one.
double mirror_likeness(const AvatarMirror& mirror, const Positions& a, const Positions& b,
                       const std::vector<int>& over) {
  double dot = 0, aa = 0, bb = 0;
  for (int v : over) {
    const int w = mirror.partner[static_cast<size_t>(v)];
    if (w < 0) continue;
    const Eigen::Vector3d reflected = mirror.reflection * a.row(v).transpose();
    const Eigen::Vector3d other = b.row(w).transpose();
    dot += reflected.dot(other);
    aa += reflected.squaredNorm();
    bb += other.squaredNorm();
  }
  return aa > 0 && bb > 0 ? dot / std::sqrt(aa * bb) : 0.0;
}

// What a face does at its landmarks, measured on the face itself (not through deformation
// transfer), in its own proportions: per eye, its upper and lower lid's motion upwards over the
// eye's width; per brow point, likewise; the lips' centres' motion upwards and each mouth corner's
// upwards and outwards, over the mouth's width. The features are those both the human and the
// avatar can measure: a lid point is `eyelid_upper_<side>` or else the mean of
// `eyelid_upper_inner_<side>` and `eyelid_upper_outer_<side>` (the 68-point sets'), and so on.
struct LandmarkFeatures {
  struct Point {
    std::vector<int> vertices;  // averaged
    Eigen::Vector3d direction;  // unit, the face's up or a corner's outwards
    double scale = 1;           // the eye's or the mouth's width
  };
  std::vector<std::string> names;
  std::vector<Point> points;  // one per name
  // The features of an offset (#V x 3): one per point.
  Eigen::VectorXd of(const Positions& offset) const {
    Eigen::VectorXd out(static_cast<Eigen::Index>(points.size()));
    for (size_t i = 0; i < points.size(); ++i) {
      Eigen::Vector3d d = Eigen::Vector3d::Zero();
      for (int v : points[i].vertices) d += offset.row(v).transpose();
      d /= static_cast<double>(points[i].vertices.size());
      out(static_cast<Eigen::Index>(i)) = d.dot(points[i].direction) / points[i].scale;
    }
    return out;
  }
};

// The vertices a face names `name` by (see LandmarkFeatures); empty if it names none.
std::vector<int> landmark_vertices(const std::map<std::string, int>& landmarks, const std::string& name) {
  const auto it = landmarks.find(name);
  if (it != landmarks.end()) return {it->second};
  const size_t side = name.rfind('_');
  if (name.rfind("eyelid_", 0) != 0 || side == std::string::npos) return {};
  const auto inner = landmarks.find(name.substr(0, side) + "_inner" + name.substr(side));
  const auto outer = landmarks.find(name.substr(0, side) + "_outer" + name.substr(side));
  if (inner == landmarks.end() || outer == landmarks.end()) return {};
  return {inner->second, outer->second};
}

// The features `a` and `b` (human, avatar) can both measure, each on its own face; empty when
// either lacks the eyes' and mouth's corners (no up, no scale).
std::array<LandmarkFeatures, 2> shared_landmark_features(const std::map<std::string, int>& a, const Positions& va,
                                                         const std::map<std::string, int>& b, const Positions& vb) {
  std::array<LandmarkFeatures, 2> out;
  const std::map<std::string, int>* marks[2] = {&a, &b};
  const Positions* positions[2] = {&va, &vb};
  struct Frame {
    Eigen::Vector3d up, left;
    double eye[2] = {0, 0}, mouth = 0;
    double lids[2] = {0, 0};  // the eye's opening at rest, upper to lower lid (0: unknown)
  } frame[2];
  for (int f = 0; f < 2; ++f) {
    const auto at = [&](const std::string& name) { return Eigen::Vector3d(positions[f]->row(marks[f]->at(name))); };
    for (const char* name :
         {"eye_inner_left", "eye_outer_left", "eye_inner_right", "eye_outer_right", "mouth_left", "mouth_right"})
      if (!marks[f]->count(name)) return {};
    const Eigen::Vector3d eyes =
        0.25 * (at("eye_inner_left") + at("eye_outer_left") + at("eye_inner_right") + at("eye_outer_right"));
    const Eigen::Vector3d mouth = 0.5 * (at("mouth_left") + at("mouth_right"));
    frame[f].left = (at("eye_outer_left") + at("eye_inner_left") - at("eye_outer_right") - at("eye_inner_right") +
                     at("mouth_left") - at("mouth_right"))
                        .normalized();
    frame[f].up = (eyes - mouth - (eyes - mouth).dot(frame[f].left) * frame[f].left).normalized();
    frame[f].eye[0] = (at("eye_outer_left") - at("eye_inner_left")).norm();
    frame[f].eye[1] = (at("eye_outer_right") - at("eye_inner_right")).norm();
    frame[f].mouth = (at("mouth_left") - at("mouth_right")).norm();
    for (int side = 0; side < 2; ++side) {
      const std::string s = side == 0 ? "left" : "right";
      const std::vector<int> upper = landmark_vertices(*marks[f], "eyelid_upper_" + s);
      const std::vector<int> lower = landmark_vertices(*marks[f], "eyelid_lower_" + s);
      if (upper.empty() || lower.empty()) continue;
      Eigen::Vector3d gap = Eigen::Vector3d::Zero();
      for (int v : upper) gap += positions[f]->row(v).transpose() / static_cast<double>(upper.size());
      for (int v : lower) gap -= positions[f]->row(v).transpose() / static_cast<double>(lower.size());
      frame[f].lids[side] = std::abs(gap.dot(frame[f].up));
    }
    if (!(frame[f].eye[0] > 0 && frame[f].eye[1] > 0 && frame[f].mouth > 0 && frame[f].up.allFinite())) return {};
  }
  const auto add = [&](const std::string& name, int kind, int side) {  // kind 0: up, 1: outwards
    std::vector<int> vertices[2];
    for (int f = 0; f < 2; ++f) {
      vertices[f] = landmark_vertices(*marks[f], name);
      if (vertices[f].empty()) return;
    }
    for (int f = 0; f < 2; ++f) {
      LandmarkFeatures::Point p;
      p.vertices = vertices[f];
      p.direction = kind == 0 ? frame[f].up : (side == 0 ? 1.0 : -1.0) * frame[f].left;
      p.scale = name.rfind("mouth_", 0) == 0 || name.rfind("lip_", 0) == 0 ? frame[f].mouth : frame[f].eye[side];
      if (name.rfind("eyelid_", 0) == 0 && frame[f].lids[side] > 0.1 * frame[f].eye[side])
        p.scale = frame[f].lids[side];
      out[static_cast<size_t>(f)].names.push_back(name + (kind == 0 ? " up" : " outwards"));
      out[static_cast<size_t>(f)].points.push_back(std::move(p));
    }
  };
  for (int side = 0; side < 2; ++side) {
    const std::string s = side == 0 ? "left" : "right";
    for (const char* point : {"eyelid_upper_", "eyelid_lower_", "brow_inner_", "brow_middle_", "brow_outer_"})
      add(point + s, 0, side);
    add("mouth_" + s, 0, side);
    add("mouth_" + s, 1, side);
  }
  add("lip_upper_center", 0, 0);
  add("lip_lower_center", 0, 0);
  return out;
}

// `value` rounded to 3 significant digits.
double three_digits(double value) {
  if (value == 0 || !std::isfinite(value)) return value;
  const double scale = std::pow(10.0, 2 - std::floor(std::log10(std::abs(value))));
  return std::round(value * scale) / scale;
}

std::string weight_text(double w) { return fmt::format("{:.3g}", w); }

// A YAML scalar as the emitter would write it (quoted only when needed).
std::string yaml_scalar(const std::string& text) {
  YAML::Emitter out;
  out << text;
  return out.c_str();
}

}  // namespace meaning_detail

std::string name_side(const std::string& name) {
  const std::vector<std::string> words = name_words(name);  // geometry/rig_parts.h
  std::string side;
  for (size_t i = 0; i < words.size(); ++i) {
    const std::string& w = words[i];
    const bool edge = i == 0 || i + 1 == words.size();
    std::string found;
    if (w == "left" || (edge && w == "l" && words.size() > 1)) found = "left";
    if (w == "right" || (edge && w == "r" && words.size() > 1)) found = "right";
    if (!found.empty()) side = side.empty() || side == found ? found : "both";
  }
  return side == "both" ? "" : side;
}

std::string meaning_name_key(const std::string& name) {
  std::string key;
  for (char ch : name) {
    const unsigned char c = static_cast<unsigned char>(ch);
    if (c == '_' || c == '-' || c == '.' || c == ' ') continue;
    key.push_back(static_cast<char>(std::tolower(c)));
  }
  auto ends_with = [&](const std::string& suffix) {
    return key.size() > suffix.size() && key.compare(key.size() - suffix.size(), suffix.size(), suffix) == 0;
  };
  if (ends_with("left")) key = key.substr(0, key.size() - 4) + "l";
  if (ends_with("right")) key = key.substr(0, key.size() - 5) + "r";
  return key;
}

void ControllerMeaningOptions::validate() const {
  auto fail = [](const std::string& field, const std::string& what) {
    throw Error("controller_meaning." + field, what);
  };
  if (!std::isfinite(ridge) || ridge < 0) fail("ridge", fmt::format("expected a finite number >= 0, got {}", ridge));
  if (!(min_share > 0 && min_share < 1))
    fail("min_share", fmt::format("expected a share in (0, 1), got {}", min_share));
  if (!(relative_keep > 0 && relative_keep <= 1))
    fail("relative_keep", fmt::format("expected a share in (0, 1], got {}", relative_keep));
  if (max_shapes < 1) fail("max_shapes", fmt::format("expected at least 1, got {}", max_shapes));
  if (!(min_confidence >= 0 && min_confidence < 1))
    fail("min_confidence", fmt::format("expected a share in [0, 1), got {}", min_confidence));
  if (!std::isfinite(max_human_weight) || max_human_weight <= 0)
    fail("max_human_weight", fmt::format("expected a finite number above 0, got {}", max_human_weight));
  if (!(reach_floor >= 0 && reach_floor < 1))
    fail("reach_floor", fmt::format("expected a share in [0, 1), got {}", reach_floor));
  if (!(min_coverage >= 0 && min_coverage < 1))
    fail("min_coverage", fmt::format("expected a share in [0, 1), got {}", min_coverage));
  if (!(landmark_weight >= 0 && std::isfinite(landmark_weight)))
    fail("landmark_weight", fmt::format("expected a finite weight >= 0, got {}", landmark_weight));
  if (!(mirror_likeness > 0 && mirror_likeness <= 1))
    fail("mirror_likeness", fmt::format("expected a cosine in (0, 1], got {}", mirror_likeness));
  transfer.validate();
}

const ControllerMeaningRow& ControllerMeaning::row(const std::string& controller) const {
  for (const ControllerMeaningRow& r : rows)
    if (r.controller == controller) return r;
  throw Error("controller meaning", "no controller \"" + controller + "\"");
}

namespace meaning_detail {

// Rows for the placeholders (they stand for nothing) and for the controllers named like a human
// shape; returns the controllers left to match by geometry.
std::vector<int> rows_by_name(const Rig& rig, const FaceModel& face, const ControllerMeaningOptions& options,
                              ControllerMeaning& result) {
  const int C = rig.controller_count();
  std::map<std::string, std::string> shape_by_key;
  for (const Blendshape& b : face.expressions) shape_by_key.emplace(meaning_name_key(b.name), b.name);
  const std::vector<std::string> still = rig.still_controllers();
  if (static_cast<int>(still.size()) == C)
    throw Error(where_of(rig), fmt::format("none of the rig's {} controllers moves a vertex (every target equals the "
                                           "neutral, or every range is only 0): there is no expression to give a "
                                           "meaning to; is this the right mesh or rig.yaml?",
                                           C));
  std::vector<int> by_geometry;
  for (int c = 0; c < C; ++c) {
    ControllerMeaningRow& row = result.rows[c];
    row.controller = rig.controllers[c].name;
    // A placeholder (a target equal to the neutral, or a range of only 0) stands for nothing.
    if (std::find(still.begin(), still.end(), row.controller) != still.end()) {
      row.method = "none";
      row.note =
          "moves no vertex (its target equals the neutral): a placeholder, left {}; give it a target to have "
          "it matched";
      result.table[row.controller] = {};
      continue;
    }
    const auto named = options.match_names ? shape_by_key.find(meaning_name_key(row.controller)) : shape_by_key.end();
    if (named != shape_by_key.end()) {
      row.method = "name";
      row.confidence = row.explained_by_all = row.coverage = 1;
      row.main_shape = named->second;
      row.candidates.push_back({named->second, 1.0, 0.0, 1.0, 1.0, true});
      result.table[row.controller] = {{named->second, 1.0}};
    } else {
      by_geometry.push_back(c);
    }
  }
  return by_geometry;
}

// Landmark pairs by the names both meshes share (human = source, avatar = target); at least 3.
std::vector<LandmarkPair> shared_landmark_pairs(const Rig& rig, const FaceModel& face,
                                                const std::vector<int>& by_geometry, ControllerMeaning& result) {
  std::vector<LandmarkPair> pairs;
  for (const auto& [name, vertex] : face.landmarks) {
    const auto it = rig.landmarks.find(name);
    if (it == rig.landmarks.end()) continue;
    pairs.push_back({vertex, it->second});
    result.landmarks.push_back(name);
  }
  if (pairs.size() < 3) {
    std::vector<std::string> rig_names, face_names;
    for (const auto& entry : rig.landmarks) rig_names.push_back(entry.first);
    for (const auto& entry : face.landmarks) face_names.push_back(entry.first);
    throw Error(
        where_of(rig),
        fmt::format("the rig and the face model {} share {} landmark name{} ({}); deformation transfer needs "
                    "at least 3 to carry the human shapes onto the avatar (needed for {} controller{} not "
                    "named like a human shape, e.g. \"{}\"); rig landmarks: [{}]; face model landmarks: "
                    "[{}]; name at least 3 of the same points in both (rig.yaml `landmarks:`)",
                    where_of(face), pairs.size(), pairs.size() == 1 ? "" : "s", joined_names(result.landmarks),
                    by_geometry.size(), by_geometry.size() == 1 ? "" : "s", rig.controllers[by_geometry.front()].name,
                    joined_names(rig_names), joined_names(face_names)));
  }
  return pairs;
}

// Every human shape at weight 1 on the mean face, carried onto the avatar; offsets against the
// transfer of the neutral itself, so that whatever the transfer does to an unmoved face cancels.
// E offsets, #V(avatar) x 3 each.
std::vector<Positions> transferred_shapes(const Rig& rig, const FaceModel& face, const std::vector<LandmarkPair>& pairs,
                                          const ControllerMeaningOptions& options, ControllerMeaning& result) {
  const int E = static_cast<int>(face.expressions.size());
  const DeformationTransfer transfer(face.neutral, rig.neutral, pairs, options.transfer);
  result.transferred = true;
  result.transfer = transfer.report();
  std::vector<Positions> sources;
  sources.reserve(E + 1);
  sources.push_back(face.neutral.vertices);
  for (const Blendshape& b : face.expressions) sources.push_back(face.neutral.vertices + b.offset);
  std::vector<Positions> moved = transfer.transfer(sources);
  std::vector<Positions> transfers(E);
  for (int h = 0; h < E; ++h) transfers[h] = moved[h + 1] - moved[0];
  return transfers;
}

// What the geometric match works from and what it decides, step by step (G controllers matched
// by geometry, E human shapes).
struct GeometryMatch {
  const Rig& rig;
  const FaceModel& face;
  const ControllerMeaningOptions& options;
  std::vector<int> by_geometry;           // G controller indices
  std::vector<Positions> transfers;       // E human shapes carried onto the avatar (#V x 3 offsets)
  std::vector<int> rig_moving;            // the vertices the rig moves
  Eigen::MatrixXd F;                      // C x E: controller c's weight in the fit of human shape h's transfer
  std::vector<int> moving;                // the vertices the rig moves where a human face moves it too
  Eigen::MatrixXd share;                  // G x E: each human shape's share of each controller's motion
  std::vector<int> mirror_shape;          // E: each shape's mirror image (itself if none)
  std::vector<int> partner;               // G: each controller's mirror partner (itself: symmetric; -1: none)
  Eigen::MatrixXd evidence;               // G x E: the shares, averaged over mirror partners
  std::set<int> claimed;                  // human shapes that are some controller's main shape
  std::vector<int> main;                  // G: each controller's main shape, -1 if none
  std::vector<std::vector<int>> kept_of;  // G: the shapes each controller's row keeps, main first
  std::vector<ShapeFit> chosen_of;        // G: their fit to the controller's motion

  GeometryMatch(const Rig& rig, const FaceModel& face, const ControllerMeaningOptions& options,
                std::vector<int> by_geometry, std::vector<Positions> transfers)
      : rig(rig), face(face), options(options), by_geometry(std::move(by_geometry)), transfers(std::move(transfers)) {}

  int E() const { return static_cast<int>(face.expressions.size()); }
  int G() const { return static_cast<int>(by_geometry.size()); }
  std::pair<double, double> positive() const { return {0.0, options.max_human_weight}; }
  Eigen::VectorXd mirrored(int g) const {  // controller g's shares with the human sides swapped
    Eigen::VectorXd out(E());
    for (int h = 0; h < E(); ++h) out(mirror_shape[h]) = share(g, h);
    return out;
  }
};

// Where a human face can move the avatar at all: the vertices the rig moves that some
// transferred human shape moves by more than `reach_floor` of the largest such motion. A
// controller's motion elsewhere (a rabbit's ears, flicking with its smile) has no human
// counterpart; its share of the motion is the controller's coverage.
void find_human_reach(GeometryMatch& m, ControllerMeaning& result) {
  Eigen::VectorXd reach = Eigen::VectorXd::Zero(m.rig.neutral.vertex_count());
  for (const Positions& t : m.transfers) reach = reach.cwiseMax(t.rowwise().norm());
  double reach_max = 0;
  for (int v : m.rig_moving) reach_max = std::max(reach_max, reach(v));
  for (int v : m.rig_moving)
    if (reach(v) > m.options.reach_floor * reach_max) m.moving.push_back(v);
  result.human_reach_vertices = static_cast<int>(m.moving.size());
  for (int c : m.by_geometry) {
    const double all = squared_norm_over(m.rig.controllers[c].offset, m.rig_moving);
    result.rows[c].coverage = all > 0 ? squared_norm_over(m.rig.controllers[c].offset, m.moving) / all : 0.0;
  }
}

// What each controller is made of: every human shape's share of its motion (G x E), fitted over
// the moving vertices and, `landmark_weight` times as much (below), over what each face does at the
// landmarks both name (measured on each face itself: a blink closes the lids on both, however
// deformation transfer carries the human's lid onto a cartoon eye). The features ride along as
// extra rows of the fit, after the vertices. Human weights are non-negative: a human shape at a
// negative weight is no expression a person makes.
void find_shares(GeometryMatch& m, ControllerMeaning& result) {
  const Rig& rig = m.rig;
  const int E = m.E(), G = m.G();
  const std::array<LandmarkFeatures, 2> features =
      shared_landmark_features(m.face.landmarks, m.face.neutral.vertices, rig.landmarks, rig.neutral.vertices);
  const Eigen::Index V = rig.neutral.vertex_count(), P = static_cast<Eigen::Index>(features[1].points.size());
  std::vector<Eigen::VectorXd> human_features(E);
  for (int h = 0; h < E; ++h) human_features[h] = features[0].of(m.face.expressions[h].offset);
  Mesh with_features = rig.neutral;
  with_features.vertices.conservativeResize(V + P, 3);
  with_features.vertices.bottomRows(P).setZero();
  std::vector<int> moving_and_features = m.moving;
  for (Eigen::Index i = 0; i < P; ++i) moving_and_features.push_back(static_cast<int>(V + i));
  // One scale for the rig, so that over its controllers the features weigh as much as the
  // vertices (times landmark_weight); a controller that moves no landmark is fitted by its
  // vertices, and by the human shapes' features staying still.
  double vertex_total = 0, feature_total = 0;
  for (int c : m.by_geometry) {
    vertex_total += squared_norm_over(rig.controllers[c].offset, m.moving);
    feature_total += features[1].of(rig.controllers[c].offset).squaredNorm();
  }
  const double weight = feature_total > 0 ? m.options.landmark_weight * std::sqrt(vertex_total / feature_total) : 0.0;
  const auto widened = [&](const Positions& vertices, const Eigen::VectorXd& values) {
    Positions out = Positions::Zero(V + P, 3);
    out.topRows(V) = vertices;
    out.col(0).tail(P) = weight * values;
    return out;
  };
  std::vector<Positions> widened_shapes;
  widened_shapes.reserve(static_cast<size_t>(E));
  for (int h = 0; h < E; ++h) widened_shapes.push_back(widened(m.transfers[h], human_features[h]));
  std::vector<const Positions*> widened_pointers;
  for (const Positions& w : widened_shapes) widened_pointers.push_back(&w);
  const std::vector<std::pair<double, double>> positive(E, m.positive());
  const ShapeFitter every_shape(with_features, widened_pointers, positive, moving_and_features);
  m.share.resize(G, E);
  for (int g = 0; g < G; ++g) {
    const Positions& offset = rig.controllers[m.by_geometry[g]].offset;
    const ShapeFit everything = every_shape.fit(widened(offset, features[1].of(offset)));
    result.rows[m.by_geometry[g]].explained_by_all = everything.explained;
    m.share.row(g) = everything.contribution.transpose().cwiseMax(0.0);
  }
}

// Symmetry: a controller and its mirror image (the controller whose motion is most like its
// own mirrored; see `likeness` below) get the same evidence, mirrored; a symmetric controller
// (its own mirror) gets both sides' evidence alike.
void pair_mirrors(GeometryMatch& m, ControllerMeaning& result) {
  const int E = m.E(), G = m.G();
  m.mirror_shape.resize(E);
  for (int h = 0; h < E; ++h) {
    const int s = m.face.expression_index(mirror_name(m.face.expressions[h].name));
    m.mirror_shape[h] = s >= 0 ? s : h;
  }
  // How alike: by the avatar's own symmetry when its landmarks give it (one controller's motion
  // mirrored against the other's: a blink and a squint that the human shapes explain alike are
  // still told apart), else by the shares with the human sides swapped.
  const AvatarMirror avatar = avatar_mirror(m.rig);
  auto likeness = [&](int g, int d) {
    if (!avatar.partner.empty())
      return mirror_likeness(avatar, m.rig.controllers[m.by_geometry[g]].offset,
                             m.rig.controllers[m.by_geometry[d]].offset, m.rig_moving);
    const Eigen::VectorXd a = m.share.row(g).transpose(), b = m.mirrored(d);
    const double n = a.norm() * b.norm();
    return n > 0 ? a.dot(b) / n : 0.0;
  };
  // Pairs by likeness, the most alike first, each controller in one pair at most (a controller
  // paired with itself is symmetric): a blink is more like the other side's blink than the other
  // side's squint.
  m.partner.assign(G, -1);
  std::vector<std::tuple<double, int, int>> candidates;
  for (int g = 0; g < G; ++g)
    for (int d = g; d < G; ++d) {
      const double l = likeness(g, d);
      if (l >= m.options.mirror_likeness) candidates.emplace_back(l, g, d);
    }
  std::stable_sort(candidates.begin(), candidates.end(),
                   [](const auto& a, const auto& b) { return std::get<0>(a) > std::get<0>(b); });
  for (const auto& [l, g, d] : candidates)
    if (m.partner[g] < 0 && m.partner[d] < 0) m.partner[g] = d, m.partner[d] = g;
  m.evidence = m.share;
  for (int g = 0; g < G; ++g) {
    const int d = m.partner[g];
    if (d < 0) continue;
    m.evidence.row(g) = 0.5 * (m.share.row(g) + m.mirrored(d).transpose());
    result.rows[m.by_geometry[g]].mirror = m.rig.controllers[m.by_geometry[d]].name;
  }
}

// Main shapes: the largest evidence first, each human shape the main meaning of one controller
// at most (name matches claim theirs first), so that near-alike shapes (a blink and a squint,
// both closing the lids) go to the controllers they suit best; a mirror pair takes a shape and
// its mirror image together (a shape without a side, both of them).
void choose_main_shapes(GeometryMatch& m, const ControllerMeaning& result) {
  const int E = m.E(), G = m.G();
  for (const ControllerMeaningRow& row : result.rows)
    if (row.method == "name") m.claimed.insert(m.face.expression_index(row.main_shape));
  m.main.assign(G, -1);
  std::vector<std::pair<int, int>> pairs_by_evidence;
  for (int g = 0; g < G; ++g)
    for (int h = 0; h < E; ++h)
      if (m.evidence(g, h) >= m.options.min_share) pairs_by_evidence.push_back({g, h});
  std::stable_sort(pairs_by_evidence.begin(), pairs_by_evidence.end(),
                   [&](const std::pair<int, int>& a, const std::pair<int, int>& b) {
                     return m.evidence(a.first, a.second) > m.evidence(b.first, b.second);
                   });
  for (const auto& [g, h] : pairs_by_evidence) {
    if (m.main[g] >= 0 || m.claimed.count(h)) continue;
    const int d = m.partner[g];
    if (d >= 0 && d != g) {
      const int s = m.mirror_shape[h];
      if (s != h && m.claimed.count(s)) continue;
      m.main[d] = s;
      m.claimed.insert(s);
    }
    m.main[g] = h;
    m.claimed.insert(h);
  }
}

// Controller g's shapes by evidence, most first.
std::vector<int> shapes_by_evidence(const GeometryMatch& m, int g) {
  std::vector<int> order(m.E());
  for (int h = 0; h < m.E(); ++h) order[h] = h;
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return m.evidence(g, a) > m.evidence(g, b); });
  return order;
}

// The shapes controller g's row keeps: its main shape, then unclaimed ones with enough evidence.
std::vector<int> kept_shapes(const GeometryMatch& m, int g, const std::vector<int>& order) {
  std::vector<int> kept;
  if (m.main[g] < 0) return kept;
  kept.push_back(m.main[g]);
  for (int h : order) {
    if (static_cast<int>(kept.size()) == m.options.max_shapes) break;
    if (h == m.main[g] || m.claimed.count(h)) continue;
    if (m.evidence(g, h) < m.options.min_share || m.evidence(g, h) < m.options.relative_keep * m.evidence(g, m.main[g]))
      break;
    kept.push_back(h);
  }
  return kept;
}

// Controller g's row: the shapes it keeps and their fit (its confidence), its candidates (the six
// with the most evidence, and any kept beyond them) and the side it moves.
void read_row(GeometryMatch& m, int g, ControllerMeaning& result) {
  const int E = m.E(), c = m.by_geometry[g];
  ControllerMeaningRow& row = result.rows[c];
  const std::vector<int> order = shapes_by_evidence(m, g);
  const std::vector<int> kept = kept_shapes(m, g, order);
  ShapeFit chosen;
  if (!kept.empty()) {
    std::vector<const Positions*> shapes;
    for (int h : kept) shapes.push_back(&m.transfers[h]);
    chosen =
        ShapeFitter(m.rig.neutral, shapes, std::vector<std::pair<double, double>>(kept.size(), m.positive()), m.moving)
            .fit(m.rig.controllers[c].offset);
    row.confidence = chosen.explained;
  }
  for (int k = 0; k < std::min(E, 6); ++k) {
    const int h = order[k];
    if (m.evidence(g, h) <= 0) break;
    MeaningCandidate candidate;
    candidate.shape = m.face.expressions[h].name;
    candidate.share = m.evidence(g, h);
    candidate.fitted = m.F(c, h);
    row.candidates.push_back(candidate);
  }
  for (int h : kept)
    if (std::find(order.begin(), order.begin() + std::min(E, 6), h) == order.begin() + std::min(E, 6))
      row.candidates.push_back({m.face.expressions[h].name, m.evidence(g, h), m.F(c, h), 0, 0, false});
  // The side the controller moves, from its evidence: the human shapes of one side explain at
  // least twice as much of it as the other side's.
  double left = 0, right = 0;
  for (int h = 0; h < E; ++h) {
    const std::string side = name_side(m.face.expressions[h].name);
    if (side == "left") left += m.evidence(g, h);
    if (side == "right") right += m.evidence(g, h);
  }
  row.side = left > 2 * right ? "left" : right > 2 * left ? "right" : "";
  const std::string named = name_side(row.controller);
  if (!named.empty() && !row.side.empty() && named != row.side)
    row.note = fmt::format("named {}, but moves the face's {} side", named, row.side);
  m.kept_of[g] = kept;
  m.chosen_of[g] = chosen;
}

// Controller g's table row, when its confidence (a mirror pair's: their mean, so that both sides
// are decided alike) reaches min_confidence; else its method is "none".
void write_table_row(const GeometryMatch& m, int g, ControllerMeaning& result) {
  const int c = m.by_geometry[g];
  const ControllerMeaningOptions& options = m.options;
  ControllerMeaningRow& row = result.rows[c];
  std::map<std::string, double>& table_row = result.table[row.controller];
  const std::vector<int>& kept = m.kept_of[g];
  const ShapeFit& chosen = m.chosen_of[g];
  const int d = m.partner[g];
  const double confidence = d >= 0 && !m.kept_of[d].empty()
                                ? 0.5 * (row.confidence + result.rows[m.by_geometry[d]].confidence)
                                : row.confidence;
  if (kept.empty() || confidence < options.min_confidence || row.coverage < options.min_coverage ||
      chosen.weights(0) <= 0) {
    row.method = "none";
    table_row.clear();
    return;
  }
  row.method = "geometry";
  double fitted_norm = 0;
  for (int h : kept) fitted_norm += m.F(c, h) * m.F(c, h);
  std::string shapes_text;
  for (size_t k = 0; k < kept.size(); ++k) {
    const int h = kept[k];
    const std::string& shape = m.face.expressions[h].name;
    const double human = chosen.weights(static_cast<Eigen::Index>(k));
    double t = human / chosen.weights(0);
    if (options.weights == ControllerMeaningOptions::Weights::human) t = human;
    if (options.weights == ControllerMeaningOptions::Weights::fitted && fitted_norm > 0) t = m.F(c, h) / fitted_norm;
    t = meaning_detail::three_digits(t);  // what the file shows is the table
    if (t == 0) continue;
    table_row[shape] = t;
    for (MeaningCandidate& candidate : row.candidates)
      if (candidate.shape == shape) {
        candidate.kept = true;
        candidate.human_weight = human;
        candidate.table_weight = t;
      }
    shapes_text += (shapes_text.empty() ? "" : ", ") + shape;
  }
  row.main_shape = m.face.expressions[kept.front()].name;
  if (!row.note.empty()) row.note += " (" + shapes_text + "): geometry kept";
}

// The rows of the controllers in `by_geometry`: the human shapes carried onto the avatar, each
// controller's motion fitted by them, mirror pairs, main shapes, then each row and its table row.
void match_by_geometry(const Rig& rig, const FaceModel& face, const ControllerMeaningOptions& options,
                       std::vector<int> by_geometry, ControllerMeaning& result) {
  const std::vector<LandmarkPair> pairs = shared_landmark_pairs(rig, face, by_geometry, result);
  GeometryMatch m(rig, face, options, std::move(by_geometry), transferred_shapes(rig, face, pairs, options, result));
  RigWeightFitOptions fit_options;
  fit_options.ridge = options.ridge;
  fit_options.sweeps = 2000;
  const RigWeightFit fit(rig, fit_options);
  m.rig_moving = fit.moving_vertices();
  result.moving_vertices = static_cast<int>(m.rig_moving.size());
  m.F.resize(rig.controller_count(), m.E());
  for (int h = 0; h < m.E(); ++h) m.F.col(h) = fit.fit(rig.neutral.vertices + m.transfers[h]);

  find_human_reach(m, result);
  find_shares(m, result);
  pair_mirrors(m, result);
  choose_main_shapes(m, result);
  m.kept_of.resize(m.G());
  m.chosen_of.resize(m.G());
  for (int g = 0; g < m.G(); ++g) read_row(m, g, result);
  for (int g = 0; g < m.G(); ++g) write_table_row(m, g, result);
}

}  // namespace meaning_detail

ControllerMeaning propose_controller_meaning(const Rig& rig, const FaceModel& face,
                                             const ControllerMeaningOptions& options) {
  using namespace meaning_detail;
  const auto start = std::chrono::steady_clock::now();
  options.validate();
  const int C = rig.controller_count();
  const int E = static_cast<int>(face.expressions.size());
  if (C == 0) throw Error(where_of(rig), "the rig has no controllers: there is nothing to give a meaning to");
  if (E == 0) throw Error(where_of(face), "the face model has no expressions to give the controllers a meaning by");
  ControllerMeaning result;
  result.rows.resize(C);
  std::vector<int> by_geometry = rows_by_name(rig, face, options, result);
  if (!by_geometry.empty()) match_by_geometry(rig, face, options, std::move(by_geometry), result);
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

std::string controller_meaning_header(const Rig& rig, const FaceModel& face, const ControllerMeaning& meaning) {
  std::ostringstream text;
  text << fmt::format("Proposed by `retarget avatar meaning` for the rig {} against the face model {}:\n",
                      meaning_detail::where_of(rig), meaning_detail::where_of(face));
  text << "which human blendshapes each controller stands for (controller at weight 1 = these shapes at\n"
          "these weights). A proposal for a person to confirm: check each row against its picture.\n";
  if (meaning.transferred)
    text << fmt::format(
        "Geometry: {} human shapes carried onto the avatar by deformation transfer over {} shared\n"
        "landmarks ({}); the rig moves {} vertices, {} of them where a human face moves it.\n",
        face.expressions.size(), meaning.landmarks.size(), meaning_detail::joined_names(meaning.landmarks),
        meaning.moving_vertices, meaning.human_reach_vertices);
  text << "confidence: the share of the controller's motion there that the row's shapes explain; coverage:\n"
          "the share of its motion that lies there (both 1 for name matches).\n";
  for (const ControllerMeaningRow& row : meaning.rows) {
    if (row.note.empty()) continue;
    text << row.controller << ": " << row.note << "\n";
  }
  return text.str();
}

void write_controller_meaning(const std::string& path, const Rig& rig, const FaceModel& face,
                              const ControllerMeaning& meaning) {
  using meaning_detail::yaml_scalar;
  std::ostringstream text;
  std::istringstream lines(controller_meaning_header(rig, face, meaning));
  for (std::string line; std::getline(lines, line);) text << (line.empty() ? "#" : "# " + line) << "\n";
  if (!rig.name.empty()) text << "avatar: " << yaml_scalar(rig.name) << "\n";
  if (!face.name.empty()) text << "human: " << yaml_scalar(face.name) << "\n";
  text << "controllers:\n";
  for (const ControllerMeaningRow& row : meaning.rows) {
    const auto it = meaning.table.find(row.controller);
    std::string entries;
    if (it != meaning.table.end())
      for (const auto& [shape, w] : it->second)
        entries += (entries.empty() ? "" : ", ") + yaml_scalar(shape) + ": " + fmt::format("{}", w);
    std::string comment = fmt::format("confidence {:.2f} ({})", row.confidence, row.method);
    if (row.method != "name") comment += fmt::format(", coverage {:.2f}", row.coverage);
    if (row.method == "none") {
      comment += fmt::format("; human-like at most {:.2f}", row.explained_by_all);
      if (!row.candidates.empty())
        comment += fmt::format("; largest share {} {:.2f}", row.candidates.front().shape, row.candidates.front().share);
    }
    if (!row.note.empty()) comment += "; " + row.note;
    text << "  " << yaml_scalar(row.controller) << ": {" << entries << "}  # " << comment << "\n";
  }
  const std::string content = text.str();
  write_file_atomically(path, [&](std::ostream& out) { out << content; });
}

void MeaningPictureOptions::validate() const {
  if (size < 64 || size > 2048)
    throw Error("meaning_picture.size", fmt::format("expected 64..2048 pixels, got {}", size));
}

Image controller_meaning_picture(const Rig& rig, const FaceModel& face, const ControllerMeaning& meaning,
                                 const std::string& controller, const MeaningPictureOptions& options) {
  options.validate();
  const int c = rig.controller_index(controller);
  if (c < 0) throw Error(meaning_detail::where_of(rig), "no controller \"" + controller + "\"");
  const ControllerMeaningRow& row = meaning.row(controller);
  const Controller& k = rig.controllers[c];
  const double weight = std::clamp(1.0, k.min, k.max);
  Eigen::VectorXd w = Eigen::VectorXd::Zero(rig.controller_count());
  w(c) = weight;

  const auto table_row = meaning.table.find(controller);
  std::map<std::string, double> human;
  if (table_row != meaning.table.end()) human = table_row->second;
  std::string shapes;
  for (const auto& [shape, value] : human)
    shapes += (shapes.empty() ? "" : " + ") + meaning_detail::weight_text(value) + " " + shape;

  GridOptions grid;
  grid.render.width = grid.render.height = options.size;
  grid.text_scale = options.size >= 384 ? 2 : 1;
  grid.share_frame = true;
  const auto avatar_mesh = std::make_shared<const Mesh>(rig.neutral);
  const auto human_mesh = std::make_shared<const Mesh>(face.neutral);
  std::vector<GridCell> avatar_cells = {
      {avatar_mesh, rig.neutral.vertices, {}, "avatar neutral"},
      {avatar_mesh, rig.evaluate(w), {}, fmt::format("{} = {}", controller, meaning_detail::weight_text(weight))}};
  // A row left {}: the human side shows its largest share at weight 1, marked as not proposed, so
  // that a person filling the row in sees what the geometry found nearest.
  std::map<std::string, double> shown = human;
  std::string caption = shapes;
  if (human.empty()) {
    caption = "no human counterpart";
    if (!row.candidates.empty() && face.expression_index(row.candidates.front().shape) >= 0) {
      shown = {{row.candidates.front().shape, 1.0}};
      caption = "nearest, not proposed: " + row.candidates.front().shape;
    }
  }
  std::vector<GridCell> human_cells = {{human_mesh, face.neutral.vertices, {}, "human neutral"},
                                       {human_mesh, face.expression(face.neutral.vertices, shown), {}, caption}};
  const Image left = render_grid(avatar_cells, 2, grid);
  const Image right = render_grid(human_cells, 2, grid);
  const Image body = hconcat({left, right}, grid.render.background);

  std::string title = fmt::format("{}: {} ({}, confidence {:.2f})", controller,
                                  human.empty() ? std::string("{}") : shapes, row.method, row.confidence);
  if (!row.note.empty()) title += "; " + row.note;
  Image band(body.width, text_band_height(grid.text_scale), grid.render.background);
  draw_text(band, 4 * grid.text_scale, 4 * grid.text_scale, title, grid.text_scale, grid.text_colour);
  return vconcat({band, body}, grid.render.background);
}

}  // namespace retarget
