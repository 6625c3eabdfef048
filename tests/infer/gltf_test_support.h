// Reading a glTF file back in the tests (infer/gltf_animation.h's output): the model through
// tinygltf (images skipped) and a FLOAT accessor's values.
#pragma once

#include <tiny_gltf.h>

#include <catch2/catch.hpp>
#include <cstring>
#include <string>
#include <vector>

namespace retarget::test {

inline bool skip_image(tinygltf::Image*, const int, std::string*, std::string*, int, int, const unsigned char*, int,
                       void*) {
  return true;
}

inline tinygltf::Model load_gltf_model(const std::string& path) {
  tinygltf::Model model;
  tinygltf::TinyGLTF loader;
  loader.SetImageLoader(skip_image, nullptr);
  std::string error, warning;
  const bool ok = path.size() > 4 && path.substr(path.size() - 4) == ".glb"
                      ? loader.LoadBinaryFromFile(&model, &error, &warning, path)
                      : loader.LoadASCIIFromFile(&model, &error, &warning, path);
  INFO(error << warning);
  REQUIRE(ok);
  return model;
}

// The floats of a tightly packed FLOAT accessor.
inline std::vector<float> gltf_floats(const tinygltf::Model& model, int index) {
  const tinygltf::Accessor& a = model.accessors.at(index);
  REQUIRE(a.componentType == TINYGLTF_COMPONENT_TYPE_FLOAT);
  const tinygltf::BufferView& view = model.bufferViews.at(a.bufferView);
  const size_t n = a.count * tinygltf::GetNumComponentsInType(static_cast<uint32_t>(a.type));
  REQUIRE(a.byteOffset + n * 4 <= view.byteLength);
  std::vector<float> out(n);
  std::memcpy(out.data(), model.buffers.at(view.buffer).data.data() + view.byteOffset + a.byteOffset, n * 4);
  return out;
}

}  // namespace retarget::test
