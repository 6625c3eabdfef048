// The folder a command writes into: refused when it is a file, or not empty without --force.
#pragma once

#include <string>

namespace retarget::cli {

// Throws retarget::Error naming `folder` when it exists and is not a folder, or when it is a
// non-empty folder and `force` is false ("pass --force to write into it anyway").
void check_output_folder(const std::string& folder, bool force);

}  // namespace retarget::cli
