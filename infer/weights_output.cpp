#include "infer/weights_output.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "core/atomic_file.h"
#include "core/error.h"

namespace retarget {

// Named, not anonymous: a unity batch shares one anonymous namespace among its files.
namespace weights_output_detail {

namespace fs = std::filesystem;

RigWeightFitOptions fit_options(const WeightsOutputOptions& options) {
  options.validate();
  RigWeightFitOptions fit;
  fit.ridge = options.ridge;
  fit.smoothness = options.smoothness;
  return fit;
}

// A CSV field, quoted when it holds a comma, a quote, a line break or outer spaces (RFC 4180).
std::string csv_field(const std::string& text) {
  const bool quote = text.find_first_of(",\"\r\n") != std::string::npos ||
                     (!text.empty() && (text.front() == ' ' || text.back() == ' '));
  if (!quote) return text;
  std::string out = "\"";
  for (const char c : text) {
    if (c == '"') out += '"';
    out += c;
  }
  return out + "\"";
}

// Shortest text that reads back as the same double ("nan" and "inf" as C++ writes them).
std::string number(double value) { return fmt::format("{}", value); }

}  // namespace weights_output_detail

void WeightsOutputOptions::validate() const {
  if (!(ridge >= 0) || !std::isfinite(ridge))
    throw Error("--weights-ridge", fmt::format("expected a finite number >= 0, got {}", ridge));
  if (!(smoothness >= 0) || !std::isfinite(smoothness))
    throw Error("--weights-smoothness", fmt::format("expected a finite number >= 0, got {}", smoothness));
  if (!csv && !jsonl) throw Error("--weights-format", "expected csv, jsonl or both");
}

ResidualUnit residual_unit(const Rig& rig, double millimetres_per_unit) {
  if (millimetres_per_unit > 0 && std::isfinite(millimetres_per_unit)) return {millimetres_per_unit, "mm"};
  return {1, rig.units.empty() ? "mesh units" : rig.units};
}

WeightsOutput::WeightsOutput(const Rig& rig, double millimetres_per_unit, const std::string& folder,
                             const WeightsOutputOptions& options)
    : rig_(rig), fit_(rig, weights_output_detail::fit_options(options)), csv_(options.csv), jsonl_(options.jsonl) {
  const ResidualUnit unit = retarget::residual_unit(rig, millimetres_per_unit);
  scale_ = unit.scale;
  residual_unit_ = unit.name;
  const std::filesystem::path dir(folder);
  try {
    if (csv_) {
      open(csv_file_, (dir / kCsvFile).string());
      csv_file_.out << "frame";
      for (const Controller& c : rig.controllers) csv_file_.out << ',' << weights_output_detail::csv_field(c.name);
      csv_file_.out << ",residual_mm\n";
      check(csv_file_);
    }
    if (jsonl_) open(jsonl_file_, (dir / kJsonlFile).string());
  } catch (...) {
    for (File* f : {&csv_file_, &jsonl_file_})
      if (!f->temporary.empty()) discard_temporary_file(f->temporary);
    throw;
  }
}

WeightsOutput::~WeightsOutput() {
  if (finished_) return;
  for (File* f : {&csv_file_, &jsonl_file_}) {
    if (f->temporary.empty()) continue;
    f->out.close();
    discard_temporary_file(f->temporary);
  }
}

void WeightsOutput::open(File& file, const std::string& path) {
  file.path = path;
  file.temporary = temporary_path_for(path);
  file.out.open(file.temporary, std::ios::binary | std::ios::trunc);
  if (!file.out) throw Error(path, "cannot write the file (" + file.temporary + " does not open)");
  files_.push_back(path);
}

void WeightsOutput::check(File& file) const {
  file.out.flush();
  if (!file.out) throw Error(file.path, "writing the file failed (disk full?)");
}

FrameWeights WeightsOutput::add(const std::string& frame, const Positions& avatar) {
  FrameWeights result;
  result.weights = fit_.fit(avatar, previous_);
  result.residual = fit_.residual(avatar, result.weights) * scale_;
  previous_ = result.weights;
  ++frames_;
  residual_sum_ += result.residual;
  residual_max_ = std::max(residual_max_, result.residual);

  if (csv_) {
    std::string row = weights_output_detail::csv_field(frame);
    for (Eigen::Index k = 0; k < result.weights.size(); ++k)
      row += "," + weights_output_detail::number(result.weights(k));
    row += "," + weights_output_detail::number(result.residual) + "\n";
    csv_file_.out << row;
    check(csv_file_);
  }
  if (jsonl_) {
    nlohmann::ordered_json weights = nlohmann::ordered_json::object();
    for (int k = 0; k < rig_.controller_count(); ++k) weights[rig_.controllers[k].name] = result.weights(k);
    const nlohmann::ordered_json line = {{"frame", frame}, {"weights", weights}, {"residual_mm", result.residual}};
    jsonl_file_.out << line.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace) << '\n';
    check(jsonl_file_);
  }
  return result;
}

void WeightsOutput::finish() {
  if (finished_) return;
  for (File* f : {&csv_file_, &jsonl_file_}) {
    if (f->temporary.empty()) continue;
    check(*f);
    f->out.close();
    if (!f->out) throw Error(f->path, "closing the file failed");
  }
  for (File* f : {&csv_file_, &jsonl_file_}) {
    if (f->temporary.empty()) continue;
    commit_temporary_file(f->temporary, f->path);
    f->temporary.clear();
  }
  finished_ = true;
}

}  // namespace retarget
