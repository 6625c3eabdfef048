#include "geometry/rig_footprint.h"

#include <algorithm>
#include <cctype>
#include <cmath>

namespace retarget {

std::string face_region_of(const std::string& name) {
  std::string n = name;
  std::transform(n.begin(), n.end(), n.begin(), [](unsigned char ch) { return static_cast<char>(std::tolower(ch)); });
  const auto has = [&](const char* word) { return n.find(word) != std::string::npos; };
  if (has("brow")) return "brows";
  if (has("eye") || has("blink") || has("squint") || has("lid")) return "eyes";
  for (const char* word : {"jaw", "mouth", "lip", "smile", "cheek", "tongue", "nose", "sneer", "chin", "teeth", "frown",
                           "pucker", "funnel", "dimple"})
    if (has(word)) return "mouth";
  return "";
}

Eigen::VectorXd vertex_motion(const Positions& rest, const std::vector<Positions>& shapes) {
  Eigen::VectorXd motion = Eigen::VectorXd::Zero(rest.rows());
  for (const Positions& s : shapes) motion = motion.cwiseMax((s - rest).rowwise().norm());
  return motion;
}

std::vector<int> moving_vertices(const Eigen::VectorXd& motion, double absolute, double relative) {
  std::vector<int> out;
  if (motion.size() == 0) return out;
  const double limit = std::max(absolute, relative * motion.maxCoeff());
  for (Eigen::Index v = 0; v < motion.size(); ++v)
    if (motion(v) > limit) out.push_back(static_cast<int>(v));
  return out;
}

RigFootprint rig_footprint(const Rig& rig, double threshold,
                           const std::map<std::string, std::vector<std::string>>& controller_names) {
  RigFootprint f;
  const Eigen::Index v = rig.neutral.vertex_count();
  f.motion = Eigen::VectorXd::Zero(v);
  std::map<std::string, Eigen::VectorXd> region_motion;
  for (const Controller& c : rig.controllers) {
    const double reach = std::max(std::abs(c.min), std::abs(c.max));
    const Eigen::VectorXd m = c.offset.rowwise().norm() * reach;
    f.motion = f.motion.cwiseMax(m);
    std::string region;
    const auto listed = controller_names.find(c.name);
    if (listed != controller_names.end() && !listed->second.empty()) {
      std::map<std::string, int> votes;
      for (const std::string& name : listed->second) ++votes[face_region_of(name)];
      int best = 0;
      for (const auto& [r, count] : votes)
        if (count > best || (count == best && region.empty())) best = count, region = r;
    } else {
      region = face_region_of(c.name);
    }
    f.controller_region[c.name] = region;
    if (region.empty()) continue;
    auto it = region_motion.find(region);
    if (it == region_motion.end()) it = region_motion.emplace(region, Eigen::VectorXd::Zero(v)).first;
    it->second = it->second.cwiseMax(m);
  }
  f.moving = moving_vertices(f.motion, threshold);
  const double limit = std::max(threshold, 0.01 * (v > 0 ? f.motion.maxCoeff() : 0.0));
  for (const auto& [region, m] : region_motion) {
    std::vector<int> vertices = moving_vertices(m, limit, 0.0);
    if (!vertices.empty()) f.regions[region] = std::move(vertices);
  }
  return f;
}

}  // namespace retarget
