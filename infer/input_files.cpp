#include "infer/input_files.h"

#include <glob.h>

#include <algorithm>
#include <cctype>
#include <filesystem>

namespace retarget {

namespace {

namespace fs = std::filesystem;

bool is_digit(char c) { return std::isdigit(static_cast<unsigned char>(c)) != 0; }

// -1, 0, 1 as a < b, a == b, a > b in natural order (without the final tie-break).
int natural_compare(const std::string& a, const std::string& b) {
  size_t i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    if (is_digit(a[i]) && is_digit(b[j])) {
      const size_t i0 = i, j0 = j;
      while (i < a.size() && is_digit(a[i])) ++i;
      while (j < b.size() && is_digit(b[j])) ++j;
      size_t zi = i0, zj = j0;  // skip leading zeros, then compare by length and digits
      while (zi + 1 < i && a[zi] == '0') ++zi;
      while (zj + 1 < j && b[zj] == '0') ++zj;
      if (i - zi != j - zj) return i - zi < j - zj ? -1 : 1;
      const int digits = a.compare(zi, i - zi, b, zj, j - zj);
      if (digits != 0) return digits < 0 ? -1 : 1;
      if (i - i0 != j - j0) return i - i0 < j - j0 ? -1 : 1;  // "7" before "007"
      continue;
    }
    if (a[i] != b[j]) return static_cast<unsigned char>(a[i]) < static_cast<unsigned char>(b[j]) ? -1 : 1;
    ++i;
    ++j;
  }
  if (i < a.size()) return 1;
  if (j < b.size()) return -1;
  return 0;
}

bool has_glob_characters(const std::string& text) { return text.find_first_of("*?[") != std::string::npos; }

void sort_naturally(std::vector<std::string>& paths) { std::sort(paths.begin(), paths.end(), natural_less); }

std::vector<InputFile> folder_files(const std::string& folder) {
  std::vector<std::string> paths;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(folder, ec)) {
    std::error_code type_error;
    if (entry.is_regular_file(type_error) && is_mesh_file(entry.path().string()))
      paths.push_back(entry.path().string());
  }
  if (ec) return {{folder, "cannot list the folder: " + ec.message()}};
  if (paths.empty()) return {{folder, "a folder with no .obj, .ply or .off files"}};
  sort_naturally(paths);
  std::vector<InputFile> files;
  for (std::string& path : paths) files.push_back({std::move(path), ""});
  return files;
}

std::vector<InputFile> glob_files(const std::string& pattern) {
  glob_t matches{};
  int flags = 0;
#ifdef GLOB_BRACE
  flags |= GLOB_BRACE;
#endif
#ifdef GLOB_TILDE
  flags |= GLOB_TILDE;
#endif
  const int status = ::glob(pattern.c_str(), flags, nullptr, &matches);
  std::vector<std::string> paths;
  if (status == 0) {
    for (size_t k = 0; k < matches.gl_pathc; ++k) {
      const std::string path = matches.gl_pathv[k];
      std::error_code ec;
      if (fs::is_regular_file(path, ec) && is_mesh_file(path)) paths.push_back(path);
    }
  }
  globfree(&matches);
  if (status != 0 && status != GLOB_NOMATCH) return {{pattern, "cannot expand the pattern (glob failed)"}};
  if (paths.empty()) return {{pattern, "the pattern matches no .obj, .ply or .off file"}};
  sort_naturally(paths);
  std::vector<InputFile> files;
  for (std::string& path : paths) files.push_back({std::move(path), ""});
  return files;
}

}  // namespace

bool natural_less(const std::string& a, const std::string& b) {
  const int order = natural_compare(a, b);
  return order != 0 ? order < 0 : a < b;
}

bool is_mesh_file(const std::string& path) {
  std::string extension = fs::path(path).extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return extension == ".obj" || extension == ".ply" || extension == ".off";
}

std::vector<InputFile> expand_inputs(const std::vector<std::string>& inputs) {
  std::vector<InputFile> files;
  for (const std::string& input : inputs) {
    std::error_code ec;
    std::vector<InputFile> expanded;
    if (fs::is_directory(input, ec)) {
      expanded = folder_files(input);
    } else if (has_glob_characters(input) && !fs::exists(input, ec)) {
      expanded = glob_files(input);
    } else if (!fs::exists(fs::symlink_status(input, ec))) {
      // Said here, before read_mesh() would judge a mistyped folder by its (missing) extension.
      expanded = {{input, "no such file or folder: the path does not exist"}};
    } else {
      expanded = {{input, ""}};
    }
    files.insert(files.end(), expanded.begin(), expanded.end());
  }
  return files;
}

}  // namespace retarget
