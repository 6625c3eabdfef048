#include "cli/output_folder.h"

#include <filesystem>

#include "core/error.h"

namespace retarget::cli {

void check_output_folder(const std::string& folder, bool force) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (fs::exists(folder, ec) && !fs::is_directory(folder, ec)) throw Error(folder, "exists and is not a folder");
  if (fs::is_directory(folder, ec) && !fs::is_empty(folder, ec) && !force)
    throw Error(folder, "the folder is not empty; pass --force to write into it anyway");
}

}  // namespace retarget::cli
