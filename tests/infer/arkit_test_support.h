// Shared pieces of the ARKit take tests: a small face model on the runtime tests' human patch
// (so that its faces go through the tiny bundle), with expressions named as the ICT model names
// them, the Live Link spelling of those names, takes written as CSV and JSON lines, and a log
// capture.
#pragma once

#include <fmt/format.h>

#include <cctype>
#include <cmath>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "core/log.h"
#include "geometry/face_model.h"
#include "tests/infer/infer_test_support.h"

namespace retarget::test {

// ICT-style names (the model sorts them like the ICT model and the synthetic human).
inline const std::vector<std::string>& arkit_test_names() {
  static const std::vector<std::string> names = {"browInnerUp_L", "browInnerUp_R", "cheekPuff_L",  "cheekPuff_R",
                                                 "eyeBlink_L",    "eyeBlink_R",    "jawOpen",      "mouthLeft",
                                                 "mouthPucker",   "mouthRight",    "mouthSmile_L", "mouthSmile_R"};
  return names;
}

// A smooth offset field over the patch, different for every `k`: small enough (<= 0.08 of a
// 2 x 2.4 patch) that the tiny bundle's features stay in range.
inline Positions smooth_offset(const Mesh& mesh, int k) {
  Positions offset(mesh.vertex_count(), 3);
  for (int v = 0; v < mesh.vertex_count(); ++v) {
    const double x = mesh.vertices(v, 0), y = mesh.vertices(v, 1);
    offset(v, 0) = 0.02 * std::sin(1.3 * x + 0.7 * k) * std::cos(0.9 * y);
    offset(v, 1) = 0.02 * std::cos(0.8 * x * (k % 3 + 1) + y);
    offset(v, 2) = 0.04 * std::exp(-(x - 0.2 * k) * (x - 0.2 * k) - y * y);
  }
  return offset;
}

// The model: neutral = human_patch() (the tiny bundle's human rest), 2 identity modes, the 12
// expressions of arkit_test_names(); units cm.
inline FaceModel arkit_test_model() {
  FaceModel model;
  model.name = "patch-model";
  model.source = "patch-model.yaml";
  model.units = "cm";
  model.neutral = human_patch();
  for (int i = 0; i < 2; ++i)
    model.identities.push_back({"identity" + std::to_string(i), 0.5 * smooth_offset(model.neutral, 20 + i)});
  const std::vector<std::string>& names = arkit_test_names();
  for (int k = 0; k < static_cast<int>(names.size()); ++k)
    model.expressions.push_back({names[k], smooth_offset(model.neutral, k)});
  return model;
}

// "eyeBlink_L" -> "EyeBlinkLeft", "jawOpen" -> "JawOpen" (Live Link Face's spelling).
inline std::string live_link_name(const std::string& name) {
  std::string out = name;
  out[0] = static_cast<char>(std::toupper(static_cast<unsigned char>(out[0])));
  if (out.size() > 2 && out.compare(out.size() - 2, 2, "_L") == 0) out = out.substr(0, out.size() - 2) + "Left";
  if (out.size() > 2 && out.compare(out.size() - 2, 2, "_R") == 0) out = out.substr(0, out.size() - 2) + "Right";
  return out;
}

// Frame f's weights by expression name: a few expressions per frame, in [0, 1], some exactly 0 or 1.
inline std::vector<std::map<std::string, double>> arkit_test_frames(int frames) {
  const std::vector<std::string>& names = arkit_test_names();
  std::vector<std::map<std::string, double>> out(frames);
  for (int f = 0; f < frames; ++f)
    for (int k = 0; k < static_cast<int>(names.size()); ++k) {
      if ((f + k) % 3 == 0) continue;
      const double w = (f + k) % 5 == 0 ? 1.0 : 0.5 + 0.5 * std::sin(0.37 * f + 1.1 * k + 0.1);
      out[f][names[k]] = w;
    }
  return out;
}

// Timecodes as Live Link writes them.
inline std::string live_link_timecode(int frame) {
  return fmt::format("12:34:{:02d}:{:02d}.{:03d}", frame / 60, frame % 60, 7 * frame % 1000);
}

// A Live Link Face CSV of `frames` (every expression a column in Live Link's spelling, then the
// head rotation columns), weights written with 17 significant digits (exact round trip).
inline std::string live_link_csv(const std::vector<std::map<std::string, double>>& frames) {
  std::string text = "Timecode,BlendShapeCount";
  for (const std::string& name : arkit_test_names()) text += "," + live_link_name(name);
  text += ",HeadYaw,HeadPitch,HeadRoll\n";
  for (size_t f = 0; f < frames.size(); ++f) {
    text += live_link_timecode(static_cast<int>(f)) + "," + std::to_string(arkit_test_names().size());
    for (const std::string& name : arkit_test_names()) {
      const auto it = frames[f].find(name);
      text += fmt::format(",{:.17g}", it == frames[f].end() ? 0.0 : it->second);
    }
    text += ",0.1,-0.2,0.3\n";
  }
  return text;
}

// JSON lines of `frames` in the nested form with the model's own (ICT) names, only the non-zero weights.
inline std::string ict_jsonl(const std::vector<std::map<std::string, double>>& frames) {
  std::string text;
  for (size_t f = 0; f < frames.size(); ++f) {
    std::string weights;
    for (const auto& [name, w] : frames[f])
      weights += fmt::format("{}\"{}\": {:.17g}", weights.empty() ? "" : ", ", name, w);
    text += fmt::format("{{\"timecode\": \"{}\", \"weights\": {{{}}}}}\n", live_link_timecode(static_cast<int>(f)),
                        weights);
  }
  return text;
}

// The log lines written while it lives (level info and above).
struct LogCapture {
  std::vector<std::pair<log::Level, std::string>> lines;
  log::Sink previous;
  log::Level previous_level = log::level();

  LogCapture() {
    log::set_level(log::Level::info);
    previous =
        log::set_sink([this](log::Level level, const std::string& message) { lines.emplace_back(level, message); });
  }
  ~LogCapture() {
    log::set_sink(previous);
    log::set_level(previous_level);
  }
  // How many lines of `level` contain `text`.
  int count(log::Level level, const std::string& text) const {
    int n = 0;
    for (const auto& [l, message] : lines) n += l == level && message.find(text) != std::string::npos;
    return n;
  }
};

}  // namespace retarget::test
