#include "correspond/rig_face_metric.h"

#include "geometry/metrics.h"
#include "geometry/rig_footprint.h"

namespace retarget {

namespace {

// The rig units of 0.1 mm (`avatar`'s eye distance gives the millimetres; without eyes, 1).
double still_threshold(const Rig& rig, const Dataset& avatar) {
  return 0.1 / (avatar.eyes.left.empty() ? 1.0 : millimetres_per_unit(rig.neutral.vertices, avatar.eyes));
}

// B' B / |vertices|, B the controllers' offsets at `vertices` (3|vertices| x C).
Eigen::MatrixXd offset_gram(const Rig& rig, const std::vector<int>& vertices) {
  const Eigen::Index c = rig.controller_count();
  Eigen::MatrixXd b(static_cast<Eigen::Index>(vertices.size()) * 3, c);
  for (Eigen::Index j = 0; j < c; ++j)
    for (size_t i = 0; i < vertices.size(); ++i)
      b.block<3, 1>(static_cast<Eigen::Index>(3 * i), j) =
          rig.controllers[static_cast<size_t>(j)].offset.row(vertices[i]).transpose();
  return vertices.empty() ? Eigen::MatrixXd::Zero(c, c)
                          : Eigen::MatrixXd(b.transpose() * b / static_cast<double>(vertices.size()));
}

// Scaled to a mean diagonal of 1; the identity for a rig that moves nothing.
Eigen::MatrixXd unit_scaled(const Eigen::MatrixXd& g) {
  const double scale = g.diagonal().mean();
  return scale > 0 ? Eigen::MatrixXd(g / scale) : Eigen::MatrixXd::Identity(g.rows(), g.cols());
}

}  // namespace

Eigen::MatrixXd rig_face_metric(const Rig& rig, const Dataset& avatar) {
  return unit_scaled(offset_gram(rig, rig_footprint(rig, still_threshold(rig, avatar)).moving));
}

Eigen::MatrixXd rig_face_metric(const Rig& rig, const Dataset& avatar,
                                const std::map<std::string, std::vector<std::string>>& rows) {
  std::map<std::string, std::vector<std::string>> names;
  for (const Controller& c : rig.controllers) {
    const auto row = rows.find(c.name);
    // A controller with no human shape is classified by nothing (not by its own name).
    names[c.name] = row == rows.end() || row->second.empty() ? std::vector<std::string>{"-"} : row->second;
  }
  const RigFootprint footprint = rig_footprint(rig, still_threshold(rig, avatar), names);
  if (footprint.regions.empty()) return rig_face_metric(rig, avatar);
  Eigen::MatrixXd g = Eigen::MatrixXd::Zero(rig.controller_count(), rig.controller_count());
  for (const auto& [region, vertices] : footprint.regions) g += offset_gram(rig, vertices);
  return unit_scaled(g);
}

Eigen::VectorXd rig_lower(const Rig& rig) {
  Eigen::VectorXd v(rig.controller_count());
  for (int c = 0; c < rig.controller_count(); ++c) v(c) = rig.controllers[static_cast<size_t>(c)].min;
  return v;
}

Eigen::VectorXd rig_upper(const Rig& rig) {
  Eigen::VectorXd v(rig.controller_count());
  for (int c = 0; c < rig.controller_count(); ++c) v(c) = rig.controllers[static_cast<size_t>(c)].max;
  return v;
}

}  // namespace retarget
