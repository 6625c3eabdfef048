// Builds glTF files for the rig tests: a model in memory (one buffer, views and accessors
// appended as needed) written with tinygltf as .gltf or .glb.
#pragma once

#include <tiny_gltf.h>

#include <catch2/catch.hpp>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

namespace retarget::test {

struct GltfBuilder {
  tinygltf::Model model;

  GltfBuilder() {
    model.buffers.emplace_back();
    model.asset.version = "2.0";
  }

  template <typename T>
  int view(const std::vector<T>& values, size_t stride = 0) {
    std::vector<unsigned char>& data = model.buffers[0].data;
    while (data.size() % 4) data.push_back(0);
    tinygltf::BufferView v;
    v.buffer = 0;
    v.byteOffset = data.size();
    v.byteLength = values.size() * sizeof(T);
    v.byteStride = stride;
    data.resize(data.size() + v.byteLength);
    std::memcpy(data.data() + v.byteOffset, values.data(), v.byteLength);
    model.bufferViews.push_back(v);
    return static_cast<int>(model.bufferViews.size()) - 1;
  }

  int accessor(int view_index, int component_type, size_t count, int type, bool normalized = false,
               size_t byte_offset = 0) {
    tinygltf::Accessor a;
    a.bufferView = view_index;
    a.byteOffset = byte_offset;
    a.componentType = component_type;
    a.count = count;
    a.type = type;
    a.normalized = normalized;
    if (type == TINYGLTF_TYPE_VEC3) {
      a.minValues = {-100, -100, -100};
      a.maxValues = {100, 100, 100};
    }
    model.accessors.push_back(a);
    return static_cast<int>(model.accessors.size()) - 1;
  }

  int vec3(const std::vector<float>& xyz) {
    return accessor(view(xyz), TINYGLTF_COMPONENT_TYPE_FLOAT, xyz.size() / 3, TINYGLTF_TYPE_VEC3);
  }

  void add_mesh(const std::string& name, std::vector<tinygltf::Primitive> primitives,
                const std::vector<std::string>& target_names = {}) {
    tinygltf::Mesh mesh;
    mesh.name = name;
    mesh.primitives = std::move(primitives);
    if (!target_names.empty()) {
      tinygltf::Value::Array names;
      for (const std::string& n : target_names) names.emplace_back(n);
      tinygltf::Value::Object extras;
      extras["targetNames"] = tinygltf::Value(names);
      mesh.extras = tinygltf::Value(extras);
    }
    model.meshes.push_back(mesh);
    tinygltf::Node node;
    node.mesh = static_cast<int>(model.meshes.size()) - 1;
    model.nodes.push_back(node);
  }

  std::string write(const std::filesystem::path& path) {
    if (model.scenes.empty()) {
      tinygltf::Scene scene;
      for (int n = 0; n < static_cast<int>(model.nodes.size()); ++n) scene.nodes.push_back(n);
      model.scenes.push_back(scene);
      model.defaultScene = 0;
    }
    tinygltf::TinyGLTF writer;
    const bool binary = path.extension() == ".glb";
    REQUIRE(writer.WriteGltfSceneToFile(&model, path.string(), false, true, true, binary));
    return path.string();
  }
};

inline tinygltf::Primitive triangles_primitive(int position, int indices, std::vector<int> target_positions) {
  tinygltf::Primitive p;
  p.attributes["POSITION"] = position;
  p.indices = indices;
  p.mode = TINYGLTF_MODE_TRIANGLES;
  for (int t : target_positions) p.targets.push_back({{"POSITION", t}});
  return p;
}

}  // namespace retarget::test
