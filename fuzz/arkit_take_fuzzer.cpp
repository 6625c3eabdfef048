// libFuzzer target: a take's bytes through parse_arkit_take (infer/arkit_take.h) as CSV and as
// JSON lines, against a face model's expression names in the ICT spelling (so that Live Link's
// and MediaPipe's names match, and side-less names drive both sides).
#include <string>
#include <vector>

#include "core/error.h"
#include "core/log.h"
#include "fuzz/fuzz_input.h"
#include "infer/arkit_take.h"

namespace {

const std::vector<std::string>& expressions() {
  static const std::vector<std::string> names = {"browInnerUp_L", "browInnerUp_R", "eyeBlink_L",   "eyeBlink_R",
                                                 "jawOpen",       "mouthLeft",     "mouthSmile_L", "mouthSmile_R",
                                                 "cheekPuff_L",   "cheekPuff_R"};
  return names;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  retarget::log::set_level(retarget::log::Level::off);
  const std::string text(retarget::fuzz::bytes(data, size));
  for (const auto format : {retarget::ArkitTakeFormat::csv, retarget::ArkitTakeFormat::jsonl}) {
    try {
      const retarget::ArkitTake take = retarget::parse_arkit_take(text, "take", format, expressions());
      (void)retarget::arkit_frames_csv(take);
    } catch (const retarget::Error&) {
    }
  }
  return 0;
}
