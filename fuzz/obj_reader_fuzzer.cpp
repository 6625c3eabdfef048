// libFuzzer target: OBJ bytes through read_obj(), then what read_mesh() does next.
#include "core/error.h"
#include "fuzz/fuzz_input.h"
#include "geometry/mesh_validation.h"
#include "geometry/obj_reader.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    retarget::Mesh mesh = retarget::read_obj("fuzz.obj", retarget::fuzz::bytes(data, size));
    retarget::triangulate(mesh);
    retarget::validate_mesh(mesh);
  } catch (const retarget::Error&) {
  }
  return 0;
}
