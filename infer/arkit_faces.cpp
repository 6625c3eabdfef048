#include "infer/arkit_faces.h"

#include <fmt/format.h>

#include <cmath>
#include <map>
#include <string_view>
#include <utility>

#include "core/error.h"
#include "core/log.h"
#include "geometry/text_lines.h"
#include "geometry/topology_fingerprint.h"

namespace retarget {

namespace {

std::string_view trim_blanks(std::string_view text) {
  while (!text.empty() && (text.front() == ' ' || text.front() == '\t')) text.remove_prefix(1);
  while (!text.empty() && (text.back() == ' ' || text.back() == '\t')) text.remove_suffix(1);
  return text;
}

std::string face_model_name(const FaceModel& model) { return model.source.empty() ? model.name : model.source; }

}  // namespace

Eigen::VectorXd parse_identity(const std::string& text, const std::string& option) {
  std::vector<double> values;
  size_t start = 0;
  while (true) {
    const size_t comma = text.find(',', start);
    const std::string_view entry = trim_blanks(
        std::string_view(text).substr(start, comma == std::string::npos ? std::string::npos : comma - start));
    const int number = static_cast<int>(values.size()) + 1;
    double value = 0;
    if (entry.empty())
      throw Error(option, fmt::format("entry {} is empty; expected comma-separated numbers like 0.5,-1.2", number));
    if (parse_real(entry, value) != NumberStatus::ok || !std::isfinite(value))
      throw Error(option, fmt::format("entry {}: expected a finite number, got {}", number, retarget::quoted(entry)));
    values.push_back(value);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return Eigen::Map<const Eigen::VectorXd>(values.data(), static_cast<Eigen::Index>(values.size()));
}

ArkitFaces::ArkitFaces(FaceModel model, const Eigen::VectorXd& identity) : model_(std::move(model)) {
  for (Eigen::Index i = 0; i < identity.size(); ++i)
    if (!std::isfinite(identity[i]))
      throw Error(face_model_name(model_), fmt::format("identity coefficient {} is not finite", i + 1));
  person_ = model_.person(identity);
}

std::vector<std::string> ArkitFaces::expression_names() const {
  std::vector<std::string> names;
  for (const Blendshape& shape : model_.expressions) names.push_back(shape.name);
  return names;
}

Positions ArkitFaces::frame(const ArkitTake& take, int frame) const {
  if (take.expressions != expression_names())
    throw Error(take.source,
                "the take was read for other expression names than those of the face model " + face_model_name(model_));
  if (frame < 0 || frame >= take.frames())
    throw Error(take.source, fmt::format("no frame {} (the take has {})", frame, take.frames()));
  std::map<std::string, double> weights;
  for (int k = 0; k < static_cast<int>(take.expressions.size()); ++k)
    weights.emplace(take.expressions[k], take.weights(frame, k));
  return model_.expression(person_, weights);
}

Mesh ArkitFaces::mesh(const ArkitTake& take, int frame) const {
  Mesh mesh = with_positions(model_.neutral, this->frame(take, frame));
  mesh.source = fmt::format("{} frame {}", take.source, frame);
  return mesh;
}

FaceModelRestFit check_face_model_for_bundle(const FaceModel& model, const Mesh& human_rest,
                                             const std::string& human_units) {
  const std::string name = face_model_name(model);
  const Mesh& neutral = model.neutral;
  const std::string advice = "give the face model the bundle's human dataset was made from (--face-model)";
  if (neutral.vertex_count() != human_rest.vertex_count())
    throw Error(name, fmt::format("the face model has {} vertices but the bundle's human rest {} has {}; {}",
                                  neutral.vertex_count(), human_rest.source, human_rest.vertex_count(), advice));
  const std::string model_fingerprint = topology_fingerprint(neutral),
                    rest_fingerprint = topology_fingerprint(human_rest);
  if (model_fingerprint != rest_fingerprint)
    throw Error(name,
                fmt::format("the face model has the topology {} but the bundle's human rest {} has {} (both "
                            "have {} vertices: other faces or another vertex order); {}",
                            model_fingerprint, human_rest.source, rest_fingerprint, neutral.vertex_count(), advice));
  if (!model.units.empty() && !human_units.empty() && model.units != human_units)
    throw Error(name, fmt::format("the face model is in {} but the bundle's human side is in {}; {}", model.units,
                                  human_units, advice));
  FaceModelRestFit fit;
  fit.largest_difference = (neutral.vertices - human_rest.vertices).rowwise().norm().maxCoeff();
  fit.rest_size = (human_rest.vertices.colwise().maxCoeff() - human_rest.vertices.colwise().minCoeff()).norm();
  fit.same = fit.largest_difference <= 1e-4 * fit.rest_size;
  if (!fit.same)
    log::warn(
        "{}: the face model's neutral is not the bundle's human rest {} (vertices up to {:.4g} {} apart, {:.2g}% of "
        "the face's size); the bundle measures the take's faces against its own rest, so expect an offset if "
        "this is not the model the bundle was trained with",
        name, human_rest.source, fit.largest_difference, model.units, 100 * fit.largest_difference / fit.rest_size);
  return fit;
}

ArkitFaces load_arkit_faces(const std::string& face_model, const std::vector<double>& identity, const Mesh& human_rest,
                            const std::string& human_units) {
  FaceModel model = load_face_model(face_model);
  check_face_model_for_bundle(model, human_rest, human_units);
  return ArkitFaces(std::move(model),
                    Eigen::Map<const Eigen::VectorXd>(identity.data(), static_cast<Eigen::Index>(identity.size())));
}

}  // namespace retarget
