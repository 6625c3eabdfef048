#include "geometry/part_motion.h"

#include <algorithm>
#include <map>

#include "core/error.h"
#include "geometry/mesh_topology.h"
#include "geometry/rigid_alignment.h"

namespace retarget {

std::vector<std::vector<int>> rig_parts_to_move(const Rig& rig) {
  const int n = rig.neutral.vertex_count();
  const Components components = connected_components(edge_topology(rig.neutral.triangles), n);
  std::vector<std::vector<int>> members(static_cast<size_t>(components.count()));
  for (int v = 0; v < n; ++v) members[static_cast<size_t>(components.component[static_cast<size_t>(v)])].push_back(v);
  size_t skin = 0;
  for (size_t c = 1; c < members.size(); ++c)
    if (members[c].size() > members[skin].size()) skin = c;
  std::vector<std::vector<int>> parts;
  std::vector<char> named(static_cast<size_t>(n), 0);
  // A named part, piece by piece: one mesh often holds both rows of teeth, which move apart.
  for (const RigPart& part : rig.parts) {
    std::map<int, std::vector<int>> by_piece;
    for (int v : part.vertices) {
      if (v < 0 || v >= n)
        throw Error(rig.source.empty() ? rig.name : rig.source,
                    "part \"" + part.name + "\": vertex " + std::to_string(v) + " is out of range (the rig has " +
                        std::to_string(n) + " vertices)");
      by_piece[components.component[static_cast<size_t>(v)]].push_back(v);
      named[static_cast<size_t>(v)] = 1;
    }
    for (auto& [piece, vertices] : by_piece)
      if (vertices.size() >= 3) parts.push_back(std::move(vertices));
  }
  // Every other piece apart from the skin: lashes, brows, a second island of skin.
  for (size_t c = 0; c < members.size(); ++c) {
    if (c == skin) continue;
    std::vector<int> rest;
    for (int v : members[c])
      if (!named[static_cast<size_t>(v)]) rest.push_back(v);
    if (rest.size() >= 3) parts.push_back(std::move(rest));
  }
  return parts;
}

PartMotion::PartMotion(const Rig& rig, std::vector<std::vector<int>> parts, const RigWeightFitOptions& fit)
    : parts_(parts.empty() ? rig_parts_to_move(rig) : std::move(parts)) {
  const int n = rig.neutral.vertex_count();
  std::vector<char> in_part(static_cast<size_t>(n), 0);
  for (size_t p = 0; p < parts_.size(); ++p) {
    const std::string where = (rig.source.empty() ? rig.name : rig.source) + ": part " + std::to_string(p);
    if (parts_[p].size() < 3) throw Error(where, "has fewer than 3 vertices: no rigid motion to fit");
    for (int v : parts_[p]) {
      if (v < 0 || v >= n)
        throw Error(
            where, "vertex " + std::to_string(v) + " is out of range (the rig has " + std::to_string(n) + " vertices)");
      if (in_part[static_cast<size_t>(v)]) throw Error(where, "vertex " + std::to_string(v) + " is in two parts");
      in_part[static_cast<size_t>(v)] = 1;
    }
  }
  if (!parts_.empty() && std::count(in_part.begin(), in_part.end(), 1) == n)
    throw Error(rig.source.empty() ? rig.name : rig.source, "the parts cover every vertex: there is no skin to follow");
  for (const std::vector<int>& part : parts_) {
    Positions rest(static_cast<Eigen::Index>(part.size()), 3);
    std::vector<Positions> offsets(rig.controllers.size(), Positions(rest.rows(), 3));
    for (size_t i = 0; i < part.size(); ++i) {
      rest.row(static_cast<Eigen::Index>(i)) = rig.neutral.vertices.row(part[i]);
      for (size_t c = 0; c < rig.controllers.size(); ++c)
        offsets[c].row(static_cast<Eigen::Index>(i)) = rig.controllers[c].offset.row(part[i]);
    }
    part_rest_.push_back(std::move(rest));
    part_offsets_.push_back(std::move(offsets));
  }
  // The fit's rig: the skin as it is, each part's offsets about their mean over the part (what
  // the part's shape does, not where it goes), matched by apply() to the part's shape about its
  // own centroid.
  fit_rig_ = std::make_unique<Rig>(rig);
  for (Controller& c : fit_rig_->controllers)
    for (const std::vector<int>& part : parts_) {
      Eigen::RowVector3d mean = Eigen::RowVector3d::Zero();
      for (int v : part) mean += c.offset.row(v);
      mean /= static_cast<double>(part.size());
      for (int v : part) c.offset.row(v) -= mean;
    }
  for (const Positions& rest : part_rest_) part_centroid_.push_back(rest.colwise().mean());
  fit_ = std::make_unique<RigWeightFit>(*fit_rig_, fit);
}

PartMotion::~PartMotion() = default;

void PartMotion::apply(Positions& mesh) const {
  if (parts_.empty() || fit_rig_->controllers.empty()) return;
  if (mesh.rows() != fit_rig_->neutral.vertex_count())
    throw Error("part motion", "the mesh has " + std::to_string(mesh.rows()) + " vertices, the rig " +
                                   std::to_string(fit_rig_->neutral.vertex_count()));
  // Each part's shape about its centroid, put at its rest centroid: the fit reads its turn, not its place.
  for (size_t p = 0; p < parts_.size(); ++p) {
    Eigen::RowVector3d centroid = Eigen::RowVector3d::Zero();
    for (int v : parts_[p]) centroid += mesh.row(v);
    centroid /= static_cast<double>(parts_[p].size());
    const Eigen::RowVector3d shift = part_centroid_[p] - centroid;
    for (int v : parts_[p]) mesh.row(v) += shift;
  }
  const Eigen::VectorXd weights = fit_->fit(mesh);
  for (size_t p = 0; p < parts_.size(); ++p) {
    const std::vector<int>& part = parts_[p];
    Positions from(part_rest_[p].rows(), 3);
    for (size_t i = 0; i < part.size(); ++i) from.row(static_cast<Eigen::Index>(i)) = mesh.row(part[i]);
    Positions to = part_rest_[p];
    for (size_t c = 0; c < part_offsets_[p].size(); ++c)
      to += weights(static_cast<Eigen::Index>(c)) * part_offsets_[p][c];
    const Positions moved = rigid_alignment(from, to).apply(from);
    for (size_t i = 0; i < part.size(); ++i) mesh.row(part[i]) = moved.row(static_cast<Eigen::Index>(i));
  }
}

}  // namespace retarget
