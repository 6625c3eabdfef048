// glTF 2.0 morph-target rigs through tinygltf (Debian's shared library; its implementation is
// compiled there, so TINYGLTF_IMPLEMENTATION is not defined here).
#include <tiny_gltf.h>

#include <algorithm>
#include <cctype>
#include <cstring>
#include <filesystem>
#include <map>
#include <set>

#include "core/error.h"
#include "geometry/mesh_validation.h"
#include "geometry/rig.h"

namespace retarget {

namespace fs = std::filesystem;

namespace {

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

// Reads accessors into doubles, with the checks a hand-made or truncated file needs.
class AccessorReader {
 public:
  AccessorReader(const tinygltf::Model& model, std::string path) : model_(model), path_(std::move(path)) {}

  // count x components values; `what` names the accessor's role for messages.
  Eigen::MatrixXd read(int index, int components, const std::string& what) const {
    if (index < 0 || index >= static_cast<int>(model_.accessors.size()))
      fail(what + ": accessor " + std::to_string(index) + " does not exist");
    const tinygltf::Accessor& accessor = model_.accessors[index];
    const std::string where = what + " (accessor " + std::to_string(index) + ")";
    const int found = tinygltf::GetNumComponentsInType(static_cast<uint32_t>(accessor.type));
    if (found != components)
      fail(where + ": expected " + std::to_string(components) + " components per element, got " +
           std::to_string(found));
    const size_t count = accessor.count;
    Eigen::MatrixXd values = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(count), components);
    if (accessor.bufferView >= 0)
      read_view(accessor.bufferView, accessor.byteOffset, accessor.ByteStride(view(accessor.bufferView, where)),
                accessor.componentType, accessor.normalized, count, components, values, where);
    if (accessor.sparse.isSparse) {
      const auto& sparse = accessor.sparse;
      if (sparse.count < 0 || static_cast<size_t>(sparse.count) > count)
        fail(where + ": sparse count " + std::to_string(sparse.count) + " exceeds the accessor's " +
             std::to_string(count) + " elements");
      const int index_type = sparse.indices.componentType;
      if (index_type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE && index_type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
          index_type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
        fail(where + ": sparse indices must be unsigned integers");
      Eigen::MatrixXd rows(sparse.count, 1);
      read_view(sparse.indices.bufferView, sparse.indices.byteOffset, 0, index_type, false, sparse.count, 1, rows,
                where + " sparse indices");
      Eigen::MatrixXd replaced(sparse.count, components);
      read_view(sparse.values.bufferView, sparse.values.byteOffset, 0, accessor.componentType, accessor.normalized,
                sparse.count, components, replaced, where + " sparse values");
      for (int k = 0; k < sparse.count; ++k) {
        if (rows(k, 0) >= static_cast<double>(count))
          fail(where + ": sparse index " + std::to_string(static_cast<uint64_t>(rows(k, 0))) + " is out of range (" +
               std::to_string(count) + " elements)");
        values.row(static_cast<Eigen::Index>(rows(k, 0))) = replaced.row(k);
      }
    }
    return values;
  }

  // Vertex indices of a primitive: unsigned integers, checked against `vertex_count`.
  std::vector<int> indices(int index, int vertex_count, const std::string& what) const {
    if (index >= 0 && index < static_cast<int>(model_.accessors.size())) {
      const int type = model_.accessors[index].componentType;
      if (type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE && type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
          type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
        fail(what + " (accessor " + std::to_string(index) +
             "): indices must be unsigned integers, got component type " + std::to_string(type));
    }
    const Eigen::MatrixXd values = read(index, 1, what);
    std::vector<int> out(values.rows());
    for (Eigen::Index k = 0; k < values.rows(); ++k) {
      if (values(k, 0) >= vertex_count)
        fail(what + ": index " + std::to_string(static_cast<uint64_t>(values(k, 0))) + " (entry " + std::to_string(k) +
             ") is out of range (the primitive has " + std::to_string(vertex_count) + " vertices)");
      out[k] = static_cast<int>(values(k, 0));
    }
    return out;
  }

  [[noreturn]] void fail(const std::string& message) const { throw Error(path_, message); }

 private:
  const tinygltf::BufferView& view(int index, const std::string& where) const {
    if (index < 0 || index >= static_cast<int>(model_.bufferViews.size()))
      fail(where + ": buffer view " + std::to_string(index) + " does not exist");
    return model_.bufferViews[index];
  }

  // Element e, component j of the view's data into out(e, j). stride 0: the view's byteStride, else packed.
  void read_view(int view_index, size_t byte_offset, int stride, int component_type, bool normalized, size_t count,
                 int components, Eigen::MatrixXd& out, const std::string& where) const {
    const tinygltf::BufferView& bv = view(view_index, where);
    if (bv.buffer < 0 || bv.buffer >= static_cast<int>(model_.buffers.size()))
      fail(where + ": buffer " + std::to_string(bv.buffer) + " does not exist");
    const std::vector<unsigned char>& data = model_.buffers[bv.buffer].data;
    const int size = tinygltf::GetComponentSizeInBytes(static_cast<uint32_t>(component_type));
    if (size <= 0) fail(where + ": unsupported component type " + std::to_string(component_type));
    const size_t element = static_cast<size_t>(size) * components;
    if (stride == 0) stride = static_cast<int>(bv.byteStride != 0 ? bv.byteStride : element);
    if (stride < 0 || static_cast<size_t>(stride) < element)
      fail(where + ": byte stride " + std::to_string(bv.byteStride) + " is invalid for " + std::to_string(element) +
           "-byte elements");
    if (count == 0) return;
    const size_t end = byte_offset + (count - 1) * static_cast<size_t>(stride) + element;
    if (end > bv.byteLength || bv.byteOffset + bv.byteLength > data.size())
      fail(where + ": reads past the end of its buffer view or buffer (" + std::to_string(end) +
           " bytes from the view's start, view " + std::to_string(bv.byteLength) + " bytes, buffer " +
           std::to_string(data.size()) + " bytes)");
    const unsigned char* base = data.data() + bv.byteOffset + byte_offset;
    for (size_t e = 0; e < count; ++e)
      for (int j = 0; j < components; ++j)
        out(static_cast<Eigen::Index>(e), j) = component(base + e * stride + j * size, component_type, normalized);
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
      case TINYGLTF_COMPONENT_TYPE_DOUBLE:
        return get(double{});
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
      case TINYGLTF_COMPONENT_TYPE_INT: {
        const double v = get(int32_t{});
        return normalized ? std::max(v / 2147483647.0, -1.0) : v;
      }
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: {
        const double v = get(uint32_t{});
        return normalized ? v / 4294967295.0 : v;
      }
      default:
        return 0;  // unreachable: GetComponentSizeInBytes rejected it
    }
  }

  const tinygltf::Model& model_;
  std::string path_;
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

Rig load_rig_gltf(const std::string& path, const std::string& mesh_name) {
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
    throw Error(path, "cannot read glTF" + (error.empty() ? std::string() : ": " + error));
  }
  const AccessorReader reader(model, path);

  // Choose the mesh.
  int chosen = -1;
  if (!mesh_name.empty()) {
    for (int m = 0; m < static_cast<int>(model.meshes.size()) && chosen < 0; ++m)
      if (model.meshes[m].name == mesh_name) chosen = m;
    if (chosen < 0) {
      std::string names;
      for (int m = 0; m < static_cast<int>(model.meshes.size()); ++m) names += (m ? ", " : "") + mesh_label(model, m);
      reader.fail("no mesh named \"" + mesh_name + "\" (meshes: " + (names.empty() ? "none" : names) + ")");
    }
    if (target_count(model.meshes[chosen]) == 0) reader.fail("mesh \"" + mesh_name + "\" has no morph targets");
  } else {
    for (int m = 0; m < static_cast<int>(model.meshes.size()); ++m)
      if (target_count(model.meshes[m]) > 0 &&
          (chosen < 0 || target_count(model.meshes[m]) > target_count(model.meshes[chosen])))
        chosen = m;
    if (chosen < 0)
      reader.fail("no mesh has morph targets (" + std::to_string(model.meshes.size()) +
                  " meshes); a glTF rig needs a mesh whose morph targets are the controllers");
  }
  const tinygltf::Mesh& mesh = model.meshes[chosen];
  const std::string label = mesh_label(model, chosen);
  const int targets = target_count(mesh);

  // Merge the primitives. Primitives that share their POSITION and target accessors (one
  // vertex buffer, several index ranges, as many exporters write) share their vertices.
  std::vector<Eigen::MatrixXd> positions, offsets(targets);
  std::vector<int> faces;
  std::map<std::vector<int>, int> first_vertex;  // accessors of a vertex block -> its first vertex
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
    if (position == primitive.attributes.end()) reader.fail(where + " has no POSITION attribute");

    std::vector<int> key = {position->second};
    for (const auto& target : primitive.targets) {
      const auto delta = target.find("POSITION");
      key.push_back(delta == target.end() ? -1 : delta->second);
    }
    auto block = first_vertex.find(key);
    if (block == first_vertex.end()) {
      Eigen::MatrixXd vertices = reader.read(position->second, 3, where + " POSITION");
      const Eigen::Index rows = vertices.rows();
      for (int t = 0; t < targets; ++t) {
        const int accessor = key[t + 1];
        Eigen::MatrixXd delta =
            accessor < 0 ? Eigen::MatrixXd::Zero(rows, 3)
                         : reader.read(accessor, 3, where + " morph target " + std::to_string(t) + " POSITION");
        if (delta.rows() != rows)
          reader.fail(where + " morph target " + std::to_string(t) + " has " + std::to_string(delta.rows()) +
                      " POSITION deltas but the primitive has " + std::to_string(rows) + " vertices");
        offsets[t].conservativeResize(vertex_count + rows, 3);
        offsets[t].bottomRows(rows) = delta;
      }
      positions.push_back(std::move(vertices));
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
    for (int corner : corners) faces.push_back(base + corner);
  }

  Rig rig;
  rig.source = path;
  rig.name = fs::path(path).stem().string();
  rig.units = "m";  // glTF's unit
  rig.neutral.source = path;
  rig.neutral.vertices.resize(vertex_count, 3);
  int row = 0;
  for (const Eigen::MatrixXd& block : positions) {
    rig.neutral.vertices.middleRows(row, block.rows()) = block;
    row += static_cast<int>(block.rows());
  }
  for (size_t k = 0; k < faces.size(); k += 3) rig.neutral.faces.add(&faces[k], 3);
  triangulate(rig.neutral);
  try {
    require_valid_mesh(rig.neutral);
  } catch (const Error& e) {
    reader.fail("mesh " + label + ": " + e.detail());
  }

  const std::vector<std::string> names = target_names(mesh, targets, reader, label);
  std::map<std::string, int> seen;
  for (int t = 0; t < targets; ++t) {
    const auto [previous, inserted] = seen.emplace(names[t], t);
    if (!inserted)
      reader.fail("mesh " + label + ": morph targets " + std::to_string(previous->second) + " and " +
                  std::to_string(t) + " are both named \"" + names[t] + "\"");
    Controller controller;
    controller.name = names[t];
    controller.offset = offsets[t];
    if (!controller.offset.allFinite())
      reader.fail("mesh " + label + ": morph target \"" + names[t] + "\" has a non-finite POSITION delta");
    rig.controllers.push_back(std::move(controller));
  }
  return rig;
}

}  // namespace retarget
