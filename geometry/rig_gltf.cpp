// glTF 2.0 morph-target rigs through tinygltf (Debian's shared library; its implementation is
// compiled there, so TINYGLTF_IMPLEMENTATION is not defined here).
#include <tiny_gltf.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <set>

#include "core/error.h"
#include "geometry/mesh_validation.h"
#include "geometry/rig.h"
#include "geometry/rig_parts.h"

namespace retarget {

namespace fs = std::filesystem;

namespace gltf_detail {
// What to do about compressed geometry, the end of every message about it.
constexpr const char* kDecompressHint =
    "re-export the avatar without mesh compression (Blender's glTF exporter: untick Compression; Ready Player Me: "
    "leave meshCompression and useMeshOptCompression off), or decompress it with a glTF tool such as gltf-transform "
    "or gltf-pipeline";
}  // namespace gltf_detail

namespace {

// The largest dense storage ((targets + 1) x vertices x 3 doubles) a glTF rig may ask for.
constexpr double kMaxDenseBytes = 2.0 * (1ull << 30);

// Images are irrelevant to a rig: skip decoding them (and any dependency on stb_image).
bool skip_image(tinygltf::Image*, const int, std::string*, std::string*, int, int, const unsigned char*, int, void*) {
  return true;
}

std::string mesh_label(const tinygltf::Model& model, int m) {
  const std::string& name = model.meshes[m].name;
  return name.empty() ? "#" + std::to_string(m) : "\"" + name + "\"";
}

int target_count(const tinygltf::Mesh& mesh) {
  return mesh.primitives.empty() ? 0 : static_cast<int>(mesh.primitives[0].targets.size());
}

std::string mode_name(int mode) {
  switch (mode) {
    case TINYGLTF_MODE_POINTS:
      return "points";
    case TINYGLTF_MODE_LINE:
      return "lines";
    case TINYGLTF_MODE_LINE_LOOP:
      return "line loop";
    case TINYGLTF_MODE_LINE_STRIP:
      return "line strip";
    case TINYGLTF_MODE_TRIANGLE_STRIP:
      return "triangle strip";
    case TINYGLTF_MODE_TRIANGLE_FAN:
      return "triangle fan";
    default:
      return "mode " + std::to_string(mode);
  }
}

// What an accessor feeds, for the component types glTF 2.0 allows it (3.7.2.1 and 3.7.2.2):
// POSITION and morph target POSITION deltas are FLOAT VEC3; with KHR_mesh_quantization also
// (normalised or plain) BYTE/UNSIGNED_BYTE/SHORT/UNSIGNED_SHORT positions and BYTE/SHORT deltas.
// Indices are UNSIGNED_BYTE/SHORT/INT SCALAR, never normalised.
enum class Role { position, morph_delta, indices };

std::string component_name(int type) {
  switch (type) {
    case TINYGLTF_COMPONENT_TYPE_BYTE:
      return "BYTE";
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
      return "UNSIGNED_BYTE";
    case TINYGLTF_COMPONENT_TYPE_SHORT:
      return "SHORT";
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT:
      return "UNSIGNED_SHORT";
    case TINYGLTF_COMPONENT_TYPE_INT:
      return "INT";
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
      return "UNSIGNED_INT";
    case TINYGLTF_COMPONENT_TYPE_FLOAT:
      return "FLOAT";
    case TINYGLTF_COMPONENT_TYPE_DOUBLE:
      return "DOUBLE";
    default:
      return "component type " + std::to_string(type);
  }
}

std::string type_name(int type) {
  switch (type) {
    case TINYGLTF_TYPE_SCALAR:
      return "SCALAR";
    case TINYGLTF_TYPE_VEC2:
      return "VEC2";
    case TINYGLTF_TYPE_VEC3:
      return "VEC3";
    case TINYGLTF_TYPE_VEC4:
      return "VEC4";
    case TINYGLTF_TYPE_MAT2:
      return "MAT2";
    case TINYGLTF_TYPE_MAT3:
      return "MAT3";
    case TINYGLTF_TYPE_MAT4:
      return "MAT4";
    default:
      return "type " + std::to_string(type);
  }
}

bool is_index_type(int type) {
  return type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE || type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT ||
         type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT;
}

// The JSON text of a .gltf file or a GLB's JSON chunk (at most 64 MiB of it).
std::string gltf_json_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::string json;
  char header[20];
  if (in.read(header, 20) && std::memcmp(header, "glTF", 4) == 0 && std::memcmp(header + 16, "JSON", 4) == 0) {
    uint32_t length = 0;
    std::memcpy(&length, header + 12, 4);
    json.resize(std::min<uint32_t>(length, 64u << 20));
    in.read(json.data(), static_cast<std::streamsize>(json.size()));
    json.resize(static_cast<size_t>(std::max<std::streamsize>(in.gcount(), 0)));
  } else {
    in.clear();
    in.seekg(0);
    json.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  return json;
}

// accessors[index].sparse.count as the file writes it (tinygltf reads it into an int, so 2^31
// arrives as -2^31); "?" when it cannot be found.
std::string raw_sparse_count(const std::string& path, int index) {
  try {
    const nlohmann::json root = nlohmann::json::parse(gltf_json_text(path));
    return root.at("accessors").at(static_cast<size_t>(index)).at("sparse").at("count").dump();
  } catch (const std::exception&) {
    return "?";
  }
}

// Reads accessors into doubles. Every count, offset and stride is checked against its buffer
// view and buffer before anything is allocated, so a hand-made, truncated or hostile file gets
// a message naming the accessor instead of an over-read or std::bad_alloc.
class AccessorReader {
 public:
  AccessorReader(const tinygltf::Model& model, std::string path) : model_(model), path_(std::move(path)) {
    const auto& used = model.extensionsUsed;
    quantized_ = std::find(used.begin(), used.end(), "KHR_mesh_quantization") != used.end();
  }

  // Accessor `index` checked for `role` (type, component type, normalized, count, and the
  // bytes its buffer view, byteOffset, stride and sparse storage span); no data is read.
  // `what` names the accessor's role for messages ("mesh \"Face\" primitive 0 POSITION").
  const tinygltf::Accessor& checked(int index, Role role, const std::string& what) const {
    if (index < 0 || index >= static_cast<int>(model_.accessors.size()))
      fail(what + ": accessor " + std::to_string(index) + " does not exist");
    const tinygltf::Accessor& a = model_.accessors[index];
    const std::string where = what + " (accessor " + std::to_string(index) + ")";
    const int type = role == Role::indices ? TINYGLTF_TYPE_SCALAR : TINYGLTF_TYPE_VEC3;
    if (a.type != type) fail(where + ": expected " + type_name(type) + " elements, got " + type_name(a.type));
    const int c = a.componentType;
    bool allowed = false;
    std::string expected;
    switch (role) {
      case Role::position:
        allowed = c == TINYGLTF_COMPONENT_TYPE_FLOAT ||
                  (quantized_ && (c == TINYGLTF_COMPONENT_TYPE_BYTE || c == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE ||
                                  c == TINYGLTF_COMPONENT_TYPE_SHORT || c == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT));
        expected = quantized_ ? "FLOAT, BYTE, UNSIGNED_BYTE, SHORT or UNSIGNED_SHORT (KHR_mesh_quantization)"
                              : "FLOAT (glTF 2.0; integer positions need the KHR_mesh_quantization extension)";
        break;
      case Role::morph_delta:
        allowed = c == TINYGLTF_COMPONENT_TYPE_FLOAT ||
                  (quantized_ && (c == TINYGLTF_COMPONENT_TYPE_BYTE || c == TINYGLTF_COMPONENT_TYPE_SHORT));
        expected = quantized_ ? "FLOAT, BYTE or SHORT (KHR_mesh_quantization)"
                              : "FLOAT (glTF 2.0; integer deltas need the KHR_mesh_quantization extension)";
        break;
      case Role::indices:
        allowed = is_index_type(c);
        expected = "UNSIGNED_BYTE, UNSIGNED_SHORT or UNSIGNED_INT";
        break;
    }
    if (!allowed) fail(where + ": components are " + component_name(c) + "; expected " + expected);
    if (a.normalized && (role == Role::indices || c == TINYGLTF_COMPONENT_TYPE_FLOAT))
      fail(where +
           ": normalized is set, which glTF allows only for BYTE, UNSIGNED_BYTE, SHORT and UNSIGNED_SHORT "
           "vertex data, not " +
           component_name(c) + (role == Role::indices ? " indices" : ""));
    if (a.count == 0) fail(where + ": count 0; glTF requires at least 1 element");
    if (a.count > static_cast<size_t>(std::numeric_limits<int>::max()))
      fail(where + ": count " + std::to_string(a.count) + " is more than " +
           std::to_string(std::numeric_limits<int>::max()) + " elements");
    const size_t size = static_cast<size_t>(tinygltf::GetComponentSizeInBytes(static_cast<uint32_t>(c)));
    const size_t element = size * (role == Role::indices ? 1 : 3);
    if (a.bufferView >= 0) {
      span(a.bufferView, a.byteOffset, a.count, element, size, role != Role::indices, where);
    } else if (role != Role::morph_delta || !a.sparse.isSparse) {
      // Morph deltas may be all zeros (no buffer view) with sparse changes; positions and
      // indices without data mean nothing.
      if (role != Role::morph_delta) fail(where + ": no buffer view: the accessor holds no data");
    }
    if (a.sparse.isSparse) {
      if (role == Role::indices) fail(where + ": sparse index accessors are not supported");
      const auto& sparse = a.sparse;
      if (sparse.count < 1 || static_cast<size_t>(sparse.count) > a.count)
        fail(where + ": sparse count " + raw_sparse_count(path_, index) + " is outside 1.." + std::to_string(a.count));
      if (!is_index_type(sparse.indices.componentType))
        fail(where + ": sparse indices are " + component_name(sparse.indices.componentType) +
             "; expected UNSIGNED_BYTE, UNSIGNED_SHORT or UNSIGNED_INT");
      if (sparse.indices.byteOffset < 0 || sparse.values.byteOffset < 0) fail(where + ": negative sparse byteOffset");
      const size_t index_size =
          static_cast<size_t>(tinygltf::GetComponentSizeInBytes(static_cast<uint32_t>(sparse.indices.componentType)));
      span(sparse.indices.bufferView, static_cast<size_t>(sparse.indices.byteOffset), sparse.count, index_size,
           index_size, false, where + " sparse indices", true);
      span(sparse.values.bufferView, static_cast<size_t>(sparse.values.byteOffset), sparse.count, element, size, false,
           where + " sparse values", true);
    }
    return a;
  }

  // count x components values (3 for positions and deltas, 1 for indices), after checked().
  // Normalised integers map to [-1, 1] or [0, 1]; non-finite values are refused.
  Eigen::MatrixXd read(int index, Role role, const std::string& what) const {
    const tinygltf::Accessor& a = checked(index, role, what);
    const std::string where = what + " (accessor " + std::to_string(index) + ")";
    const int components = role == Role::indices ? 1 : 3;
    const size_t size = static_cast<size_t>(tinygltf::GetComponentSizeInBytes(static_cast<uint32_t>(a.componentType)));
    const size_t element = size * components;
    Eigen::MatrixXd values = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(a.count), components);
    if (a.bufferView >= 0) {
      const tinygltf::BufferView& bv = model_.bufferViews[a.bufferView];
      const size_t stride = bv.byteStride != 0 && role != Role::indices ? bv.byteStride : element;
      const unsigned char* base =
          span(a.bufferView, a.byteOffset, a.count, element, size, role != Role::indices, where);
      decode(base, stride, a.count, components, a.componentType, a.normalized, values, where);
    }
    if (a.sparse.isSparse) {
      const auto& sparse = a.sparse;
      const int index_type = sparse.indices.componentType;
      const size_t index_size =
          static_cast<size_t>(tinygltf::GetComponentSizeInBytes(static_cast<uint32_t>(index_type)));
      const unsigned char* rows = span(sparse.indices.bufferView, static_cast<size_t>(sparse.indices.byteOffset),
                                       sparse.count, index_size, index_size, false, where + " sparse indices", true);
      Eigen::MatrixXd replaced(sparse.count, components);
      const unsigned char* base = span(sparse.values.bufferView, static_cast<size_t>(sparse.values.byteOffset),
                                       sparse.count, element, size, false, where + " sparse values", true);
      decode(base, element, sparse.count, components, a.componentType, a.normalized, replaced,
             where + " sparse values");
      double previous = -1;
      for (int k = 0; k < sparse.count; ++k) {
        const double row = component(rows + k * index_size, index_type, false);
        if (row >= static_cast<double>(a.count))
          fail(where + ": sparse index " + std::to_string(static_cast<uint64_t>(row)) + " (entry " + std::to_string(k) +
               ") is out of range (" + std::to_string(a.count) + " elements)");
        if (row <= previous)
          fail(where + ": sparse indices must increase strictly; entry " + std::to_string(k) + " is " +
               std::to_string(static_cast<uint64_t>(row)) + " after " +
               std::to_string(static_cast<uint64_t>(previous)));
        previous = row;
        values.row(static_cast<Eigen::Index>(row)) = replaced.row(k);
      }
    }
    return values;
  }

  // Vertex indices of a primitive, each checked against `vertex_count`.
  std::vector<int> indices(int index, int vertex_count, const std::string& what) const {
    const Eigen::MatrixXd values = read(index, Role::indices, what);
    std::vector<int> out(values.rows());
    for (Eigen::Index k = 0; k < values.rows(); ++k) {
      if (values(k, 0) >= vertex_count)
        fail(what + " (accessor " + std::to_string(index) + "): index " +
             std::to_string(static_cast<uint64_t>(values(k, 0))) + " (entry " + std::to_string(k) +
             ") is out of range (the primitive has " + std::to_string(vertex_count) + " vertices)");
      out[k] = static_cast<int>(values(k, 0));
    }
    return out;
  }

  [[noreturn]] void fail(const std::string& message) const { throw Error(path_, message); }

  // Whether the file lists `extension` in extensionsRequired.
  bool required(const std::string& extension) const {
    const auto& list = model_.extensionsRequired;
    return std::find(list.begin(), list.end(), extension) != list.end();
  }

 private:
  // The first byte of `count` elements of `element` bytes, `stride` apart (the view's
  // byteStride when `strided` and set, else packed), from `offset` into buffer view `view_index`,
  // after checking that they lie inside the view and the view inside its buffer. `component`:
  // the alignment glTF requires of offset. Sparse storage (`sparse`) is always packed.
  const unsigned char* span(int view_index, size_t offset, size_t count, size_t element, size_t component, bool strided,
                            const std::string& where, bool sparse = false) const {
    if (view_index < 0 || view_index >= static_cast<int>(model_.bufferViews.size()))
      fail(where + ": buffer view " + std::to_string(view_index) + " does not exist");
    const tinygltf::BufferView& bv = model_.bufferViews[view_index];
    const std::string view = "buffer view " + std::to_string(view_index);
    if (bv.buffer < 0 || bv.buffer >= static_cast<int>(model_.buffers.size()))
      fail(where + ": " + view + " names buffer " + std::to_string(bv.buffer) + ", which does not exist");
    // meshopt: the view's own bytes are an uncompressed fallback only when the file does not
    // require the extension and the buffer is not a placeholder (its own extension, no data).
    for (const char* meshopt : {"EXT_meshopt_compression", "KHR_meshopt_compression"})
      if (bv.extensions.count(meshopt) && (required(meshopt) || model_.buffers[bv.buffer].extensions.count(meshopt) ||
                                           model_.buffers[bv.buffer].data.empty()))
        fail(where + ": " + view + " is meshopt-compressed (" + meshopt + "), which is not supported; " +
             gltf_detail::kDecompressHint);
    const size_t buffer = model_.buffers[bv.buffer].data.size();
    if (bv.byteLength > buffer || bv.byteOffset > buffer - bv.byteLength)
      fail(where + ": " + view + " (byteOffset " + std::to_string(bv.byteOffset) + ", byteLength " +
           std::to_string(bv.byteLength) + ") reaches past the end of buffer " + std::to_string(bv.buffer) + " (" +
           std::to_string(buffer) + " bytes)");
    if (offset % component != 0)
      fail(where + ": byteOffset " + std::to_string(offset) + " is not a multiple of the component size " +
           std::to_string(component));
    size_t stride = element;
    if (!sparse && bv.byteStride != 0) {
      if (bv.byteStride < element || bv.byteStride > 252 || (strided && bv.byteStride % 4 != 0))
        fail(where + ": " + view + " has byteStride " + std::to_string(bv.byteStride) + "; expected " +
             (strided ? "a multiple of 4 " : "") + "between the element size " + std::to_string(element) + " and 252");
      if (strided) stride = bv.byteStride;
    }
    if (offset > bv.byteLength || element > bv.byteLength - offset ||
        count - 1 > (bv.byteLength - offset - element) / stride)
      fail(where + ": " + std::to_string(count) + " elements of " + std::to_string(element) + " bytes, " +
           std::to_string(stride) + " bytes apart from byteOffset " + std::to_string(offset) +
           ", reach past the end of " + view + " (" + std::to_string(bv.byteLength) + " bytes)");
    return model_.buffers[bv.buffer].data.data() + bv.byteOffset + offset;
  }

  // count elements from base, stride bytes apart, into out(e, j); floats must be finite.
  void decode(const unsigned char* base, size_t stride, size_t count, int components, int type, bool normalized,
              Eigen::MatrixXd& out, const std::string& where) const {
    const size_t size = static_cast<size_t>(tinygltf::GetComponentSizeInBytes(static_cast<uint32_t>(type)));
    for (size_t e = 0; e < count; ++e)
      for (int j = 0; j < components; ++j) {
        const double value = component(base + e * stride + j * size, type, normalized);
        if (!std::isfinite(value))
          fail(where + ": element " + std::to_string(e) + " has a non-finite value (" + std::string(1, "xyz"[j]) +
               " = " + std::to_string(value) + ")");
        out(static_cast<Eigen::Index>(e), j) = value;
      }
  }

  static double component(const unsigned char* p, int type, bool normalized) {
    // memcpy: glTF data need not be aligned for the host.
    auto get = [p](auto value) {
      std::memcpy(&value, p, sizeof(value));
      return value;
    };
    switch (type) {
      case TINYGLTF_COMPONENT_TYPE_FLOAT:
        return get(float{});
      case TINYGLTF_COMPONENT_TYPE_BYTE: {
        const double v = get(int8_t{});
        return normalized ? std::max(v / 127.0, -1.0) : v;
      }
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: {
        const double v = get(uint8_t{});
        return normalized ? v / 255.0 : v;
      }
      case TINYGLTF_COMPONENT_TYPE_SHORT: {
        const double v = get(int16_t{});
        return normalized ? std::max(v / 32767.0, -1.0) : v;
      }
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
        const double v = get(uint16_t{});
        return normalized ? v / 65535.0 : v;
      }
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
        return get(uint32_t{});
      default:
        return 0;  // unreachable: checked() allows no other type
    }
  }

  const tinygltf::Model& model_;
  std::string path_;
  bool quantized_ = false;
};

// Target names: mesh.extras.targetNames (Blender, three.js), else the first primitive's.
std::vector<std::string> target_names(const tinygltf::Mesh& mesh, int count, const AccessorReader& reader,
                                      const std::string& label) {
  const tinygltf::Value* names = nullptr;
  if (mesh.extras.IsObject() && mesh.extras.Has("targetNames"))
    names = &mesh.extras.Get("targetNames");
  else if (!mesh.primitives.empty() && mesh.primitives[0].extras.IsObject() &&
           mesh.primitives[0].extras.Has("targetNames"))
    names = &mesh.primitives[0].extras.Get("targetNames");
  std::vector<std::string> out(count);
  if (names != nullptr) {
    if (!names->IsArray() || static_cast<int>(names->ArrayLen()) != count)
      reader.fail("mesh " + label + ": extras.targetNames should list " + std::to_string(count) +
                  " names, one per morph target, got " +
                  (names->IsArray() ? std::to_string(names->ArrayLen()) : std::string("no list")));
    for (int k = 0; k < count; ++k)
      if (names->Get(k).IsString()) out[k] = names->Get(k).Get<std::string>();
  }
  for (int k = 0; k < count; ++k)
    if (out[k].empty()) out[k] = "target_" + std::to_string(k);
  return out;
}

}  // namespace

namespace gltf_detail {

// One mesh of an avatar as read: vertices and POSITION deltas in scene coordinates.
struct MeshBlock {
  std::string label;                    // "\"Face\"" or "#3", for messages
  Eigen::MatrixXd vertices;             // #v x 3
  std::vector<int> faces;               // 3 per triangle, into `vertices`
  std::vector<std::string> targets;     // morph target names, distinct
  std::vector<Eigen::MatrixXd> deltas;  // per target, #v x 3
};

// Where a mesh's first instance in the scene puts it.
struct Placement {
  bool placed = false;  // false: no node of the scene instances the mesh (read as stored)
  int node = -1;
  Eigen::Matrix4d world = Eigen::Matrix4d::Identity();
};

std::string node_label(const tinygltf::Model& model, int n) {
  const std::string& name = model.nodes[n].name;
  return "node " + std::to_string(n) + (name.empty() ? "" : " \"" + name + "\"");
}

// The node's own transform: its matrix (column-major), else translation x rotation x scale.
Eigen::Matrix4d local_matrix(const tinygltf::Model& model, int n, const AccessorReader& reader) {
  const tinygltf::Node& node = model.nodes[n];
  auto finite = [&](const std::vector<double>& values, const char* what) {
    for (double v : values)
      if (!std::isfinite(v)) reader.fail(node_label(model, n) + ": " + what + " has a non-finite number");
  };
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  if (!node.matrix.empty()) {
    if (node.matrix.size() != 16)
      reader.fail(node_label(model, n) + ": matrix has " + std::to_string(node.matrix.size()) +
                  " numbers; expected 16");
    finite(node.matrix, "matrix");
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r) m(r, c) = node.matrix[c * 4 + r];
    return m;
  }
  auto sized = [&](const std::vector<double>& values, size_t size, const char* what) {
    if (!values.empty() && values.size() != size)
      reader.fail(node_label(model, n) + ": " + what + " has " + std::to_string(values.size()) + " numbers; expected " +
                  std::to_string(size));
    finite(values, what);
    return !values.empty();
  };
  if (sized(node.scale, 3, "scale")) m.topLeftCorner<3, 3>() = Eigen::Vector3d(node.scale.data()).asDiagonal();
  if (sized(node.rotation, 4, "rotation")) {
    Eigen::Quaterniond q(node.rotation[3], node.rotation[0], node.rotation[1], node.rotation[2]);  // glTF: x, y, z, w
    if (!(q.norm() > 1e-12)) reader.fail(node_label(model, n) + ": rotation is a zero quaternion");
    q.normalize();
    m.topLeftCorner<3, 3>() = q.toRotationMatrix() * m.topLeftCorner<3, 3>();
  }
  if (sized(node.translation, 3, "translation")) m.topRightCorner<3, 1>() = Eigen::Vector3d(node.translation.data());
  return m;
}

// Each mesh's first instance, depth-first from the scene's roots (the default scene, else
// scene 0; without scenes, the nodes that are nobody's child). A node reached a second time
// (which glTF's strict node tree forbids) is not entered again, so cycles end.
std::vector<Placement> place_meshes(const tinygltf::Model& model, const AccessorReader& reader) {
  const int nodes = static_cast<int>(model.nodes.size());
  std::vector<Placement> placements(model.meshes.size());
  std::vector<int> roots;
  if (!model.scenes.empty()) {
    const int scene =
        model.defaultScene >= 0 && model.defaultScene < static_cast<int>(model.scenes.size()) ? model.defaultScene : 0;
    roots = model.scenes[scene].nodes;
  } else {
    std::vector<char> child(nodes, 0);
    for (const tinygltf::Node& node : model.nodes)
      for (int c : node.children)
        if (c >= 0 && c < nodes) child[c] = 1;
    for (int n = 0; n < nodes; ++n)
      if (!child[n]) roots.push_back(n);
  }
  std::vector<char> visited(nodes, 0);
  struct Entry {
    int node;
    Eigen::Matrix4d parent;
    std::string from;  // for messages about a bad node index
  };
  std::vector<Entry> stack;
  for (auto r = roots.rbegin(); r != roots.rend(); ++r) stack.push_back({*r, Eigen::Matrix4d::Identity(), "the scene"});
  while (!stack.empty()) {
    const Entry entry = std::move(stack.back());
    stack.pop_back();
    if (entry.node < 0 || entry.node >= nodes)
      reader.fail(entry.from + " names node " + std::to_string(entry.node) + ", which does not exist (" +
                  std::to_string(nodes) + " nodes)");
    if (visited[entry.node]) continue;
    visited[entry.node] = 1;
    const tinygltf::Node& node = model.nodes[entry.node];
    const Eigen::Matrix4d world = entry.parent * local_matrix(model, entry.node, reader);
    if (node.mesh >= static_cast<int>(model.meshes.size()))
      reader.fail(node_label(model, entry.node) + " names mesh " + std::to_string(node.mesh) +
                  ", which does not exist (" + std::to_string(model.meshes.size()) + " meshes)");
    if (node.mesh >= 0 && !placements[node.mesh].placed) placements[node.mesh] = {true, entry.node, world};
    for (auto c = node.children.rbegin(); c != node.children.rend(); ++c)
      stack.push_back({*c, world, node_label(model, entry.node)});
  }
  return placements;
}

// Draco data replaces the primitive's accessors: refused unless the accessors also hold the
// uncompressed data (allowed when the file does not require the extension).
void refuse_draco(const tinygltf::Primitive& primitive, int position, const AccessorReader& reader,
                  const tinygltf::Model& model, const std::string& where) {
  if (!primitive.extensions.count("KHR_draco_mesh_compression")) return;
  const bool fallback =
      position >= 0 && position < static_cast<int>(model.accessors.size()) && model.accessors[position].bufferView >= 0;
  if (reader.required("KHR_draco_mesh_compression") || !fallback)
    reader.fail(where + ": Draco-compressed (KHR_draco_mesh_compression; POSITION is accessor " +
                std::to_string(position) + ") is not supported; " + kDecompressHint);
}

// Reads mesh `m`: its primitives merged (primitives that share their POSITION and target
// accessors, one vertex buffer with several index ranges as many exporters write, share their
// vertices), positions through `placement`, deltas through its linear part. `vertices_before`
// and `dense_targets`: for the size check of the whole avatar's dense storage.
MeshBlock read_mesh_block(const tinygltf::Model& model, int m, const Placement& placement, const AccessorReader& reader,
                          int vertices_before, int dense_targets) {
  const tinygltf::Mesh& mesh = model.meshes[m];
  MeshBlock out;
  out.label = mesh_label(model, m);
  const std::string& label = out.label;
  const int targets = target_count(mesh);
  // Vertex blocks are kept apart (each with its targets' deltas) and joined once at the end, so
  // many primitives cost linear time.
  std::vector<Eigen::MatrixXd> positions;
  std::vector<std::vector<Eigen::MatrixXd>> block_deltas;  // [block][target]
  std::map<std::vector<int>, int> first_vertex;            // accessors of a vertex block -> its first vertex
  int vertex_count = 0;
  for (size_t p = 0; p < mesh.primitives.size(); ++p) {
    const tinygltf::Primitive& primitive = mesh.primitives[p];
    const std::string where = "mesh " + label + " primitive " + std::to_string(p);
    if (primitive.mode != TINYGLTF_MODE_TRIANGLES && primitive.mode != -1)
      reader.fail(where + ": " + mode_name(primitive.mode) +
                  " are not supported; export the mesh as triangles (glTF mode 4)");
    if (static_cast<int>(primitive.targets.size()) != targets)
      reader.fail(where + " has " + std::to_string(primitive.targets.size()) + " morph targets but primitive 0 has " +
                  std::to_string(targets) + "; glTF requires the same number for every primitive");
    const auto position = primitive.attributes.find("POSITION");
    refuse_draco(primitive, position == primitive.attributes.end() ? -1 : position->second, reader, model, where);
    if (position == primitive.attributes.end()) reader.fail(where + " has no POSITION attribute");

    std::vector<int> key = {position->second};
    for (const auto& target : primitive.targets) {
      const auto delta = target.find("POSITION");
      key.push_back(delta == target.end() ? -1 : delta->second);
    }
    auto block = first_vertex.find(key);
    if (block == first_vertex.end()) {
      const Eigen::Index rows =
          static_cast<Eigen::Index>(reader.checked(position->second, Role::position, where + " POSITION").count);
      // The neutral and every target's offsets are stored dense: refuse sizes no machine holds
      // before allocating (blocks may repeat one big POSITION accessor with other targets).
      const double total = static_cast<double>(vertices_before) + vertex_count + static_cast<double>(rows);
      const double dense_bytes = (std::max(targets, dense_targets) + 1.0) * total * 3 * 8;
      if (dense_bytes > kMaxDenseBytes)
        reader.fail("mesh " + label + ": " + std::to_string(std::max(targets, dense_targets)) + " morph targets x " +
                    std::to_string(static_cast<long long>(total)) + " vertices need " +
                    std::to_string(static_cast<long long>(dense_bytes / (1 << 20))) +
                    " MiB of positions and offsets, more than " +
                    std::to_string(static_cast<long long>(kMaxDenseBytes / (1 << 20))) + " MiB");
      for (int t = 0; t < targets; ++t) {
        const int accessor = key[t + 1];
        if (accessor < 0) continue;
        const std::string what = where + " morph target " + std::to_string(t) + " POSITION";
        const size_t deltas = reader.checked(accessor, Role::morph_delta, what).count;
        if (deltas != static_cast<size_t>(rows))
          reader.fail(where + " morph target " + std::to_string(t) + " has " + std::to_string(deltas) +
                      " POSITION deltas but the primitive has " + std::to_string(rows) + " vertices");
      }
      positions.push_back(reader.read(position->second, Role::position, where + " POSITION"));
      std::vector<Eigen::MatrixXd> deltas(targets);
      for (int t = 0; t < targets; ++t) {
        const int accessor = key[t + 1];
        deltas[t] = accessor < 0 ? Eigen::MatrixXd::Zero(rows, 3)
                                 : reader.read(accessor, Role::morph_delta,
                                               where + " morph target " + std::to_string(t) + " POSITION");
      }
      block_deltas.push_back(std::move(deltas));
      block = first_vertex.emplace(key, vertex_count).first;
      vertex_count += static_cast<int>(rows);
    }
    const int base = block->second;
    const int block_size = static_cast<int>(model.accessors[position->second].count);

    std::vector<int> corners;
    if (primitive.indices >= 0) {
      corners = reader.indices(primitive.indices, block_size, where + " indices");
    } else {
      corners.resize(block_size);
      for (int k = 0; k < block_size; ++k) corners[k] = k;
    }
    if (corners.size() % 3 != 0)
      reader.fail(where + ": " + std::to_string(corners.size()) + " triangle corners is not a multiple of 3");
    for (int corner : corners) out.faces.push_back(base + corner);
  }

  out.vertices.resize(vertex_count, 3);
  int row = 0;
  for (const Eigen::MatrixXd& block : positions) {
    out.vertices.middleRows(row, block.rows()) = block;
    row += static_cast<int>(block.rows());
  }
  out.deltas.resize(targets);
  for (int t = 0; t < targets; ++t) {
    out.deltas[t].resize(vertex_count, 3);
    Eigen::Index first = 0;
    for (std::vector<Eigen::MatrixXd>& deltas : block_deltas) {
      out.deltas[t].middleRows(first, deltas[t].rows()) = deltas[t];
      first += deltas[t].rows();
      deltas[t] = Eigen::MatrixXd();  // released as it is copied
    }
  }
  if (placement.placed && !placement.world.isIdentity(0)) {
    const Eigen::Matrix3d linear = placement.world.topLeftCorner<3, 3>();
    const Eigen::RowVector3d shift = placement.world.topRightCorner<3, 1>().transpose();
    out.vertices = (out.vertices * linear.transpose()).rowwise() + shift;
    for (Eigen::MatrixXd& d : out.deltas) d = d * linear.transpose();
    if (!out.vertices.allFinite())
      reader.fail("mesh " + label + ": the transform of " + node_label(model, placement.node) +
                  " takes its positions out of the range of numbers");
  }

  out.targets = target_names(mesh, targets, reader, label);
  std::map<std::string, int> seen;
  for (int t = 0; t < targets; ++t) {
    const auto [previous, inserted] = seen.emplace(out.targets[t], t);
    if (!inserted)
      reader.fail("mesh " + label + ": morph targets " + std::to_string(previous->second) + " and " +
                  std::to_string(t) + " are both named \"" + out.targets[t] + "\"");
    if (!out.deltas[t].allFinite())
      reader.fail("mesh " + label + ": morph target \"" + out.targets[t] + "\" has a non-finite POSITION delta");
  }
  return out;
}

// When a file tinygltf cannot read names a compression extension, that is the likely reason
// (a meshopt fallback buffer without data, say): the extension names found in its JSON.
std::vector<std::string> compression_named_in(const std::string& path) {
  const std::string json = gltf_json_text(path);
  std::vector<std::string> found;
  for (const char* extension : {"KHR_draco_mesh_compression", "EXT_meshopt_compression", "KHR_meshopt_compression"})
    if (json.find(extension) != std::string::npos) found.push_back(extension);
  return found;
}

}  // namespace gltf_detail

Rig load_rig_gltf(const std::string& path, const GltfRigOptions& options) {
  using namespace gltf_detail;
  std::error_code ec;
  if (!fs::exists(path, ec)) throw Error(path, "file not found");
  std::string extension = fs::path(path).extension().string();
  for (char& ch : extension) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));

  tinygltf::Model model;
  tinygltf::TinyGLTF loader;
  loader.SetImageLoader(skip_image, nullptr);
  std::string error, warning;
  const bool ok = extension == ".glb" ? loader.LoadBinaryFromFile(&model, &error, &warning, path)
                                      : loader.LoadASCIIFromFile(&model, &error, &warning, path);
  if (!ok) {
    while (!error.empty() && std::isspace(static_cast<unsigned char>(error.back()))) error.pop_back();
    std::string message = "cannot read glTF" + (error.empty() ? std::string() : ": " + error);
    const std::vector<std::string> compression = compression_named_in(path);
    if (!compression.empty())
      message +=
          "; the file uses " + compression[0] + " (compressed geometry), which is not supported; " + kDecompressHint;
    throw Error(path, message);
  }
  const AccessorReader reader(model, path);
  const int mesh_count = static_cast<int>(model.meshes.size());
  auto mesh_name = [&model](int m) {
    return model.meshes[m].name.empty() ? "#" + std::to_string(m) : model.meshes[m].name;
  };

  // Choose the meshes.
  std::vector<int> chosen;
  if (!options.meshes.empty()) {
    for (const std::string& name : options.meshes) {
      int found = -1;
      for (int m = 0; m < mesh_count && found < 0; ++m)
        if (model.meshes[m].name == name) found = m;
      for (int m = 0; m < mesh_count && found < 0; ++m)
        if (model.meshes[m].name.empty() && name == "#" + std::to_string(m)) found = m;
      if (found < 0) {
        std::string names;
        for (int m = 0; m < mesh_count; ++m) names += (m ? ", " : "") + mesh_label(model, m);
        reader.fail("no mesh named \"" + name + "\" (meshes: " + (names.empty() ? "none" : names) + ")");
      }
      if (std::find(chosen.begin(), chosen.end(), found) != chosen.end())
        reader.fail("mesh \"" + name + "\" is named twice in the avatar's list of meshes");
      chosen.push_back(found);
    }
    if (target_count(model.meshes[chosen[0]]) == 0)
      reader.fail("mesh \"" + options.meshes[0] + "\" has no morph targets" +
                  (options.meshes.size() > 1 ? " (the first mesh of the list holds the controllers)" : ""));
  } else {
    int main = -1;
    for (int m = 0; m < mesh_count; ++m)
      if (target_count(model.meshes[m]) > 0 &&
          (main < 0 || target_count(model.meshes[m]) > target_count(model.meshes[main])))
        main = m;
    if (main < 0)
      reader.fail("no mesh has morph targets (" + std::to_string(mesh_count) +
                  " meshes); a glTF rig needs a mesh whose morph targets are the controllers");
    chosen.push_back(main);
  }
  if (options.find_parts && options.meshes.size() <= 1)
    for (int m = 0; m < mesh_count; ++m)
      if (m != chosen[0] && part_kind_from_name(model.meshes[m].name)) chosen.push_back(m);

  const std::vector<Placement> placements = place_meshes(model, reader);
  const int controllers = target_count(model.meshes[chosen[0]]);
  std::vector<MeshBlock> blocks;
  int vertex_count = 0;
  for (int m : chosen) {
    blocks.push_back(read_mesh_block(model, m, placements[m], reader, vertex_count, controllers));
    vertex_count += static_cast<int>(blocks.back().vertices.rows());
  }

  Rig rig;
  rig.source = path;
  rig.name = fs::path(path).stem().string();
  rig.units = "m";  // glTF's unit
  rig.neutral.source = path;
  rig.neutral.vertices.resize(vertex_count, 3);
  std::vector<int> first(blocks.size());
  int row = 0;
  for (size_t b = 0; b < blocks.size(); ++b) {
    first[b] = row;
    rig.neutral.vertices.middleRows(row, blocks[b].vertices.rows()) = blocks[b].vertices;
    for (size_t k = 0; k < blocks[b].faces.size(); k += 3) {
      const int corners[3] = {row + blocks[b].faces[k], row + blocks[b].faces[k + 1], row + blocks[b].faces[k + 2]};
      rig.neutral.faces.add(corners, 3);
    }
    row += static_cast<int>(blocks[b].vertices.rows());
  }
  triangulate(rig.neutral);
  try {
    require_valid_mesh(rig.neutral);
  } catch (const Error& e) {
    std::string labels;
    for (const MeshBlock& b : blocks) labels += (labels.empty() ? "" : ", ") + b.label;
    reader.fail((blocks.size() == 1 ? "mesh " : "meshes ") + labels + ": " + e.detail());
  }

  // Controllers: the first mesh's targets; the other meshes' targets of the same names.
  for (int t = 0; t < controllers; ++t) {
    Controller controller;
    controller.name = blocks[0].targets[t];
    controller.offset = Positions::Zero(vertex_count, 3);
    controller.offset.topRows(blocks[0].vertices.rows()) = blocks[0].deltas[t];
    blocks[0].deltas[t] = Eigen::MatrixXd();
    rig.controllers.push_back(std::move(controller));
  }
  for (size_t b = 1; b < blocks.size(); ++b)
    for (size_t k = 0; k < blocks[b].targets.size(); ++k) {
      const int c = rig.controller_index(blocks[b].targets[k]);
      if (c >= 0) rig.controllers[c].offset.middleRows(first[b], blocks[b].vertices.rows()) = blocks[b].deltas[k];
    }

  std::set<std::string> part_names;
  for (size_t b = 0; b < blocks.size(); ++b) {
    const std::string name = mesh_name(chosen[b]);
    rig.gltf_meshes.push_back(name);
    if (b == 0) continue;
    RigPart part;
    part.name = name;
    for (int n = 2; part_names.count(part.name); ++n) part.name = name + "_" + std::to_string(n);
    part_names.insert(part.name);
    part.kind = part_kind_from_name(model.meshes[chosen[b]].name).value_or(PartKind::other);
    part.mesh = name;
    part.vertices.resize(blocks[b].vertices.rows());
    for (size_t v = 0; v < part.vertices.size(); ++v) part.vertices[v] = first[b] + static_cast<int>(v);
    rig.parts.push_back(std::move(part));
  }
  eyes_from_parts(rig);
  return rig;
}

Rig load_rig_gltf(const std::string& path, const std::string& mesh_name) {
  GltfRigOptions options;
  if (!mesh_name.empty()) options.meshes = {mesh_name};
  return load_rig_gltf(path, options);
}

}  // namespace retarget
