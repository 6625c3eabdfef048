#include "pipeline/input_digests.h"

#include <algorithm>
#include <filesystem>

#include "core/sha256.h"

namespace fs = std::filesystem;

namespace retarget {

namespace {

std::string digest_of_folder(const fs::path& folder) {
  std::vector<std::pair<std::string, std::string>> files;  // relative path, digest
  for (auto it = fs::recursive_directory_iterator(folder); it != fs::recursive_directory_iterator(); ++it) {
    const std::string name = it->path().filename().string();
    if (name.front() == '.' || name.find(".tmp.") != std::string::npos) {
      if (it->is_directory()) it.disable_recursion_pending();
      continue;
    }
    if (it->is_regular_file())
      files.emplace_back(fs::relative(it->path(), folder).generic_string(), sha256_of_file(it->path().string()));
  }
  std::sort(files.begin(), files.end());
  std::string listing;
  for (const auto& [path, digest] : files) listing += digest + "  " + path + "\n";
  return sha256_of_bytes(listing);
}

}  // namespace

const std::string& InputDigests::of(const std::string& path) {
  auto it = cache_.find(path);
  if (it != cache_.end()) return it->second;
  std::string digest = "missing";
  if (fs::is_directory(path)) {
    digest = digest_of_folder(path);
  } else if (fs::exists(path)) {
    digest = sha256_of_file(path);
  }
  return cache_.emplace(path, std::move(digest)).first->second;
}

std::string stage_fingerprint(const std::string& key, const std::vector<std::string>& commands,
                              const std::vector<std::string>& input_digests,
                              const std::vector<std::string>& upstream_fingerprints) {
  std::string text = "stage " + key + "\n";
  for (const std::string& c : commands) text += "command " + c + "\n";
  for (const std::string& d : input_digests) text += "input " + d + "\n";
  for (const std::string& f : upstream_fingerprints) text += "after " + f + "\n";
  return sha256_of_bytes(text);
}

}  // namespace retarget
