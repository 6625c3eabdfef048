// Errors of an options struct (validated under a key path, e.g. "serve.threads") said of the
// command-line option the user typed ("--threads").
#pragma once

#include <map>
#include <string>

#include "core/error.h"

namespace retarget::cli {

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
