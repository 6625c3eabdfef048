#include "correspond/rig_face_metric.h"

#include "geometry/metrics.h"
#include "geometry/rig_footprint.h"

namespace retarget {

Eigen::MatrixXd rig_face_metric(const Rig& rig, const Dataset& avatar) {
  const double mm = avatar.eyes.left.empty() ? 1.0 : millimetres_per_unit(rig.neutral.vertices, avatar.eyes);
  const RigFootprint footprint = rig_footprint(rig, 0.1 / mm);
  const Eigen::Index c = rig.controller_count();
  Eigen::MatrixXd b(static_cast<Eigen::Index>(footprint.moving.size()) * 3, c);
  for (Eigen::Index j = 0; j < c; ++j)
    for (size_t i = 0; i < footprint.moving.size(); ++i)
      b.block<3, 1>(static_cast<Eigen::Index>(3 * i), j) =
          rig.controllers[static_cast<size_t>(j)].offset.row(footprint.moving[i]).transpose();
  Eigen::MatrixXd g = b.transpose() * b;
  const double scale = g.diagonal().mean();
  return scale > 0 ? Eigen::MatrixXd(g / scale) : Eigen::MatrixXd::Identity(c, c);
}

Eigen::MatrixXd rig_face_metric(const Rig& rig, const Dataset& avatar,
                                const std::map<std::string, std::vector<std::string>>& rows) {
  const double mm = avatar.eyes.left.empty() ? 1.0 : millimetres_per_unit(rig.neutral.vertices, avatar.eyes);
  std::map<std::string, std::vector<std::string>> names;
  for (const Controller& c : rig.controllers) {
    const auto row = rows.find(c.name);
    // A controller with no human shape is classified by nothing (not by its own name).
    names[c.name] = row == rows.end() || row->second.empty() ? std::vector<std::string>{"-"} : row->second;
  }
  const RigFootprint footprint = rig_footprint(rig, 0.1 / mm, names);
  if (footprint.regions.empty()) return rig_face_metric(rig, avatar);
  const Eigen::Index c = rig.controller_count();
  Eigen::MatrixXd g = Eigen::MatrixXd::Zero(c, c);
  for (const auto& [region, vertices] : footprint.regions) {
    Eigen::MatrixXd b(static_cast<Eigen::Index>(vertices.size()) * 3, c);
    for (Eigen::Index j = 0; j < c; ++j)
      for (size_t i = 0; i < vertices.size(); ++i)
        b.block<3, 1>(static_cast<Eigen::Index>(3 * i), j) =
            rig.controllers[static_cast<size_t>(j)].offset.row(vertices[i]).transpose();
    g += b.transpose() * b / static_cast<double>(vertices.size());
  }
  const double scale = g.diagonal().mean();
  return scale > 0 ? Eigen::MatrixXd(g / scale) : rig_face_metric(rig, avatar);
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
