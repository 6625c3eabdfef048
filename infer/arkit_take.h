// ARKit takes: per-frame blendshape weights from the face trackers people own (iPhone Live Link
// Face, MediaPipe's face blendshapes), named as ARKit names them, matched to a face model's
// expression names. infer/arkit_faces.h turns the frames into human face meshes.
//
// Two formats, told apart by the extension (.csv; .jsonl, .ndjson, .json) or else by the first
// character that is not blank ('{' or '[': JSON lines):
//
// CSV (Live Link Face): a header line of column names, then one line per frame, fields separated
// by commas, as many fields as the header has; blanks around a field, a UTF-8 byte order mark,
// CRLF line ends and blank lines are allowed, and a field wrapped in double quotes (no comma inside).
//   Timecode,BlendShapeCount,EyeBlinkLeft,EyeLookDownLeft,...,HeadYaw,HeadPitch,...
//   12:34:56:07.123,61,0.0312,0.2245,...
// `Timecode` (any column of that name, any case) is kept per frame as it is written;
// `BlendShapeCount` is not read. Every other column is a blendshape weight, a finite number.
//
// JSON lines: one JSON object per non-blank line, one line per frame, in either form:
//   {"timecode": "12:34:56:07.123", "weights": {"eyeBlinkLeft": 0.03, "jawOpen": 0.41}}
//   {"timecode": 1.25, "eyeBlinkLeft": 0.03, "jawOpen": 0.41}                      (flat)
// or in MediaPipe's list form (FaceLandmarker's face blendshapes: "index" and "displayName" not
// read; a list of such lists, one per face, gives the first face's), as the line itself or under
// "blendshapes":
//   [{"index": 0, "score": 0.0001, "categoryName": "_neutral"}, {"score": 0.41, "categoryName": "jawOpen"}]
//   {"timecode": 1.25, "blendshapes": [{"categoryName": "jawOpen", "score": 0.41}, ...]}
// An object with a "weights" key is the first form: "weights" is an object of name -> number and
// any key besides "timecode" and "weights" is reported as unused. Otherwise every key but
// "timecode" is a blendshape weight. "timecode" is optional, a string or a number (kept as
// written). A name a frame does not give is 0 in that frame.
//
// Names: a take's name drives the face model's expression of the same arkit_name_key():
// lower case, separators ('_', '-', '.', ' ') dropped, and a side suffix (`_L`/`_R`, `Left`/
// `Right`, any case) written `_l`/`_r`: EyeBlinkLeft, eyeBlinkLeft and eyeBlink_L are all
// "eyeblink_l", so Live Link's and MediaPipe's names meet the ICT model's and the synthetic
// human's. An exact (case-sensitive) name match comes first. A name without a side whose key the
// model lacks drives both sides when the model has them (ARKit's BrowInnerUp and CheekPuff ->
// ICT's browInnerUp_L + browInnerUp_R, cheekPuff_L + cheekPuff_R). Left and right are the face's
// own, in ARKit as in the ICT model and the synthetic human: nothing is mirrored.
//
// Reported once, not errors: unused names (no expression of the model; Live Link's head and
// eye rotations HeadYaw ... RightEyeRoll and MediaPipe's _neutral are named apart, at info
// level); the model's expressions no name drives (0 in every frame); weights outside ARKit's
// [0, 1] by at most kMaxArkitExcess, which are clamped into it (one warning with their count and
// the largest excess).
// The values of unused columns are not read.
//
// Errors that end the take (UnreadableTake, where = "file:line"): a byte that is not text (a
// binary file; core/text_bytes.h), a line longer than kMaxTakeLineBytes,
// a CSV header no column of which names an expression of the face model (a header of some other
// table, or junk), a JSON line naming weights none of which (nor any name before it) drives an
// expression.
//
// Errors (retarget::Error, where = "file:line", the message naming the column by number and name
// or the JSON key): an empty file or one without frames; a CSV without a header (a first line of
// numbers), an empty or repeated column name; a line with another field count than the header;
// a weight that is empty, not a number, NaN, infinite or farther than kMaxArkitExcess outside
// [0, 1]; two names driving one expression; a
// JSON line that is not valid JSON (naming the column), not an object, or holds a weight or
// timecode of another type, a number too large for a double (1e999).
#pragma once

#include <Eigen/Core>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/error.h"

namespace retarget {

// A take's (or a stream's) lines are at most this long (1 MiB; a frame of 61 ARKit weights is
// about 1 KB, MediaPipe's JSON about 4 KB).
inline constexpr size_t kMaxTakeLineBytes = size_t{1} << 20;

// Weights up to this far outside ARKit's [0, 1] are clamped into it (trackers overshoot a little);
// farther ones are an error naming the frame's line and column: not a weight.
inline constexpr double kMaxArkitExcess = 1;

// An error after which no further line of the take can be read (see above): a stream ends on it
// where it skips a malformed frame.
class UnreadableTake : public Error {
 public:
  using Error::Error;
};

enum class ArkitTakeFormat { csv, jsonl };

struct ArkitTake {
  std::string source;  // the file (or the name given to parse_arkit_take)
  ArkitTakeFormat format = ArkitTakeFormat::csv;
  std::vector<std::string> expressions;  // the face model's expression names: weights' columns
  Eigen::MatrixXd weights;               // #frames x #expressions, each in [0, 1]
  std::vector<std::string> timecodes;    // #frames, as written; "" for a frame without one
  std::vector<int> lines;                // #frames: the line of each frame in the file (from 1)
  std::vector<std::string> unused;       // the take's names that drive no expression, first seen first
  std::vector<std::string> missing;      // expressions no name drives (0 in every frame), model order
  int64_t clamped = 0;                   // weights that were outside [0, 1]
  double largest_excess = 0;             // how far the farthest of them was outside

  int frames() const { return static_cast<int>(weights.rows()); }
  bool has_timecodes() const;  // any frame has one
};

// The key names are matched by (above): "EyeBlinkLeft" -> "eyeblink_l", "mouthSmile_L" ->
// "mouthsmile_l", "JawOpen" -> "jawopen", "mouthLeft" -> "mouth_l".
std::string arkit_name_key(const std::string& name);

// For each take name, the expressions it drives (indices into `expressions`, empty: unused).
// Throws retarget::Error(where, ...) when two names drive one expression (naming both).
std::vector<std::vector<int>> match_arkit_names(const std::vector<std::string>& names,
                                                const std::vector<std::string>& expressions, const std::string& where);

// True for the columns trackers write that are not blendshapes (Live Link's HeadYaw, HeadPitch,
// HeadRoll, LeftEyeYaw ... RightEyeRoll; MediaPipe's _neutral), any case.
bool is_arkit_pose_column(const std::string& name);

// The format of `path` by its extension, else by the first non-blank character of `text`.
ArkitTakeFormat arkit_take_format(const std::string& path, const std::string& text);

// `text` in `format`, `source` naming it in messages; `expressions`: the face model's names.
// Logs the reports above (log::warn / log::info) and throws the errors above.
ArkitTake parse_arkit_take(const std::string& text, const std::string& source, ArkitTakeFormat format,
                           const std::vector<std::string>& expressions);

// One frame of a take as it arrives (ArkitRowParser).
struct ArkitRow {
  Eigen::VectorXd weights;  // #expressions, each in [0, 1] (clamped as parse_arkit_take clamps)
  std::string timecode;     // as written; "" for a frame without one
  int line = 0;             // its line (from 1)
};

// A take line by line, for frames that arrive one at a time (retarget-infer --stream): the same
// format, name matching, clamping and messages as parse_arkit_take, whose frame f is row() of its
// f-th frame line. A malformed frame line throws and leaves the parser ready for the next line.
class ArkitRowParser {
 public:
  // source: names the input in messages ("file:line"); expressions: the face model's names.
  ArkitRowParser(std::string source, ArkitTakeFormat format, std::vector<std::string> expressions);
  ~ArkitRowParser();
  ArkitRowParser(const ArkitRowParser&) = delete;
  ArkitRowParser& operator=(const ArkitRowParser&) = delete;

  // CSV: the header given ahead of the lines (text: column names separated by commas; line: the
  // number messages give it). Throws retarget::Error(source:line, ...) as parse_arkit_take does
  // for a bad header, or for a second header or a JSON lines parser.
  void header(std::string_view text, int line);
  bool has_header() const;  // JSON lines always; CSV once a header was read

  // One line (its line end, if any, is dropped; a UTF-8 byte order mark on line 1 too). nullopt
  // for a blank line and for a CSV header (the first non-blank line when header() was not
  // called); else the frame. Throws retarget::Error(source:line, "column N (Name): ...") for a
  // malformed frame, UnreadableTake for a bad header, bytes that are not text, a line over
  // kMaxTakeLineBytes or JSON names none of which drives an expression, as parse_arkit_take does.
  std::optional<ArkitRow> row(std::string_view text, int line);
  int frames() const;  // frames returned so far

  // What parse_arkit_take reports (unused names, expressions no name drives, clamped weights) for
  // the lines so far, in a take without frames; report_arkit_take logs them.
  ArkitTake reports() const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

// Logs a take's reports as parse_arkit_take does (log::warn / log::info; nothing for empty ones).
void report_arkit_take(const ArkitTake& take);

// Reads the file (throws retarget::Error(path, ...) when it cannot be read) and parses it.
ArkitTake read_arkit_take(const std::string& path, const std::vector<std::string>& expressions);

// The frames file retarget-infer --arkit writes beside its meshes: "frame,timecode" then one line
// per frame (index from 0, the timecode as the take has it, empty if none; RFC 4180 quotes for a
// timecode with a comma, a quote or a line break).
std::string arkit_frames_csv(const ArkitTake& take);

}  // namespace retarget
