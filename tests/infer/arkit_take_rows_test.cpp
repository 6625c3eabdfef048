// ArkitRowParser (infer/arkit_take.h): a take line by line gives parse_arkit_take's frames, and a
// malformed line throws parse_arkit_take's message and leaves the parser usable.
#include <catch2/catch.hpp>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "core/error.h"
#include "infer/arkit_take.h"
#include "tests/infer/arkit_test_support.h"

namespace retarget::test {
// The helpers and test cases in a namespace of their own: unity builds put several test files together.
namespace arkit_take_rows_test {

std::vector<std::string> text_lines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

// The frames of `text` fed line by line.
std::vector<ArkitRow> rows_of(ArkitRowParser& parser, const std::string& text) {
  std::vector<ArkitRow> rows;
  const std::vector<std::string> lines = text_lines(text);
  for (size_t l = 0; l < lines.size(); ++l)
    if (std::optional<ArkitRow> row = parser.row(lines[l], static_cast<int>(l) + 1)) rows.push_back(*row);
  return rows;
}

TEST_CASE("ArkitRowParser gives parse_arkit_take's frames line by line, CSV and JSON lines", "[arkit]") {
  const LogCapture log;
  const std::vector<std::string>& names = arkit_test_names();
  std::vector<std::map<std::string, double>> frames = arkit_test_frames(7);
  frames[3]["jawOpen"] = 1.25;  // clamped alike
  for (const ArkitTakeFormat format : {ArkitTakeFormat::csv, ArkitTakeFormat::jsonl}) {
    INFO((format == ArkitTakeFormat::csv ? "CSV" : "JSON lines"));
    const std::string text = format == ArkitTakeFormat::csv ? live_link_csv(frames) : ict_jsonl(frames);
    const ArkitTake take = parse_arkit_take(text, "take", format, names);
    ArkitRowParser parser("take", format, names);
    const std::vector<ArkitRow> rows = rows_of(parser, text);
    REQUIRE(static_cast<int>(rows.size()) == take.frames());
    CHECK(parser.frames() == take.frames());
    for (int f = 0; f < take.frames(); ++f) {
      INFO("frame " << f);
      CHECK(rows[f].weights == take.weights.row(f).transpose());
      CHECK(rows[f].timecode == take.timecodes[f]);
      CHECK(rows[f].line == take.lines[f]);
    }
    const ArkitTake reports = parser.reports();
    CHECK(reports.unused == take.unused);
    CHECK(reports.missing == take.missing);
    CHECK(reports.clamped == take.clamped);
    CHECK(reports.largest_excess == take.largest_excess);
  }
}

TEST_CASE("ArkitRowParser: a header given ahead, blank lines, CRLF; a malformed line throws and the next one reads",
          "[arkit]") {
  const std::vector<std::string>& names = arkit_test_names();
  ArkitRowParser parser("live", ArkitTakeFormat::csv, names);
  CHECK_FALSE(parser.has_header());
  parser.header("Timecode,JawOpen,EyeBlinkLeft", 1);
  CHECK(parser.has_header());
  CHECK_FALSE(parser.row("  ", 2));
  const std::optional<ArkitRow> first = parser.row("00:00:01,0.5,0.25\r", 3);
  REQUIRE(first);
  CHECK(first->timecode == "00:00:01");
  CHECK(first->weights[6] == 0.5);   // jawOpen
  CHECK(first->weights[4] == 0.25);  // eyeBlink_L
  CHECK_THROWS_WITH(parser.row("00:00:02,0.5,x", 4), "live:4: column 3 (EyeBlinkLeft): expected a number, got \"x\"");
  CHECK_THROWS_WITH(parser.row("00:00:02,0.5", 5),
                    "live:5: 2 fields but the header (line 1) has 3: column 3 (EyeBlinkLeft) is missing");
  const std::optional<ArkitRow> next = parser.row("00:00:03,1,0", 6);
  REQUIRE(next);
  CHECK(next->line == 6);
  CHECK(parser.frames() == 2);
  CHECK_THROWS_WITH(parser.header("Timecode", 7), "live:7: a second header");

  ArkitRowParser jsonl("live", ArkitTakeFormat::jsonl, names);
  CHECK(jsonl.has_header());
  CHECK_THROWS_WITH(jsonl.row("{\"jawOpen\": 0.5,", 1), Catch::Matchers::StartsWith("live:1: column "));
  REQUIRE(jsonl.row("{\"jawOpen\": 0.5}", 2));
}

}  // namespace arkit_take_rows_test
}  // namespace retarget::test
