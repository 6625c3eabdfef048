// Hand-written glTF avatars for the tests of folders that do not link tinygltf: a .gltf (JSON)
// and its .bin buffer, one node per mesh (optionally translated), float positions, uint32
// indices and float morph-target deltas named through the mesh's extras.targetNames.
#pragma once

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "geometry/mesh.h"
#include "test_support.h"
#include "tiny_data.h"

namespace retarget::test {

struct GltfTestMesh {
  std::string name;
  Mesh mesh;                                               // positions and triangles
  std::vector<std::pair<std::string, Positions>> targets;  // name -> #V x 3 deltas
};

// Writes `path` (.gltf) and `path`.bin; returns the .gltf path.
inline std::string write_gltf_avatar(const std::filesystem::path& path, const std::vector<GltfTestMesh>& meshes) {
  std::vector<unsigned char> bin;
  std::ostringstream views, accessors, json_meshes, nodes;
  int view_count = 0;
  auto add_view = [&](const void* data, size_t bytes) {
    while (bin.size() % 4) bin.push_back(0);
    const size_t offset = bin.size();
    bin.resize(offset + bytes);
    std::memcpy(bin.data() + offset, data, bytes);
    views << (view_count ? ", " : "") << "{\"buffer\": 0, \"byteOffset\": " << offset << ", \"byteLength\": " << bytes
          << "}";
    return view_count++;
  };
  int accessor_count = 0;
  auto add_vec3 = [&](const Positions& p, bool bounds) {
    std::vector<float> f(static_cast<size_t>(p.size()));
    for (int r = 0; r < p.rows(); ++r)
      for (int c = 0; c < 3; ++c) f[static_cast<size_t>(r * 3 + c)] = static_cast<float>(p(r, c));
    const int view = add_view(f.data(), f.size() * 4);
    accessors << (accessor_count ? ", " : "") << "{\"bufferView\": " << view
              << ", \"componentType\": 5126, \"type\": \"VEC3\", \"count\": " << p.rows();
    if (bounds) {
      const Eigen::RowVector3d lo = p.colwise().minCoeff(), hi = p.colwise().maxCoeff();
      accessors << ", \"min\": [" << lo(0) << ", " << lo(1) << ", " << lo(2) << "], \"max\": [" << hi(0) << ", "
                << hi(1) << ", " << hi(2) << "]";
    }
    accessors << "}";
    return accessor_count++;
  };
  for (size_t m = 0; m < meshes.size(); ++m) {
    const GltfTestMesh& g = meshes[m];
    const int position = add_vec3(g.mesh.vertices, true);
    std::vector<uint32_t> corners;
    for (int t = 0; t < g.mesh.triangles.rows(); ++t)
      for (int c = 0; c < 3; ++c) corners.push_back(static_cast<uint32_t>(g.mesh.triangles(t, c)));
    const int view = add_view(corners.data(), corners.size() * 4);
    accessors << ", {\"bufferView\": " << view
              << ", \"componentType\": 5125, \"type\": \"SCALAR\", \"count\": " << corners.size() << "}";
    const int indices = accessor_count++;
    std::ostringstream targets, names;
    for (size_t t = 0; t < g.targets.size(); ++t) {
      targets << (t ? ", " : "") << "{\"POSITION\": " << add_vec3(g.targets[t].second, false) << "}";
      names << (t ? ", " : "") << "\"" << g.targets[t].first << "\"";
    }
    json_meshes << (m ? ", " : "") << "{\"name\": \"" << g.name << "\", \"primitives\": [{\"attributes\": "
                << "{\"POSITION\": " << position << "}, \"indices\": " << indices << ", \"mode\": 4"
                << (g.targets.empty() ? "" : ", \"targets\": [" + targets.str() + "]") << "}]"
                << (g.targets.empty() ? "" : ", \"extras\": {\"targetNames\": [" + names.str() + "]}") << "}";
    nodes << (m ? ", " : "") << "{\"name\": \"" << g.name << "\", \"mesh\": " << m << "}";
  }
  std::string scene;
  for (size_t m = 0; m < meshes.size(); ++m) scene += (m ? ", " : "") + std::to_string(m);
  const std::string bin_name = path.filename().string() + ".bin";
  std::ofstream(path.string() + ".bin", std::ios::binary)
      .write(reinterpret_cast<const char*>(bin.data()), static_cast<std::streamsize>(bin.size()));
  std::ofstream(path, std::ios::binary)
      << "{\"asset\": {\"version\": \"2.0\"}, \"scene\": 0, \"scenes\": [{\"nodes\": [" << scene << "]}], "
      << "\"nodes\": [" << nodes.str() << "], \"meshes\": [" << json_meshes.str() << "], \"accessors\": ["
      << accessors.str() << "], \"bufferViews\": [" << views.str() << "], \"buffers\": [{\"uri\": \"" << bin_name
      << "\", \"byteLength\": " << bin.size() << "}]}";
  return path.string();
}

// A small eyeball stand-in: a 2 x 2 quad grid (9 vertices) of side 0.2 centred at (x, 1.2, 0.6).
inline Mesh gltf_test_eye(double x) {
  Mesh eye = quad_grid(2, 2, 0.2, 0.2);
  eye.vertices.col(0).array() += x - 0.1;
  eye.vertices.col(1).array() += 1.1;
  eye.vertices.col(2).array() += 0.6;
  return eye;
}

// An avatar as a glTF exporter writes it: "Body" (a 4 x 4 patch, 5 targets: the mesh with the
// most targets, the loader's default), "Face" (tiny_rig(5)'s patch and its 4 targets ctrl0-3)
// and, with `eyes`, "EyeLeft" (x = 1.5) and "EyeRight" (x = 0.5) meshes without targets.
inline std::string write_test_gltf_avatar(const std::filesystem::path& path, bool eyes = true) {
  std::vector<GltfTestMesh> meshes;
  GltfTestMesh body{"Body", bumpy_patch(4), {}};
  body.mesh.vertices.col(1).array() -= 3;  // below the face
  for (int k = 0; k < 5; ++k) body.targets.push_back({"b" + std::to_string(k), field(body.mesh, 30 + k, 0.1)});
  meshes.push_back(body);
  const Rig face = tiny_rig(5);
  GltfTestMesh head{"Face", face.neutral, {}};
  for (const Controller& c : face.controllers) head.targets.push_back({c.name, c.offset});
  meshes.push_back(head);
  if (eyes) {
    meshes.push_back({"EyeLeft", gltf_test_eye(1.5), {}});
    meshes.push_back({"EyeRight", gltf_test_eye(0.5), {}});
  }
  return write_gltf_avatar(path, meshes);
}

}  // namespace retarget::test
