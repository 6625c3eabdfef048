// libFuzzer target: a weights table's bytes through parse_weights_csv (infer/weights_csv.h),
// then the controllers checked against a rig's names as `retarget gltf-animation` checks them.
#include <string>

#include "core/error.h"
#include "fuzz/fuzz_input.h"
#include "infer/weights_csv.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    const retarget::WeightsCsv csv =
        retarget::parse_weights_csv(std::string(retarget::fuzz::bytes(data, size)), "w.csv");
    retarget::require_weights_controllers(csv, {"jawOpen", "smileLeft", "blink"});
  } catch (const retarget::Error&) {
  }
  return 0;
}
