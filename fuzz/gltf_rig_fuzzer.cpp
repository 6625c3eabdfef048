// libFuzzer target: glTF / GLB bytes through load_rig_gltf(). The loader reads a path, so each
// input is written to a file in a folder of this process's own (.glb when the bytes start with
// GLB's magic "glTF", else .gltf), which also exercises the loader's file handling.
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "core/error.h"
#include "fuzz/fuzz_input.h"
#include "geometry/rig.h"

namespace {

const std::string& scratch_folder() {
  static const std::string folder = [] {
    std::string pattern = (std::filesystem::temp_directory_path() / "retarget-gltf-fuzz-XXXXXX").string();
    if (!::mkdtemp(pattern.data())) std::abort();
    return pattern;
  }();
  return folder;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view bytes = retarget::fuzz::bytes(data, size);
  const bool binary = bytes.substr(0, 4) == "glTF";
  const std::string path = scratch_folder() + (binary ? "/rig.glb" : "/rig.gltf");
  std::FILE* file = std::fopen(path.c_str(), "wb");
  if (!file) std::abort();
  if (size > 0 && std::fwrite(data, 1, size, file) != size) std::abort();
  std::fclose(file);
  try {
    retarget::load_rig_gltf(path);
  } catch (const retarget::Error&) {
  }
  return 0;
}
