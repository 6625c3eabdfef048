#include "geometry/face_folder.h"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <map>
#include <set>

#include "core/error.h"
#include "geometry/mesh_io.h"
#include "geometry/mesh_validation.h"

namespace retarget {

namespace fs = std::filesystem;

namespace {

bool is_mesh_file(const fs::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext == ".obj" || ext == ".ply" || ext == ".off";
}

std::string join(const std::vector<std::string>& names, size_t limit = 12) {
  std::string out;
  for (size_t k = 0; k < names.size() && k < limit; ++k) out += (k ? ", " : "") + names[k];
  if (names.size() > limit) out += ", ... (" + std::to_string(names.size() - limit) + " more)";
  return out;
}

}  // namespace

int FaceFolder::subject_index(const std::string& name) const {
  const auto it = std::find(subjects.begin(), subjects.end(), name);
  return it == subjects.end() ? -1 : static_cast<int>(it - subjects.begin());
}

int FaceFolder::expression_index(const std::string& name) const {
  const auto it = std::find(expressions.begin(), expressions.end(), name);
  return it == expressions.end() ? -1 : static_cast<int>(it - expressions.begin());
}

const std::string& FaceFolder::path(int subject, int expression) const {
  return paths.at(static_cast<size_t>(subject) * expressions.size() + expression);
}

Positions FaceFolder::read(int subject, int expression) const {
  Mesh mesh = read_mesh(path(subject, expression));
  require_same_topology(topology, mesh);
  return std::move(mesh.vertices);
}

FaceFolder open_face_folder(const std::string& folder, const FaceFolderOptions& options) {
  if (!fs::is_directory(folder)) throw Error(folder, "face folder not found (expected <subject>/<expression>.obj)");
  FaceFolder set;
  set.root = folder;
  // subject -> expression -> file
  std::map<std::string, std::map<std::string, std::string>> files;
  for (const fs::directory_entry& entry : fs::directory_iterator(folder)) {
    const std::string subject = entry.path().filename().string();
    if (!entry.is_directory() || subject.empty() || subject[0] == '.') continue;
    std::map<std::string, std::string>& meshes = files[subject];
    for (const fs::directory_entry& file : fs::directory_iterator(entry.path())) {
      if (!file.is_regular_file() || !is_mesh_file(file.path())) continue;
      const std::string expression = file.path().stem().string();
      const auto [it, inserted] = meshes.emplace(expression, file.path().string());
      if (!inserted) {
        std::string a = it->second, b = file.path().string();
        if (b < a) std::swap(a, b);  // the message does not depend on the listing order
        throw Error(folder, "subject \"" + subject + "\" has two meshes for expression \"" + expression + "\": " + a +
                                " and " + b + "; keep one");
      }
    }
    if (meshes.empty()) throw Error(entry.path().string(), "subject folder holds no mesh files (.obj, .ply or .off)");
  }
  if (files.empty())
    throw Error(folder, "no subject folders found (expected <subject>/<expression>.obj, one folder per subject)");

  std::set<std::string> all;
  for (const auto& [subject, meshes] : files)
    for (const auto& [expression, path] : meshes) all.insert(expression);
  std::vector<std::string> problems;
  for (const auto& [subject, meshes] : files) {
    std::vector<std::string> missing;
    for (const std::string& expression : all)
      if (!meshes.count(expression)) missing.push_back(expression);
    if (!missing.empty()) problems.push_back(subject + " lacks " + join(missing, 8));
  }
  if (!problems.empty())
    throw Error(folder, "every subject must have the same expressions, but " + join(problems, 10) + " (" +
                            std::to_string(problems.size()) + " of " + std::to_string(files.size()) + " subjects)");

  for (const auto& [subject, meshes] : files) set.subjects.push_back(subject);
  set.expressions.assign(all.begin(), all.end());
  if (!options.neutral.empty() && all.count(options.neutral)) {
    set.expressions.erase(std::find(set.expressions.begin(), set.expressions.end(), options.neutral));
    set.expressions.insert(set.expressions.begin(), options.neutral);
    set.neutral = 0;
  }
  for (const std::string& subject : set.subjects)
    for (const std::string& expression : set.expressions) set.paths.push_back(files[subject][expression]);
  set.topology = read_mesh(set.paths.front());
  return set;
}

}  // namespace retarget
