// Controller weights per frame as CSV, the table `retarget-infer --weights` writes
// (infer/weights_output.h):
//   frame,<controller 1>,...,<controller C>,residual_mm
//   jawOpen_0001,0.25,...,0,0.12
// one row per frame in play order, weights in the rig's controller order; `frame` is the
// frame's name (the input file's stem), residual_mm the fit's mean distance (optional, may be
// nan). Read back to play the sequence elsewhere (infer/gltf_animation.h).
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

namespace retarget {

// The largest controller weight a weights CSV may hold, in magnitude.
inline constexpr double kMaxControllerWeight = 1000;

struct WeightsCsv {
  std::string source;                    // the file, for messages
  std::vector<std::string> controllers;  // C column names between `frame` and `residual_mm`
  std::vector<std::string> frames;       // F: the `frame` column as written
  std::vector<Eigen::VectorXd> weights;  // F rows, each C weights
  std::vector<double> residual_mm;       // F, or empty when the file has no residual_mm column
};

// Reads a weights CSV: RFC 4180 (fields in double quotes may hold commas, "" and line breaks),
// `\n` or `\r\n` line ends, blank lines skipped, blanks around an unquoted field ignored.
// Throws retarget::Error naming "file:line" for: a missing or unreadable file, a header that
// does not start with `frame` or names no controller, duplicate or empty column names, a row
// with another number of fields than the header, a weight that is not a finite number or is
// beyond +-kMaxControllerWeight (naming its column), bytes that are not text, an unterminated
// quote, no rows.
WeightsCsv read_weights_csv(const std::string& path);

// The same for the file's text; `path` names it in messages.
WeightsCsv parse_weights_csv(std::string text, const std::string& path);

// Checks that the CSV's columns are `controllers` in order (a rig's controller names).
// Throws retarget::Error naming the first column that differs, or the counts.
void require_weights_controllers(const WeightsCsv& csv, const std::vector<std::string>& controllers);

}  // namespace retarget
