// The folder a command writes into: refused when it is a file, or not empty without --force; and
// errors of an options struct said of the command-line options.
#pragma once

#include <map>
#include <string>

#include "core/error.h"

namespace retarget::cli {

// Throws retarget::Error naming `folder` when it exists and is not a folder, or when it is a
// non-empty folder and `force` is false ("pass --force to write into it anyway").
void check_output_folder(const std::string& folder, bool force);

// Runs `make` (a constructor taking an options struct validated under `key_path`, e.g. a server);
// an error about key_path.<...>.field is said of the command-line option --field ('_' as '-'),
// or of renamed[field] when the option has another name:
// "landmarks.port: must be in 0..65535" becomes "--port: must be in 0..65535".
template <typename Make>
auto with_option_names(const std::string& key_path, Make make, const std::map<std::string, std::string>& renamed = {})
    -> decltype(make()) {
  try {
    return make();
  } catch (const Error& e) {
    if (e.where().rfind(key_path + ".", 0) != 0) throw;
    std::string field = e.where().substr(e.where().rfind('.') + 1);
    if (const auto it = renamed.find(field); it != renamed.end()) throw Error(it->second, e.detail());
    for (char& c : field)
      if (c == '_') c = '-';
    throw Error("--" + field, e.detail());
  }
}

}  // namespace retarget::cli
