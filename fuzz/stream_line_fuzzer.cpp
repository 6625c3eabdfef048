// libFuzzer target: the stream's line parser (retarget-infer --stream, infer/stream_run.h): the
// bytes split into lines and fed to ArkitRowParser one at a time, in the format the first
// non-blank line gives, as the stream's reader does: a malformed frame is skipped, an
// UnreadableTake ends the input. Then the reports the stream logs at its end.
#include <string>
#include <string_view>
#include <vector>

#include "core/error.h"
#include "core/log.h"
#include "fuzz/fuzz_input.h"
#include "infer/arkit_take.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  retarget::log::set_level(retarget::log::Level::off);
  static const std::vector<std::string> expressions = {"eyeBlink_L",   "eyeBlink_R",    "jawOpen",      "mouthSmile_L",
                                                       "mouthSmile_R", "browInnerUp_L", "browInnerUp_R"};
  const std::string_view text = retarget::fuzz::bytes(data, size);
  std::vector<std::string_view> lines;
  for (size_t start = 0; start < text.size();) {
    const size_t end = std::min(text.find('\n', start), text.size());
    lines.push_back(text.substr(start, end - start));
    start = end + 1;
  }
  std::string_view first;
  for (std::string_view line : lines)
    if (line.find_first_not_of(" \t\r") != std::string_view::npos) {
      first = line.substr(line.find_first_not_of(" \t\r"));
      break;
    }
  const auto format = !first.empty() && (first.front() == '{' || first.front() == '[')
                          ? retarget::ArkitTakeFormat::jsonl
                          : retarget::ArkitTakeFormat::csv;
  retarget::ArkitRowParser parser("stream", format, expressions);
  for (size_t l = 0; l < lines.size(); ++l) {
    try {
      (void)parser.row(lines[l], static_cast<int>(l + 1));
    } catch (const retarget::UnreadableTake&) {
      break;
    } catch (const retarget::Error&) {
    }
  }
  (void)parser.reports();
  return 0;
}
