// libFuzzer target: a bundle's manifest.yaml text through parse_bundle_manifest(), and the same
// bytes as bundle.pt's metadata.json through parse_bundle_metadata_json() (bundle/bundle_format.h).
#include <string>

#include "bundle/bundle_format.h"
#include "core/error.h"
#include "fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(retarget::fuzz::bytes(data, size));
  try {
    retarget::parse_bundle_manifest(text, "manifest.yaml");
  } catch (const retarget::Error&) {
  }
  try {
    retarget::parse_bundle_metadata_json(text, "bundle.pt");
  } catch (const retarget::Error&) {
  }
  return 0;
}
