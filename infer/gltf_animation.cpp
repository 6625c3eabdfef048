// glTF 2.0 written directly as JSON (nlohmann_json) and one binary buffer: every accessor is
// FLOAT or UNSIGNED_INT, so every view starts 4-byte aligned with no padding, and what the
// Khronos validator checks (min/max equal to the stored floats, unit normals, strictly
// increasing times, F x C sampler outputs) is computed from the very floats that are stored.
#include "infer/gltf_animation.h"

#include <fmt/format.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <limits>
#include <nlohmann/json.hpp>
#include <set>

#include "core/atomic_file.h"
#include "core/error.h"

namespace retarget {

// Named, not anonymous: in a unity build (RETARGET_UNITY) the batch's files share one anonymous
// namespace, and these helpers' names are common ones.
namespace gltf_animation_detail {

using json = nlohmann::json;

constexpr int kArrayBuffer = 34962;         // bufferView.target for vertex attributes
constexpr int kElementArrayBuffer = 34963;  // bufferView.target for indices
constexpr int kFloat = 5126;
constexpr int kUnsignedInt = 5125;
constexpr int kTriangles = 4;

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

std::string base64(const std::string& bytes) {
  static const char* const alphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  size_t k = 0;
  for (; k + 2 < bytes.size(); k += 3) {
    const uint32_t v = (static_cast<uint8_t>(bytes[k]) << 16) | (static_cast<uint8_t>(bytes[k + 1]) << 8) |
                       static_cast<uint8_t>(bytes[k + 2]);
    out += alphabet[(v >> 18) & 63];
    out += alphabet[(v >> 12) & 63];
    out += alphabet[(v >> 6) & 63];
    out += alphabet[v & 63];
  }
  if (k < bytes.size()) {
    uint32_t v = static_cast<uint8_t>(bytes[k]) << 16;
    if (k + 1 < bytes.size()) v |= static_cast<uint8_t>(bytes[k + 1]) << 8;
    out += alphabet[(v >> 18) & 63];
    out += alphabet[(v >> 12) & 63];
    out += k + 1 < bytes.size() ? alphabet[(v >> 6) & 63] : '=';
    out += '=';
  }
  return out;
}

// The binary buffer and the JSON views and accessors over it, built side by side.
class GltfBuffer {
 public:
  // Appends count elements of `components` floats as one view and one FLOAT accessor; with
  // bounds, min/max per component (of the floats as stored). Returns the accessor's index.
  int add_floats(const std::vector<float>& values, int components, const char* type, int target, bool bounds) {
    const size_t count = values.size() / components;
    json accessor = {{"bufferView", add_view(values.data(), values.size() * sizeof(float), target)},
                     {"componentType", kFloat},
                     {"count", count},
                     {"type", type}};
    if (bounds) {
      std::vector<float> lo(components, std::numeric_limits<float>::infinity());
      std::vector<float> hi(components, -std::numeric_limits<float>::infinity());
      for (size_t e = 0; e < count; ++e)
        for (int j = 0; j < components; ++j) {
          lo[j] = std::min(lo[j], values[e * components + j]);
          hi[j] = std::max(hi[j], values[e * components + j]);
        }
      accessor["min"] = std::vector<double>(lo.begin(), lo.end());
      accessor["max"] = std::vector<double>(hi.begin(), hi.end());
    }
    accessors.push_back(std::move(accessor));
    return static_cast<int>(accessors.size()) - 1;
  }

  int add_indices(const std::vector<uint32_t>& values) {
    accessors.push_back({{"bufferView", add_view(values.data(), values.size() * sizeof(uint32_t), kElementArrayBuffer)},
                         {"componentType", kUnsignedInt},
                         {"count", values.size()},
                         {"type", "SCALAR"}});
    return static_cast<int>(accessors.size()) - 1;
  }

  std::string bytes;  // little-endian, as glTF stores it (the hosts this builds for are)
  json views = json::array();
  json accessors = json::array();

 private:
  int add_view(const void* data, size_t size, int target) {
    json view = {{"buffer", 0}, {"byteOffset", bytes.size()}, {"byteLength", size}};
    if (target != 0) view["target"] = target;
    bytes.append(static_cast<const char*>(data), size);
    views.push_back(std::move(view));
    return static_cast<int>(views.size()) - 1;
  }
};

// Area-weighted vertex normals of the triangles; a vertex on no (or only degenerate) triangles
// gets +z, since glTF requires every NORMAL to be unit length.
std::vector<float> vertex_normals(const Positions& v, const Triangles& t) {
  Positions n = Positions::Zero(v.rows(), 3);
  for (Eigen::Index k = 0; k < t.rows(); ++k) {
    const Eigen::RowVector3d a = v.row(t(k, 0)), b = v.row(t(k, 1)), c = v.row(t(k, 2));
    const Eigen::RowVector3d face = (b - a).cross(c - a);  // twice the area, along the normal
    for (int j = 0; j < 3; ++j) n.row(t(k, j)) += face;
  }
  std::vector<float> out(static_cast<size_t>(v.rows()) * 3);
  for (Eigen::Index i = 0; i < v.rows(); ++i) {
    const double length = n.row(i).norm();
    const Eigen::RowVector3d unit =
        length > 0 && std::isfinite(length) ? Eigen::RowVector3d(n.row(i) / length) : Eigen::RowVector3d(0, 0, 1);
    for (int j = 0; j < 3; ++j) out[i * 3 + j] = static_cast<float>(unit(j));
  }
  return out;
}

std::vector<float> scaled_floats(const Positions& p, double scale) {
  std::vector<float> out(static_cast<size_t>(p.rows()) * 3);
  for (Eigen::Index i = 0; i < p.rows(); ++i)
    for (int j = 0; j < 3; ++j) out[i * 3 + j] = static_cast<float>(p(i, j) * scale);
  return out;
}

// The checks write_gltf_animation promises, in the order a user would fix them.
void check_input(const GltfAnimationInput& in, const Mesh& mesh, const std::string& path) {
  const int v = mesh.vertex_count();
  const std::string what = mesh.source.empty() ? "the neutral mesh" : "the neutral mesh " + mesh.source;
  if (v == 0) throw Error(path, what + " has no vertices");
  if (mesh.triangle_count() == 0) throw Error(path, what + " has no faces");
  if (!mesh.vertices.allFinite()) throw Error(path, what + " has non-finite positions");
  for (Eigen::Index k = 0; k < mesh.triangles.rows(); ++k)
    for (int j = 0; j < 3; ++j)
      if (mesh.triangles(k, j) < 0 || mesh.triangles(k, j) >= v)
        throw Error(path,
                    fmt::format("{}: face {} names vertex {}, outside 0..{}", what,
                                mesh.triangle_face.empty() ? k : mesh.triangle_face[k], mesh.triangles(k, j), v - 1));

  const size_t c = in.controllers.size();
  if (c == 0) throw Error(path, "no controllers: a morph-target animation needs at least one");
  if (in.offsets.size() != c)
    throw Error(
        path, fmt::format("{} controller names but {} offsets; give one offset per controller", c, in.offsets.size()));
  std::set<std::string> seen;
  for (size_t k = 0; k < c; ++k) {
    const std::string& name = in.controllers[k];
    if (name.empty()) throw Error(path, fmt::format("controller {} has an empty name", k));
    if (!seen.insert(name).second) throw Error(path, fmt::format("controller name \"{}\" appears twice", name));
    const Positions& offset = in.offsets[k];
    if (offset.rows() != v)
      throw Error(path, fmt::format("controller \"{}\": offsets for {} vertices, but the neutral mesh has {}", name,
                                    offset.rows(), v));
    if (!offset.allFinite()) throw Error(path, fmt::format("controller \"{}\" has non-finite offsets", name));
  }

  if (in.weights.empty()) throw Error(path, "no frames of weights");
  for (size_t f = 0; f < in.weights.size(); ++f) {
    const Eigen::VectorXd& w = in.weights[f];
    if (static_cast<size_t>(w.size()) != c)
      throw Error(path, fmt::format("frame {} has {} weights but there are {} controllers", f, w.size(), c));
    for (size_t k = 0; k < c; ++k)
      if (!std::isfinite(w(k)))
        throw Error(path, fmt::format("frame {}: the weight of controller \"{}\" is not finite ({})", f,
                                      in.controllers[k], w(k)));
  }
  if (!in.times.empty()) {
    if (in.times.size() != in.weights.size())
      throw Error(path, fmt::format("{} times for {} frames; give one time per frame (or none, to use fps)",
                                    in.times.size(), in.weights.size()));
    for (size_t f = 0; f < in.times.size(); ++f) {
      const double t = in.times[f];
      if (!std::isfinite(t) || t < 0)
        throw Error(path, fmt::format("frame {}: time {} s; expected a finite number of seconds >= 0", f, t));
      if (f > 0 && !(t > in.times[f - 1]))
        throw Error(path, fmt::format("frame {}: time {} s does not come after frame {}'s {} s; times must increase", f,
                                      t, f - 1, in.times[f - 1]));
    }
  }
}

}  // namespace gltf_animation_detail

void GltfAnimationOptions::validate() const {
  if (!(fps >= 1e-3 && fps <= 1e5))
    throw Error("gltf_animation.fps", fmt::format("expected frames per second from 0.001 to 100000, got {}", fps));
  if (scale_to_metres && (!(*scale_to_metres > 0) || !std::isfinite(*scale_to_metres)))
    throw Error("gltf_animation.scale_to_metres",
                fmt::format("expected a positive number of metres per unit (0.01 for cm), got {}", *scale_to_metres));
  if (mesh_name.empty()) throw Error("gltf_animation.mesh_name", "expected a name");
  if (animation_name.empty()) throw Error("gltf_animation.animation_name", "expected a name");
}

GltfAnimationInput gltf_animation_input(const Rig& rig, std::vector<Eigen::VectorXd> weights,
                                        std::vector<double> times) {
  GltfAnimationInput in;
  in.neutral = rig.neutral;
  if (in.neutral.source.empty()) in.neutral.source = rig.source;
  for (const Controller& c : rig.controllers) {
    in.controllers.push_back(c.name);
    in.offsets.push_back(c.offset);
  }
  in.weights = std::move(weights);
  in.times = std::move(times);
  in.units = rig.units;
  return in;
}

double gltf_scale_to_metres(const std::string& units, const GltfAnimationOptions& options) {
  using namespace gltf_animation_detail;
  if (options.scale_to_metres) return *options.scale_to_metres;
  const std::string u = lower(units);
  if (u == "m" || u == "metres" || u == "meters") return 1;
  if (u == "cm" || u == "centimetres" || u == "centimeters") return 0.01;
  if (u == "mm" || u == "millimetres" || u == "millimeters") return 0.001;
  if (u.empty()) return 1;
  throw Error("gltf_animation.scale_to_metres",
              fmt::format("the mesh's units \"{}\" are not cm, mm or m; give the metres per unit", units));
}

GltfAnimationSummary write_gltf_animation(const GltfAnimationInput& input, const GltfAnimationOptions& options,
                                          const std::string& path) {
  using namespace gltf_animation_detail;
  options.validate();
  const std::string extension = lower(std::filesystem::path(path).extension().string());
  if (extension != ".glb" && extension != ".gltf")
    throw Error(path, "expected a file name ending in .glb (binary glTF) or .gltf (JSON, buffer embedded)");
  const bool binary = extension == ".glb";

  Mesh mesh = input.neutral;
  if (mesh.triangle_count() == 0 && mesh.faces.size() > 0) {
    for (int f = 0; f < mesh.faces.size(); ++f) {
      if (mesh.faces.degree(f) < 3)
        throw Error(path, fmt::format("the neutral mesh: face {} has {} vertices; faces need at least 3", f,
                                      mesh.faces.degree(f)));
      for (int k = 0; k < mesh.faces.degree(f); ++k)
        if (mesh.faces.begin(f)[k] < 0 || mesh.faces.begin(f)[k] >= mesh.vertex_count())
          throw Error(path, fmt::format("the neutral mesh: face {} names vertex {}, outside 0..{}", f,
                                        mesh.faces.begin(f)[k], mesh.vertex_count() - 1));
    }
    triangulate(mesh);
  }
  check_input(input, mesh, path);
  const double scale = gltf_scale_to_metres(input.units, options);

  const size_t frames = input.weights.size();
  const size_t c = input.controllers.size();
  std::vector<float> times(frames);
  auto time = [&](size_t f) { return input.times.empty() ? static_cast<double>(f) / options.fps : input.times[f]; };
  // glTF stores 32-bit floats; a double beyond their range is checked before the cast (which would
  // be undefined behaviour), not after.
  constexpr double kFloatMax = std::numeric_limits<float>::max();
  for (size_t f = 0; f < frames; ++f) {
    if (!(std::abs(time(f)) <= kFloatMax))
      throw Error(path, fmt::format("frame {}: the time {} s is beyond what glTF's 32-bit floats hold", f, time(f)));
    times[f] = static_cast<float>(time(f));
    if (f > 0 && !(times[f] > times[f - 1]))
      throw Error(path, fmt::format("frames {} and {} ({} s and {} s) are the same time once stored as float; "
                                    "glTF needs strictly increasing times",
                                    f - 1, f, time(f - 1), time(f)));
  }
  std::vector<float> weights(frames * c);
  for (size_t f = 0; f < frames; ++f)
    for (size_t k = 0; k < c; ++k) {
      if (!(std::abs(input.weights[f](k)) <= kFloatMax))
        throw Error(path, fmt::format("frame {}: the weight {} of controller \"{}\" is beyond what glTF's 32-bit "
                                      "floats hold",
                                      f, input.weights[f](k), input.controllers[k]));
      weights[f * c + k] = static_cast<float>(input.weights[f](k));
    }

  // glTF caps a GLB at 4 GiB (uint32 lengths); refuse before allocating.
  const double v = mesh.vertex_count();
  const double bytes_needed =
      v * 12 * (2.0 + c) + mesh.triangle_count() * 12.0 + frames * 4.0 + static_cast<double>(frames) * c * 4;
  if (bytes_needed > 4.0e9)
    throw Error(path, fmt::format("{} vertices x {} controllers and {} frames need {:.1f} GB, more than glTF's 4 GB",
                                  mesh.vertex_count(), c, frames, bytes_needed / 1e9));

  GltfBuffer buffer;
  const int position = buffer.add_floats(scaled_floats(mesh.vertices, scale), 3, "VEC3", kArrayBuffer, true);
  const Positions scaled = mesh.vertices * scale;
  const int normal = buffer.add_floats(vertex_normals(scaled, mesh.triangles), 3, "VEC3", kArrayBuffer, false);
  std::vector<uint32_t> corners(mesh.triangles.data(), mesh.triangles.data() + mesh.triangles.size());
  const int indices = buffer.add_indices(corners);
  json targets = json::array();
  for (size_t k = 0; k < c; ++k)
    targets.push_back(
        {{"POSITION", buffer.add_floats(scaled_floats(input.offsets[k], scale), 3, "VEC3", kArrayBuffer, true)}});
  const int time_accessor = buffer.add_floats(times, 1, "SCALAR", 0, true);
  const int weight_accessor = buffer.add_floats(weights, 1, "SCALAR", 0, false);

  json gltf = {
      {"asset", {{"version", "2.0"}, {"generator", std::string("retarget ") + RETARGET_VERSION}}},
      {"scene", 0},
      {"scenes", {{{"nodes", {0}}}}},
      {"nodes", {{{"name", options.mesh_name}, {"mesh", 0}}}},
      {"meshes",
       {{{"name", options.mesh_name},
         {"primitives",
          {{{"attributes", {{"POSITION", position}, {"NORMAL", normal}}},
            {"indices", indices},
            {"mode", kTriangles},
            {"targets", targets}}}},
         {"weights", std::vector<double>(c, 0.0)},
         {"extras", {{"targetNames", input.controllers}}}}}},
      {"animations",
       {{{"name", options.animation_name},
         {"channels", {{{"sampler", 0}, {"target", {{"node", 0}, {"path", "weights"}}}}}},
         {"samplers", {{{"input", time_accessor}, {"output", weight_accessor}, {"interpolation", "LINEAR"}}}}}}},
      {"accessors", std::move(buffer.accessors)},
      {"bufferViews", std::move(buffer.views)},
  };
  json buffer_json = {{"byteLength", buffer.bytes.size()}};
  if (!binary) buffer_json["uri"] = "data:application/octet-stream;base64," + base64(buffer.bytes);
  gltf["buffers"] = json::array({std::move(buffer_json)});

  std::string text;
  try {
    text = binary ? gltf.dump() : gltf.dump(1);
  } catch (const json::type_error& e) {
    // nlohmann refuses invalid UTF-8: a controller or option name with other bytes.
    throw Error(path, std::string("a controller, mesh or animation name is not valid UTF-8 (") + e.what() + ")");
  }

  size_t written = 0;
  write_file_atomically(path, [&](std::ostream& out) {
    if (!binary) {
      out << text << '\n';
      written = text.size() + 1;
      return;
    }
    // GLB: a 12-byte header, the JSON chunk (padded with spaces) and the BIN chunk (padded with
    // zeros), each chunk's length a multiple of 4.
    text.append((4 - text.size() % 4) % 4, ' ');
    std::string& bin = buffer.bytes;
    bin.append((4 - bin.size() % 4) % 4, '\0');
    const uint32_t total = static_cast<uint32_t>(12 + 8 + text.size() + 8 + bin.size());
    auto u32 = [&out](uint32_t value) {
      char b[4];
      std::memcpy(b, &value, 4);
      out.write(b, 4);
    };
    u32(0x46546C67);  // "glTF"
    u32(2);
    u32(total);
    u32(static_cast<uint32_t>(text.size()));
    u32(0x4E4F534A);  // "JSON"
    out.write(text.data(), static_cast<std::streamsize>(text.size()));
    u32(static_cast<uint32_t>(bin.size()));
    u32(0x004E4942);  // "BIN\0"
    out.write(bin.data(), static_cast<std::streamsize>(bin.size()));
    written = total;
  });

  GltfAnimationSummary summary;
  summary.vertices = mesh.vertex_count();
  summary.triangles = mesh.triangle_count();
  summary.controllers = static_cast<int>(c);
  summary.frames = static_cast<int>(frames);
  summary.duration = times.back();
  summary.scale_to_metres = scale;
  summary.bytes = written;
  return summary;
}

}  // namespace retarget
