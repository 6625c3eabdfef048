#include "pipeline/evaluation_summary.h"

#include <fmt/format.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "core/error.h"

namespace retarget {

std::string evaluation_summary(const std::string& metrics_json) {
  if (!std::filesystem::exists(metrics_json)) return "";
  std::ifstream in(metrics_json);
  nlohmann::ordered_json metrics;  // the evaluation's own order: neutral, dt, dt_rig, then the methods as given
  try {
    metrics = nlohmann::ordered_json::parse(in);
  } catch (const std::exception& e) {
    throw Error(metrics_json, std::string("not the evaluation's JSON: ") + e.what());
  }
  if (!metrics.contains("sets") || !metrics["sets"].is_object())
    throw Error(metrics_json, "has no \"sets\" (written by `retarget eval retarget`?)");
  std::string text = fmt::format("the evaluation ({}), on people the training never saw:\n", metrics_json);
  for (const auto& [set, body] : metrics["sets"].items()) {
    text += fmt::format("  {} ({} faces)\n", set, body.value("samples", 0));
    text += fmt::format("    {:<18}{:>12}{:>12}{:>16}{:>12}{:>18}\n", "method", "moving mm", "x neutral", "rig weights",
                        "x neutral", "spread, people");
    for (const auto& [name, m] : body["methods"].items()) {
      text += fmt::format("    {:<18}{:>12.3f}{:>12.2f}{:>16.3f}{:>12.2f}{:>18.3f}\n", name, m.value("moving_mm", 0.0),
                          m.value("moving_fraction_of_neutral", 0.0), m.value("weight_error_active", 0.0),
                          m.value("weight_active_fraction_of_neutral", 0.0), m.value("identity_spread_mm", 0.0));
    }
  }
  return text;
}

}  // namespace retarget
