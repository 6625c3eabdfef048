#include "geometry/controller_map.h"

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <filesystem>
#include <limits>

#include "core/atomic_file.h"
#include "core/config.h"
#include "core/error.h"
#include "core/tensor_io.h"
#include "geometry/gaussian_box_mode.h"

namespace retarget {

namespace fs = std::filesystem;

namespace {

constexpr const char* kMapFormat = "retarget-controller-map";

}  // namespace

Eigen::VectorXd ControllerMap::apply(const std::map<std::string, double>& weights, const Eigen::VectorXd& lo,
                                     const Eigen::VectorXd& hi) const {
  Eigen::VectorXd r = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(shapes.size()));
  for (size_t s = 0; s < shapes.size(); ++s) {
    const auto it = weights.find(shapes[s]);
    if (it != weights.end()) r(static_cast<Eigen::Index>(s)) = it->second;
  }
  Eigen::VectorXd y = mean_of(r);
  if (covariance.size() > 0 && lo.size() == y.size() && hi.size() == y.size())
    return gaussian_box_mode(y, covariance_of(r), lo, hi);
  if (lo.size() == y.size()) y = y.cwiseMax(lo);
  if (hi.size() == y.size()) y = y.cwiseMin(hi);
  return y;
}

Eigen::MatrixXd ControllerMap::covariance_of(const Eigen::VectorXd& r) const {
  const Eigen::Index c = matrix.rows();
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(c, c);
  if (covariance.size() == 0) return out;
  for (Eigen::Index s = 0; s < r.size(); ++s) {
    if (r(s) == 0) continue;
    for (Eigen::Index t = 0; t < r.size(); ++t)
      if (r(t) != 0) out += r(s) * r(t) * covariance.block(s * c, t * c, c, c);
  }
  return out;
}

Eigen::VectorXd ControllerMap::on_rig(const std::map<std::string, double>& weights, const Rig& rig,
                                      const std::string& where) const {
  const auto n = static_cast<Eigen::Index>(rig.controller_count());
  bool same = static_cast<Eigen::Index>(controllers.size()) == n;
  Eigen::VectorXd lo(n), hi(n);
  for (Eigen::Index c = 0; c < n; ++c) {
    const Controller& controller = rig.controllers[static_cast<size_t>(c)];
    same = same && controllers[static_cast<size_t>(c)] == controller.name;
    lo(c) = controller.min, hi(c) = controller.max;
  }
  if (!same)
    throw Error(where, fmt::format("maps onto {} controllers ({}...), not the {} of the rig {}", controllers.size(),
                                   controllers.empty() ? "" : controllers.front(), n, rig.source));
  return apply(weights, lo, hi);
}

bool is_controller_map_file(const std::string& path) {
  const ConfigNode root = ConfigNode::load_file(path);
  return root.is_map() && root.has("format") && root.child("format").as<std::string>() == kMapFormat;
}

ControllerMap controller_map_from_table(const ControllerCorrespondence& table,
                                        const std::vector<std::string>& controllers,
                                        const std::vector<std::string>& shapes) {
  ControllerMap map;
  map.controllers = controllers;
  map.shapes = shapes;
  map.matrix =
      Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(controllers.size()), static_cast<Eigen::Index>(shapes.size()));
  constexpr double kFree = std::numeric_limits<double>::max();
  for (size_t s = 0; s < shapes.size(); ++s) {
    const std::map<std::string, double> y = controller_weights_from_human(table, {{shapes[s], 1.0}}, -kFree, kFree);
    for (size_t c = 0; c < controllers.size(); ++c) {
      const auto it = y.find(controllers[c]);
      if (it != y.end()) map.matrix(static_cast<Eigen::Index>(c), static_cast<Eigen::Index>(s)) = it->second;
    }
  }
  return map;
}

ControllerMap load_prior_map(const std::string& path, const std::vector<std::string>& controllers,
                             const std::vector<std::string>& shapes) {
  if (is_controller_map_file(path)) {
    ControllerMap map = load_controller_map(path);
    if (map.controllers != controllers)
      throw Error(path,
                  fmt::format("maps {} controllers, not the rig's {}", map.controllers.size(), controllers.size()));
    if (map.shapes != shapes)
      throw Error(path, fmt::format("maps {} shapes, not the face model's {}", map.shapes.size(), shapes.size()));
    return map;
  }
  const ControllerCorrespondence table = load_controller_correspondence(path);
  check_controller_correspondence(table, controllers, shapes, path);
  ControllerMap map = controller_map_from_table(table, controllers, shapes);
  map.prior = fs::absolute(path).lexically_normal().string();
  return map;
}

void write_controller_map(const std::string& path, const ControllerMap& map) {
  YAML::Emitter y;
  y << YAML::BeginMap << YAML::Key << "format" << YAML::Value << kMapFormat;
  y << YAML::Key << "controllers" << YAML::Value << YAML::Flow << map.controllers;
  y << YAML::Key << "shapes" << YAML::Value << YAML::Flow << map.shapes;
  y << YAML::Key << "matrix" << YAML::Value << YAML::BeginSeq;
  for (Eigen::Index i = 0; i < map.matrix.rows(); ++i) {
    std::vector<double> row;
    for (Eigen::Index j = 0; j < map.matrix.cols(); ++j) row.push_back(map.matrix(i, j));
    y << YAML::Flow << row;
  }
  y << YAML::EndSeq;
  y << YAML::Key << "pairs" << YAML::Value << map.pairs;
  y << YAML::Key << "prior" << YAML::Value << map.prior;
  if (map.covariance.size() > 0) {
    const std::string file = fs::path(path).filename().string() + ".covariance.pt";
    save_tensors((fs::path(path).parent_path() / file).string(),
                 {{"covariance", torch::from_blob(const_cast<double*>(map.covariance.data()),
                                                  {map.covariance.rows(), map.covariance.cols()}, torch::kFloat64)
                                     .clone()}});
    y << YAML::Key << "covariance" << YAML::Value << file;
  }
  y << YAML::EndMap;
  write_file_atomically(path, [&](std::ostream& out) {
    out << "# retarget controller map: human blendshape weights -> avatar controller weights "
           "(geometry/controller_map.h)\n"
        << y.c_str() << "\n";
  });
}

ControllerMap load_controller_map(const std::string& path) {
  const ConfigNode root = ConfigNode::load_file(path);
  root.reject_unknown_keys({"format", "controllers", "shapes", "matrix", "pairs", "prior", "covariance"});
  if (root.child("format").as<std::string>() != kMapFormat)
    root.child("format").fail(fmt::format("expected {}", kMapFormat));
  ControllerMap map;
  root.get_required("controllers", map.controllers);
  root.get_required("shapes", map.shapes);
  root.get("pairs", map.pairs);
  root.get("prior", map.prior);
  const ConfigNode rows = root.child("matrix");
  if (!rows.is_sequence() || rows.size() != map.controllers.size())
    rows.fail(fmt::format("expected a list of {} rows (one per controller)", map.controllers.size()));
  map.matrix.resize(static_cast<Eigen::Index>(map.controllers.size()), static_cast<Eigen::Index>(map.shapes.size()));
  for (size_t i = 0; i < rows.size(); ++i) {
    const std::vector<double> row = rows.at(i).as<std::vector<double>>();
    if (row.size() != map.shapes.size())
      rows.at(i).fail(fmt::format("expected {} numbers (one per shape), got {}", map.shapes.size(), row.size()));
    for (size_t j = 0; j < row.size(); ++j) {
      if (!std::isfinite(row[j])) rows.at(i).fail(fmt::format("entry {} is not a finite number", j));
      map.matrix(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = row[j];
    }
  }
  if (root.has("covariance")) {
    const std::string file = (fs::path(path).parent_path() / root.child("covariance").as<std::string>()).string();
    const torch::Tensor t = tensor_named(load_tensors(file), "covariance", file).to(torch::kFloat64).contiguous();
    const int64_t d = map.matrix.size();
    if (t.dim() != 2 || t.size(0) != d || t.size(1) != d)
      root.child("covariance")
          .fail(fmt::format("{} holds a covariance of {}, expected [{}, {}] ({} controllers x {} "
                            "shapes)",
                            file, c10::str(t.sizes()), d, d, map.controllers.size(), map.shapes.size()));
    if (!torch::isfinite(t).all().item<bool>())
      root.child("covariance").fail(file + " holds values that are not finite");
    map.covariance = Eigen::Map<const Eigen::MatrixXd>(t.data_ptr<double>(), d, d);
  }
  return map;
}

}  // namespace retarget
