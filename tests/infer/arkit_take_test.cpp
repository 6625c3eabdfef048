#include "infer/arkit_take.h"

#include <string>
#include <vector>

#include "tests/infer/arkit_test_support.h"

namespace retarget::test {

namespace {

ArkitTake csv_take(const std::string& text) {
  return parse_arkit_take(text, "take.csv", ArkitTakeFormat::csv, arkit_test_names());
}
ArkitTake jsonl_take(const std::string& text) {
  return parse_arkit_take(text, "take.jsonl", ArkitTakeFormat::jsonl, arkit_test_names());
}
int expression_column(const ArkitTake& take, const std::string& expression) {
  for (size_t k = 0; k < take.expressions.size(); ++k)
    if (take.expressions[k] == expression) return static_cast<int>(k);
  FAIL("no expression " << expression);
  return -1;
}

}  // namespace

TEST_CASE("arkit_name_key brings Live Link's, MediaPipe's and the ICT model's spellings together", "[arkit]") {
  struct Row {
    const char* name;
    const char* key;
  };
  const std::vector<Row> rows = {
      {"EyeBlinkLeft", "eyeblink_l"},   {"eyeBlinkLeft", "eyeblink_l"},
      {"eyeBlink_L", "eyeblink_l"},     {"EYEBLINK_l", "eyeblink_l"},
      {"eyeBlink_Left", "eyeblink_l"},  {"MouthSmileRight", "mouthsmile_r"},
      {"mouthSmile_R", "mouthsmile_r"}, {"JawOpen", "jawopen"},
      {"jawOpen", "jawopen"},           {"mouthLeft", "mouth_l"},
      {"MouthLeft", "mouth_l"},         {"BrowInnerUp", "browinnerup"},
      {" jawOpen ", "jawopen"},         {"Left", "left"},
      {"_neutral", "neutral"},
  };
  for (const Row& row : rows) {
    INFO(row.name);
    CHECK(arkit_name_key(row.name) == row.key);
  }
}

TEST_CASE("match_arkit_names: exact first, then by key, unsided names drive both sides", "[arkit]") {
  const std::vector<std::string> names = {"EyeBlinkLeft", "eyeBlink_R", "JAWOPEN", "BrowInnerUp",
                                          "MouthLeft",    "TongueOut",  "HeadYaw"};
  const std::vector<std::vector<int>> targets = match_arkit_names(names, arkit_test_names(), "take");
  REQUIRE(targets.size() == names.size());
  CHECK(targets[0] == std::vector<int>{4});     // eyeBlink_L
  CHECK(targets[1] == std::vector<int>{5});     // eyeBlink_R
  CHECK(targets[2] == std::vector<int>{6});     // jawOpen
  CHECK(targets[3] == std::vector<int>{0, 1});  // browInnerUp_L and _R
  CHECK(targets[4] == std::vector<int>{7});     // mouthLeft (not a side of "mouth")
  CHECK(targets[5].empty());
  CHECK(targets[6].empty());

  const std::string twice = error_of([] {
    match_arkit_names({"EyeBlinkLeft", "eyeBlink_L"}, arkit_test_names(), "take");
  });
  CHECK(twice ==
        "take: \"eyeBlink_L\" and \"EyeBlinkLeft\" both drive the expression \"eyeBlink_L\"; keep one of them");
  const std::string alike = error_of([] { match_arkit_names({"mouth_l"}, {"mouthLeft", "mouth_L"}, "take"); });
  CHECK(alike ==
        "take: \"mouth_l\" matches the face model's expressions mouthLeft, mouth_L alike; name one of them exactly");
  CHECK(is_arkit_pose_column("HeadYaw"));
  CHECK(is_arkit_pose_column("righteyeroll"));
  CHECK(is_arkit_pose_column("_neutral"));
  CHECK_FALSE(is_arkit_pose_column("JawOpen"));
}

TEST_CASE("a Live Link Face CSV: timecodes, weights by either spelling, unused and missing columns", "[arkit]") {
  LogCapture log;
  const std::string text =
      "\xEF\xBB\xBFTimecode,BlendShapeCount,EyeBlinkLeft,eyeBlink_R,JawOpen,BrowInnerUp,TongueOut,HeadYaw,"
      "LeftEyePitch\r\n"
      "12:34:56:07.123,61,0.25,0.5,1,0.125,0.9,12.5,-3\r\n"
      "\r\n"
      "12:34:56:08.456, 61 , 0 ,0.75, 0.5 ,0,0.1,x,y\r\n";
  const ArkitTake take = csv_take(text);
  CHECK(take.format == ArkitTakeFormat::csv);
  REQUIRE(take.frames() == 2);
  CHECK(take.timecodes == std::vector<std::string>{"12:34:56:07.123", "12:34:56:08.456"});
  CHECK(take.has_timecodes());
  CHECK(take.lines == std::vector<int>{2, 4});
  CHECK(take.expressions == arkit_test_names());
  CHECK(take.weights(0, expression_column(take, "eyeBlink_L")) == 0.25);
  CHECK(take.weights(0, expression_column(take, "eyeBlink_R")) == 0.5);
  CHECK(take.weights(0, expression_column(take, "jawOpen")) == 1);
  CHECK(take.weights(0, expression_column(take, "browInnerUp_L")) == 0.125);
  CHECK(take.weights(0, expression_column(take, "browInnerUp_R")) == 0.125);
  CHECK(take.weights(1, expression_column(take, "eyeBlink_R")) == 0.75);
  CHECK(take.weights(1, expression_column(take, "jawOpen")) == 0.5);
  CHECK(take.weights.row(0).sum() == 0.25 + 0.5 + 1 + 0.125 + 0.125);
  CHECK(take.unused == std::vector<std::string>{"TongueOut", "HeadYaw", "LeftEyePitch"});
  CHECK(take.missing == std::vector<std::string>{"cheekPuff_L", "cheekPuff_R", "mouthLeft", "mouthPucker", "mouthRight",
                                                 "mouthSmile_L", "mouthSmile_R"});
  CHECK(take.clamped == 0);
  // One report each: unknown names warn, head and eye rotations are named apart (info).
  CHECK(log.count(log::Level::warn, "take.csv: 1 name matches no expression of the face model, not used: TongueOut") ==
        1);
  CHECK(log.count(log::Level::info,
                  "not used (head and eye rotations; retargeting carries the blendshapes): HeadYaw, "
                  "LeftEyePitch") == 1);
  CHECK(log.count(log::Level::warn,
                  "take.csv: 7 of the face model's 12 expressions in no column of the take, held at "
                  "0: cheekPuff_L, cheekPuff_R") == 1);
  CHECK(log.lines.size() == 3);
}

TEST_CASE("a CSV without timecodes, with a trailing comma and the ICT spelling in any case", "[arkit]") {
  const ArkitTake take = csv_take("EYEBLINK_L,mouthsmile_r,\n0.5,0.25,\n1,0\n");
  REQUIRE(take.frames() == 2);
  CHECK_FALSE(take.has_timecodes());
  CHECK(take.timecodes == std::vector<std::string>{"", ""});
  CHECK(take.weights(0, expression_column(take, "eyeBlink_L")) == 0.5);
  CHECK(take.weights(0, expression_column(take, "mouthSmile_R")) == 0.25);
  CHECK(take.weights(1, expression_column(take, "eyeBlink_L")) == 1);
  CHECK(take.unused.empty());
}

TEST_CASE("weights outside [0, 1] are clamped with one warning", "[arkit]") {
  LogCapture log;
  const ArkitTake take = csv_take("Timecode,JawOpen,EyeBlinkLeft\na,1.25,-0.0625\nb,0.5,2\n");
  CHECK(take.weights(0, expression_column(take, "jawOpen")) == 1);
  CHECK(take.weights(0, expression_column(take, "eyeBlink_L")) == 0);
  CHECK(take.weights(1, expression_column(take, "eyeBlink_L")) == 1);
  CHECK(take.clamped == 3);
  CHECK(take.largest_excess == 1);
  CHECK(log.count(log::Level::warn,
                  "take.csv: 3 weights outside ARKit's range [0, 1] clamped into it (the farthest by 1)") == 1);
}

TEST_CASE("every malformed CSV is an error naming the file, line and column", "[arkit]") {
  struct Row {
    const char* text;
    const char* message;
  };
  const std::vector<Row> rows = {
      {"", "take.csv: an empty take: no header and no frames"},
      {"\n  \r\n\n", "take.csv: an empty take: no header and no frames"},
      {"0.5,0.25\n0.5,0.5\n",
       "take.csv:1: column 1: expected a header of column names (Timecode, BlendShapeCount, EyeBlinkLeft, ...) on the "
       "first line, got the number \"0.5\"; the take has no header"},
      {"Timecode,JawOpen\n", "take.csv: no frames: only a header (line 1)"},
      {"\nTimecode,JawOpen\n\n", "take.csv: no frames: only a header (line 2)"},
      {"Timecode,,JawOpen\n", "take.csv:1: column 2: an empty column name"},
      {"Timecode,JawOpen,jawopen\n", "take.csv:1: column 3 (jawopen): the same name as column 2 (JawOpen)"},
      {"Timecode,JawOpen,jawOpen\n", "take.csv:1: column 3 (jawOpen): the same name as column 2 (JawOpen)"},
      {"Timecode,EyeBlinkLeft,eyeBlink_L\n",
       "take.csv:1: column 3: \"eyeBlink_L\" and \"EyeBlinkLeft\" both drive the expression \"eyeBlink_L\"; keep one "
       "of "
       "them"},
      {"Timecode,JawOpen\n1,abc\n", "take.csv:2: column 2 (JawOpen): expected a number, got \"abc\""},
      {"Timecode,JawOpen\n1,0.5\n\n2,0.5x\n", "take.csv:4: column 2 (JawOpen): expected a number, got \"0.5x\""},
      {"Timecode,JawOpen\n1,\n", "take.csv:2: column 2 (JawOpen): an empty field, expected a number"},
      {"Timecode,JawOpen\n1,  \n", "take.csv:2: column 2 (JawOpen): an empty field, expected a number"},
      {"Timecode,JawOpen\n1,nan\n",
       "take.csv:2: column 2 (JawOpen): \"nan\" is not a weight (NaN); expected a finite number"},
      {"Timecode,JawOpen\n1,NaN\n",
       "take.csv:2: column 2 (JawOpen): \"NaN\" is not a weight (NaN); expected a finite number"},
      {"Timecode,JawOpen\n1,-inf\n",
       "take.csv:2: column 2 (JawOpen): \"-inf\" is not a weight (infinite); expected a finite number"},
      {"Timecode,JawOpen\n1,1e999\n", "take.csv:2: column 2 (JawOpen): the number \"1e999\" is out of range"},
      {"Timecode,JawOpen\n1,1e300\n",
       "take.csv:2: column 2 (JawOpen): the weight 1e300 is far outside ARKit's range [0, 1] (up to 1 beyond it is "
       "clamped); is this column a blendshape weight?"},
      {"Timecode,JawOpen\n1,-1.5\n",
       "take.csv:2: column 2 (JawOpen): the weight -1.5 is far outside ARKit's range [0, 1] (up to 1 beyond it is "
       "clamped); is this column a blendshape weight?"},
      {"Timecode,JawOpen,EyeBlinkLeft\n1,0.5\n",
       "take.csv:2: 2 fields but the header (line 1) has 3: column 3 (EyeBlinkLeft) is missing"},
      {"Timecode,JawOpen\n1,0.5,0.25\n", "take.csv:2: 3 fields but the header (line 1) has 2: column 3 has no name"},
      {"Timecode,JawOpen\n1,0.5\n2\n",
       "take.csv:3: 1 fields but the header (line 1) has 2: column 2 (JawOpen) is missing"},
  };
  for (const Row& row : rows) {
    INFO(row.text);
    CHECK(error_of([&] { csv_take(row.text); }) == row.message);
  }
}

TEST_CASE("a take that cannot be read ends with one error naming its line: junk headers, bytes that are not text",
          "[arkit]") {
  struct Row {
    std::string text;
    bool jsonl;
    std::string message;
  };
  const std::string huge(kMaxTakeLineBytes + 10, '0');
  const std::vector<Row> rows = {
      {"foo;bar\n1\n2\n", false,
       "take.csv:1: no column of the header names an expression of the face model (1 column: foo;bar); a take's first "
       "line names its blendshapes (EyeBlinkLeft, JawOpen, ...)"},
      {"Timecode,HeadYaw,Mystery\n1,0.1,0.2\n", false,
       "take.csv:1: no column of the header names an expression of the face model (3 columns: Timecode, HeadYaw, "
       "Mystery); a take's first line names its blendshapes (EyeBlinkLeft, JawOpen, ...)"},
      {"\x89PNG\r\n\x1a\n", false,
       "take.csv:1: column 1: byte 0x89 is not text; a take is a CSV or JSON lines text file (is this a binary file?)"},
      {std::string("Timecode,JawOpen\n1,0.\0"
                   "5\n",
                   24),
       false,
       "take.csv:2: column 5: byte 0x00 is not text; a take is a CSV or JSON lines text file (is this a binary file?)"},
      {"Timecode,JawOpen\n1," + huge + "\n", false,
       "take.csv:2: a line longer than a take's lines may be (1048576 bytes); is this a take?"},
      {"{\"jawOpen\": 7}\n", true,
       "take.jsonl:1: key \"jawOpen\" (column 13): the weight 7 is far outside ARKit's range [0, 1] (up to 1 beyond it "
       "is clamped); is this column a blendshape weight?"},
      {"{\"jawOpen\": 0.5}\n{\"jawOpen\": 1e999}\n", true,
       "take.jsonl:2: a number too large for a double (beyond 1.8e308); expected weights in [0, 1]"},
      {"{\"timecode\": 1, \"foo\": 0.5, \"bar\": 0.25}\n", true,
       "take.jsonl:1: no name on this line (nor on a line before it) names an expression of the face model (foo, bar); "
       "a take's weights are named as ARKit names them (eyeBlinkLeft, jawOpen, ...)"},
  };
  for (const Row& row : rows) {
    INFO(row.message);
    CHECK(error_of([&] { row.jsonl ? jsonl_take(row.text) : csv_take(row.text); }) == row.message);
  }
  // 100 KB of random bytes: one message about the first byte that is not text, not a parse error.
  std::string junk(100000, '\0');
  uint64_t x = 88172645463325252ull;
  for (char& c : junk) {
    x ^= x << 13, x ^= x >> 7, x ^= x << 17;
    c = static_cast<char>(x & 0xFF);
  }
  CHECK_THROWS_AS(csv_take(junk), UnreadableTake);
  CHECK_THAT(error_of([&] { csv_take(junk); }), Catch::Matchers::Contains("is not text; a take is a CSV"));
  // A frame that names nothing the model knows is fine once a known name was seen.
  CHECK(jsonl_take("{\"jawOpen\": 0.5}\n{\"foo\": 0.5}\n").frames() == 2);
}

TEST_CASE("JSON lines: the nested and the flat form, timecodes as strings or numbers", "[arkit]") {
  LogCapture log;
  const std::string text =
      "{\"timecode\": \"00:00:01:02.5\", \"weights\": {\"eyeBlinkLeft\": 0.5, \"jawOpen\": 0.25, \"_neutral\": 0.1}, "
      "\"source\": \"mediapipe\"}\n"
      "\n"
      "{\"timecode\": 1.25, \"eyeBlinkRight\": 1, \"cheekPuff\": 0.5, \"tongueOut\": \"x\"}\n"
      "{\"mouthSmileRight\": 0.75}\r\n";
  const ArkitTake take = jsonl_take(text);
  CHECK(take.format == ArkitTakeFormat::jsonl);
  REQUIRE(take.frames() == 3);
  CHECK(take.timecodes == std::vector<std::string>{"00:00:01:02.5", "1.25", ""});
  CHECK(take.lines == std::vector<int>{1, 3, 4});
  CHECK(take.weights(0, expression_column(take, "eyeBlink_L")) == 0.5);
  CHECK(take.weights(0, expression_column(take, "jawOpen")) == 0.25);
  CHECK(take.weights.row(0).sum() == 0.75);
  CHECK(take.weights(1, expression_column(take, "eyeBlink_R")) == 1);
  CHECK(take.weights(1, expression_column(take, "eyeBlink_L")) == 0);  // not given in that frame
  CHECK(take.weights(1, expression_column(take, "cheekPuff_L")) == 0.5);
  CHECK(take.weights(1, expression_column(take, "cheekPuff_R")) == 0.5);
  CHECK(take.weights(2, expression_column(take, "mouthSmile_R")) == 0.75);
  CHECK(take.weights.row(2).sum() == 0.75);
  CHECK(take.unused == std::vector<std::string>{"_neutral", "tongueOut", "source"});
  CHECK(take.missing == std::vector<std::string>{"browInnerUp_L", "browInnerUp_R", "mouthLeft", "mouthPucker",
                                                 "mouthRight", "mouthSmile_L"});
  CHECK(log.count(log::Level::warn,
                  "take.jsonl: 2 names match no expression of the face model, not used: tongueOut, "
                  "source") == 1);
  CHECK(log.count(log::Level::info, "_neutral") == 1);
}

TEST_CASE("JSON lines in MediaPipe's list form give the same frames as the object form", "[arkit]") {
  const ArkitTake listed = jsonl_take(
      "[{\"index\": 0, \"score\": 0.1, \"categoryName\": \"_neutral\", \"displayName\": \"\"}, "
      "{\"index\": 1, \"score\": 0.5, \"categoryName\": \"eyeBlinkLeft\"}, {\"score\": 0.25, \"categoryName\": "
      "\"jawOpen\"}]\n"
      "{\"timecode\": 1.25, \"blendshapes\": [{\"categoryName\": \"eyeBlinkRight\", \"score\": 1}], \"face\": 0}\n"
      "[[{\"categoryName\": \"mouthSmileRight\", \"score\": 0.75}], [{\"categoryName\": \"jawOpen\", \"score\": "
      "1}]]\n");
  const ArkitTake object = jsonl_take(
      "{\"_neutral\": 0.1, \"eyeBlinkLeft\": 0.5, \"jawOpen\": 0.25}\n"
      "{\"timecode\": 1.25, \"eyeBlinkRight\": 1}\n"
      "{\"mouthSmileRight\": 0.75}\n");
  REQUIRE(listed.frames() == 3);
  CHECK(listed.weights == object.weights);
  CHECK(listed.timecodes == object.timecodes);
  CHECK(listed.weights(0, expression_column(listed, "eyeBlink_L")) == 0.5);
  CHECK(listed.weights(2, expression_column(listed, "jawOpen")) == 0);  // the second face is not read
  CHECK(listed.unused == std::vector<std::string>{"_neutral", "face"});
}

TEST_CASE("every malformed JSON line is an error naming the file, line and column or key", "[arkit]") {
  struct Row {
    const char* text;
    const char* message;
  };
  const std::vector<Row> rows = {
      {"", "take.jsonl: an empty take: no frames"},
      {"{\"jawOpen\": 0.5}\n3\n",
       "take.jsonl:2: column 1: expected one JSON object per line ({\"timecode\": ..., \"weights\": {name: weight, "
       "...}} or {name: weight, ...}) or MediaPipe's list of {\"categoryName\": ..., \"score\": ...}, got 3"},
      {"{\"jawOpen\": 0.5}\n[1, 2]\n",
       "take.jsonl:2: key \"blendshapes\", entry 1: expected {\"categoryName\": ..., \"score\": ...}, got 1"},
      {"[{\"categoryName\": \"jawOpen\"}]\n", "take.jsonl:1: key \"blendshapes\", entry 1 (\"jawOpen\"): no \"score\""},
      {"{\"blendshapes\": [{\"score\": 0.5}]}\n",
       "take.jsonl:1: key \"blendshapes\" (column 17), entry 1: no \"categoryName\" string"},
      {"{\"jawOpen\": \"x\"}\n", "take.jsonl:1: key \"jawOpen\" (column 13): expected a number, got the string \"x\""},
      {"{\"jawOpen\": null}\n", "take.jsonl:1: key \"jawOpen\" (column 13): expected a number, got null"},
      {"{\"weights\": {\"jawOpen\": true}}\n",
       "take.jsonl:1: key \"jawOpen\" (column 25): expected a number, got true"},
      {"{\"jawOpen\": 0.5}\n{\"jawOpen\": NaN}\n",
       "take.jsonl:2: column 13: NaN is not a weight; expected a finite number"},
      {"{\"jawOpen\": -Infinity}\n", "take.jsonl:1: column 14: Infinity is not a weight; expected a finite number"},
      {"{\"timecode\": [1], \"jawOpen\": 0}\n",
       "take.jsonl:1: key \"timecode\" (column 14): expected a string or a number, got an array"},
      {"{\"weights\": 3}\n", "take.jsonl:1: key \"weights\" (column 13): expected an object of name -> weight, got 3"},
      {"{\"eyeBlinkLeft\": 0.5}\n{\"eyeBlink_L\": 0.5}\n",
       "take.jsonl:2: key \"eyeBlink_L\" (column 16): \"eyeBlink_L\" and \"eyeBlinkLeft\" both drive the expression "
       "\"eyeBlink_L\"; keep one of them"},
  };
  for (const Row& row : rows) {
    INFO(row.text);
    CHECK(error_of([&] { jsonl_take(row.text); }) == row.message);
  }
  // Invalid JSON: the column of the parser's complaint.
  const std::string broken = error_of([] { jsonl_take("{\"jawOpen\": 0.5}\n{\"jawOpen\": 0.5,}\n"); });
  CHECK(broken.rfind("take.jsonl:2: column 17: not valid JSON: ", 0) == 0);
  const std::string cut = error_of([] { jsonl_take("{\"jawOpen\": 0.5\n"); });
  CHECK(cut.rfind("take.jsonl:1: column ", 0) == 0);
  CHECK(cut.find("not valid JSON") != std::string::npos);
}

TEST_CASE("read_arkit_take tells the formats apart and names unreadable files", "[arkit]") {
  const auto dir = process_scratch_dir("arkit_take");
  const std::vector<std::map<std::string, double>> frames = arkit_test_frames(4);
  const ArkitTake from_csv = read_arkit_take(write_file(dir / "take.csv", live_link_csv(frames)), arkit_test_names());
  const ArkitTake from_jsonl = read_arkit_take(write_file(dir / "take.jsonl", ict_jsonl(frames)), arkit_test_names());
  const ArkitTake sniffed = read_arkit_take(write_file(dir / "take.txt", ict_jsonl(frames)), arkit_test_names());
  CHECK(from_csv.format == ArkitTakeFormat::csv);
  CHECK(from_jsonl.format == ArkitTakeFormat::jsonl);
  CHECK(sniffed.format == ArkitTakeFormat::jsonl);
  CHECK(from_csv.source == (dir / "take.csv").string());
  CHECK(from_csv.weights == from_jsonl.weights);
  CHECK(from_csv.timecodes == from_jsonl.timecodes);
  CHECK(from_csv.timecodes[3] == live_link_timecode(3));
  CHECK(from_csv.unused == std::vector<std::string>{"HeadYaw", "HeadPitch", "HeadRoll"});
  CHECK(from_csv.missing.empty());
  for (int f = 0; f < 4; ++f)
    for (const auto& [name, w] : frames[f]) CHECK(from_csv.weights(f, expression_column(from_csv, name)) == w);

  CHECK(arkit_take_format("a.CSV", "{") == ArkitTakeFormat::csv);
  CHECK(arkit_take_format("a.ndjson", "") == ArkitTakeFormat::jsonl);
  CHECK(arkit_take_format("a", "\n  {\"jawOpen\": 1}") == ArkitTakeFormat::jsonl);
  CHECK(arkit_take_format("a", "Timecode,JawOpen") == ArkitTakeFormat::csv);

  const std::string missing = (dir / "nope.csv").string();
  CHECK(error_of([&] { read_arkit_take(missing, arkit_test_names()); }) ==
        missing + ": cannot read the take: no such file or no permission");
  CHECK(error_of([&] { read_arkit_take(dir.string(), arkit_test_names()); }) ==
        dir.string() + ": is a folder; expected a take file (.csv or .jsonl)");
}

TEST_CASE("Live Link Face's and MediaPipe's names meet the ICT model's 53 expressions", "[arkit]") {
  // The ICT-FaceKit model's expression names (its expressions/ folder) and the two trackers'
  // blendshape names, as they write them.
  const std::vector<std::string> ict = {
      "browDown_L",       "browDown_R",      "browInnerUp_L",   "browInnerUp_R", "browOuterUp_L", "browOuterUp_R",
      "cheekPuff_L",      "cheekPuff_R",     "cheekSquint_L",   "cheekSquint_R", "eyeBlink_L",    "eyeBlink_R",
      "eyeLookDown_L",    "eyeLookDown_R",   "eyeLookIn_L",     "eyeLookIn_R",   "eyeLookOut_L",  "eyeLookOut_R",
      "eyeLookUp_L",      "eyeLookUp_R",     "eyeSquint_L",     "eyeSquint_R",   "eyeWide_L",     "eyeWide_R",
      "jawForward",       "jawLeft",         "jawOpen",         "jawRight",      "mouthClose",    "mouthDimple_L",
      "mouthDimple_R",    "mouthFrown_L",    "mouthFrown_R",    "mouthFunnel",   "mouthLeft",     "mouthLowerDown_L",
      "mouthLowerDown_R", "mouthPress_L",    "mouthPress_R",    "mouthPucker",   "mouthRight",    "mouthRollLower",
      "mouthRollUpper",   "mouthShrugLower", "mouthShrugUpper", "mouthSmile_L",  "mouthSmile_R",  "mouthStretch_L",
      "mouthStretch_R",   "mouthUpperUp_L",  "mouthUpperUp_R",  "noseSneer_L",   "noseSneer_R"};
  const std::string live_link =
      "Timecode,BlendShapeCount,EyeBlinkLeft,EyeLookDownLeft,EyeLookInLeft,EyeLookOutLeft,EyeLookUpLeft,"
      "EyeSquintLeft,EyeWideLeft,EyeBlinkRight,EyeLookDownRight,EyeLookInRight,EyeLookOutRight,EyeLookUpRight,"
      "EyeSquintRight,EyeWideRight,JawForward,JawRight,JawLeft,JawOpen,MouthClose,MouthFunnel,MouthPucker,MouthRight,"
      "MouthLeft,MouthSmileLeft,MouthSmileRight,MouthFrownLeft,MouthFrownRight,MouthDimpleLeft,MouthDimpleRight,"
      "MouthStretchLeft,MouthStretchRight,MouthRollLower,MouthRollUpper,MouthShrugLower,MouthShrugUpper,"
      "MouthPressLeft,MouthPressRight,MouthLowerDownLeft,MouthLowerDownRight,MouthUpperUpLeft,MouthUpperUpRight,"
      "BrowDownLeft,BrowDownRight,BrowInnerUp,BrowOuterUpLeft,BrowOuterUpRight,CheekPuff,CheekSquintLeft,"
      "CheekSquintRight,NoseSneerLeft,NoseSneerRight,TongueOut,HeadYaw,HeadPitch,HeadRoll,LeftEyeYaw,LeftEyePitch,"
      "LeftEyeRoll,RightEyeYaw,RightEyePitch,RightEyeRoll";
  std::string row = "20:15:42:11.250,61";
  for (int k = 2; k < 63; ++k) row += ",0.5";
  LogCapture log;
  const ArkitTake take = parse_arkit_take(live_link + "\n" + row + "\n", "live.csv", ArkitTakeFormat::csv, ict);
  CHECK(take.missing.empty());
  CHECK(take.unused == std::vector<std::string>{"TongueOut", "HeadYaw", "HeadPitch", "HeadRoll", "LeftEyeYaw",
                                                "LeftEyePitch", "LeftEyeRoll", "RightEyeYaw", "RightEyePitch",
                                                "RightEyeRoll"});
  CHECK(take.weights.minCoeff() == 0.5);  // every expression driven, BrowInnerUp and CheekPuff on both sides
  CHECK(log.count(log::Level::warn, "live.csv: 1 name matches no expression of the face model, not used: TongueOut") ==
        1);
  CHECK(log.lines.size() == 2);

  const std::vector<std::string> mediapipe = {
      "_neutral",         "browDownLeft",      "browDownRight",      "browInnerUp",
      "browOuterUpLeft",  "browOuterUpRight",  "cheekPuff",          "cheekSquintLeft",
      "cheekSquintRight", "eyeBlinkLeft",      "eyeBlinkRight",      "eyeLookDownLeft",
      "eyeLookDownRight", "eyeLookInLeft",     "eyeLookInRight",     "eyeLookOutLeft",
      "eyeLookOutRight",  "eyeLookUpLeft",     "eyeLookUpRight",     "eyeSquintLeft",
      "eyeSquintRight",   "eyeWideLeft",       "eyeWideRight",       "jawForward",
      "jawLeft",          "jawOpen",           "jawRight",           "mouthClose",
      "mouthDimpleLeft",  "mouthDimpleRight",  "mouthFrownLeft",     "mouthFrownRight",
      "mouthFunnel",      "mouthLeft",         "mouthLowerDownLeft", "mouthLowerDownRight",
      "mouthPressLeft",   "mouthPressRight",   "mouthPucker",        "mouthRight",
      "mouthRollLower",   "mouthRollUpper",    "mouthShrugLower",    "mouthShrugUpper",
      "mouthSmileLeft",   "mouthSmileRight",   "mouthStretchLeft",   "mouthStretchRight",
      "mouthUpperUpLeft", "mouthUpperUpRight", "noseSneerLeft",      "noseSneerRight"};
  std::string line;
  for (const std::string& name : mediapipe) line += (line.empty() ? "{" : ", ") + ("\"" + name + "\": 0.25");
  const ArkitTake mp = parse_arkit_take(line + "}\n", "mp.jsonl", ArkitTakeFormat::jsonl, ict);
  CHECK(mp.missing.empty());
  CHECK(mp.unused == std::vector<std::string>{"_neutral"});
  CHECK(mp.weights.minCoeff() == 0.25);
}

TEST_CASE("arkit_frames_csv: frame index and timecode, quoted when it must be", "[arkit]") {
  const ArkitTake take = jsonl_take(
      "{\"timecode\": \"00:00:01:02.5\", \"jawOpen\": 0.5}\n{\"jawOpen\": 0.25}\n"
      "{\"timecode\": \"a,\\\"b\\\"\", \"jawOpen\": 0}\n");
  CHECK(arkit_frames_csv(take) == "frame,timecode\n0,00:00:01:02.5\n1,\n2,\"a,\"\"b\"\"\"\n");
}

}  // namespace retarget::test
