#include "geometry/controller_correspondence.h"

#include <Eigen/Dense>
#include <algorithm>
#include <charconv>
#include <cmath>
#include <set>
#include <sstream>

#include "core/atomic_file.h"
#include "core/config.h"
#include "core/error.h"
#include "geometry/text_lines.h"

namespace retarget {

namespace {

std::string join_names(const std::set<std::string>& names, size_t limit = 12) {
  std::string text;
  size_t count = 0;
  for (const std::string& name : names) {
    if (count == limit) return text + ", ...";
    text += (count++ ? ", " : "") + name;
  }
  return text;
}

}  // namespace

ControllerCorrespondence load_controller_correspondence(const std::string& path) {
  const ConfigNode root = ConfigNode::load_file(path);
  if (!root.is_map()) root.fail("expected a map with a `controllers` map");
  root.reject_unknown_keys({"avatar", "human", "controllers"});
  if (root.has("avatar")) (void)root.child("avatar").as<std::string>();
  if (root.has("human")) (void)root.child("human").as<std::string>();
  const ConfigNode rows = root.child("controllers");
  if (!rows.is_map()) rows.fail("expected a map {controller: {human_blendshape: weight, ...}}");
  ControllerCorrespondence table;
  for (const auto& entry : rows.yaml()) {
    const std::string controller = entry.first.as<std::string>();
    const ConfigNode row = rows.child(controller);
    std::map<std::string, double>& weights = table[controller];
    if (row.is_null()) continue;
    if (!row.is_map()) row.fail("expected a map {human_blendshape: weight} (or {} for none)");
    for (const auto& item : row.yaml()) {
      const std::string shape = item.first.as<std::string>();
      const ConfigNode value = row.child(shape);
      const double w = value.as<double>();
      if (!std::isfinite(w)) value.fail("expected a finite weight, got " + shortest_text(w));
      weights[shape] = w;
    }
  }
  return table;
}

void write_controller_correspondence(const std::string& path, const ControllerCorrespondence& table,
                                     const std::string& avatar, const std::string& header) {
  std::ostringstream text;
  std::istringstream lines(header);
  for (std::string line; std::getline(lines, line);) text << (line.empty() ? "#" : "# " + line) << "\n";
  if (!avatar.empty()) text << "avatar: " << avatar << "\n";
  text << "controllers:\n";
  for (const auto& [controller, weights] : table) {
    text << "  " << controller << ": {";
    bool first = true;
    for (const auto& [shape, w] : weights) {
      text << (first ? "" : ", ") << shape << ": " << shortest_text(w);
      first = false;
    }
    text << "}\n";
  }
  const std::string content = text.str();
  write_file_atomically(path, [&](std::ostream& out) { out << content; });
}

void check_controller_correspondence(const ControllerCorrespondence& table, const std::vector<std::string>& controllers,
                                     const std::vector<std::string>& blendshapes, const std::string& where) {
  const std::set<std::string> known_controllers(controllers.begin(), controllers.end());
  const std::set<std::string> known_shapes(blendshapes.begin(), blendshapes.end());
  for (const auto& [controller, weights] : table) {
    if (!known_controllers.count(controller))
      throw Error(where, "controllers." + controller + ": the rig has no controller \"" + controller +
                             "\" (it has: " + join_names(known_controllers) + ")");
    for (const auto& [shape, w] : weights)
      if (!known_shapes.count(shape))
        throw Error(where,
                    "controllers." + controller + "." + shape + ": the face model has no blendshape \"" + shape + "\"");
  }
  std::set<std::string> missing;
  for (const std::string& c : controllers)
    if (!table.count(c)) missing.insert(c);
  if (!missing.empty())
    throw Error(where, "no row for the rig's controller(s) " + join_names(missing) +
                           " (write `name: {}` for a controller without a human counterpart)");
}

std::map<std::string, double> controller_weights_from_human(const ControllerCorrespondence& table,
                                                            const std::map<std::string, double>& human_weights,
                                                            double lo, double hi) {
  std::map<std::string, double> result;
  std::vector<std::string> active;
  std::map<std::string, int> shape_row;
  for (const auto& [controller, weights] : table) {
    result[controller] = 0.0;
    if (weights.empty()) continue;
    active.push_back(controller);
    for (const auto& entry : weights) shape_row.emplace(entry.first, static_cast<int>(shape_row.size()));
  }
  if (active.empty()) return result;
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(static_cast<int>(shape_row.size()), static_cast<int>(active.size()));
  Eigen::VectorXd w = Eigen::VectorXd::Zero(A.rows());
  for (size_t c = 0; c < active.size(); ++c)
    for (const auto& [shape, weight] : table.at(active[c])) A(shape_row.at(shape), static_cast<int>(c)) = weight;
  for (const auto& [shape, weight] : human_weights) {
    const auto it = shape_row.find(shape);
    if (it != shape_row.end()) w(it->second) = weight;
  }
  const Eigen::MatrixXd normal = A.transpose() * A + 1e-12 * Eigen::MatrixXd::Identity(A.cols(), A.cols());
  const Eigen::VectorXd y = normal.ldlt().solve(A.transpose() * w);
  for (size_t c = 0; c < active.size(); ++c) result[active[c]] = std::clamp(y(static_cast<int>(c)), lo, hi);
  return result;
}

Eigen::VectorXd rig_weights_from_human(const ControllerCorrespondence& table, const Rig& rig,
                                       const std::map<std::string, double>& human_weights) {
  const std::map<std::string, double> mapped = controller_weights_from_human(table, human_weights, -1e300, 1e300);
  Eigen::VectorXd w = Eigen::VectorXd::Zero(rig.controller_count());
  for (int c = 0; c < rig.controller_count(); ++c) {
    const auto it = mapped.find(rig.controllers[c].name);
    if (it != mapped.end()) w(c) = std::clamp(it->second, rig.controllers[c].min, rig.controllers[c].max);
  }
  return w;
}

}  // namespace retarget
