#include "geometry/landmarks.h"

#include "core/config.h"
#include "core/error.h"

namespace retarget {

namespace {
std::vector<int> indices(const ConfigNode& node) {
  std::vector<int> out = node.as<std::vector<int>>();
  for (size_t k = 0; k < out.size(); ++k)
    if (out[k] < 0) throw Error(node.at(k).where(), "expected a vertex index >= 0, got " + std::to_string(out[k]));
  return out;
}

std::vector<LandmarkPair> same(const std::vector<int>& v) {
  std::vector<LandmarkPair> pairs;
  for (int i : v) pairs.push_back({i, i});
  return pairs;
}
}  // namespace

std::vector<LandmarkPair> read_landmark_pairs(const std::string& path, const std::string& key) {
  const ConfigNode root = ConfigNode::load_file(path);
  if (!key.empty()) return same(indices(root.child(key)));
  if (root.has("same")) {
    root.reject_unknown_keys({"same"});
    return same(indices(root.child("same")));
  }
  if (root.has("pairs")) {
    root.reject_unknown_keys({"pairs"});
    const ConfigNode list = root.child("pairs");
    std::vector<LandmarkPair> pairs;
    for (size_t k = 0; k < list.size(); ++k) {
      const std::vector<int> pair = indices(list.at(k));
      if (pair.size() != 2)
        throw Error(list.at(k).where(), "expected [source, target], got " + std::to_string(pair.size()) + " numbers");
      pairs.push_back({pair[0], pair[1]});
    }
    return pairs;
  }
  root.reject_unknown_keys({"source", "target"});
  const std::vector<int> source = indices(root.child("source"));
  const std::vector<int> target = indices(root.child("target"));
  if (source.size() != target.size())
    throw Error(root.child("target").where(),
                "has " + std::to_string(target.size()) + " indices but source has " + std::to_string(source.size()));
  std::vector<LandmarkPair> pairs;
  for (size_t k = 0; k < source.size(); ++k) pairs.push_back({source[k], target[k]});
  return pairs;
}

namespace {
std::vector<int> vertex_list(const ConfigNode& node, int vertex_count, const std::string& mesh_path) {
  const std::vector<int> list = node.as<std::vector<int>>();
  if (list.empty()) node.fail("expected at least one vertex index");
  for (size_t k = 0; k < list.size(); ++k)
    if (list[k] < 0 || list[k] >= vertex_count)
      node.at(k).fail("vertex " + std::to_string(list[k]) + " is out of range (" + mesh_path + " has " +
                      std::to_string(vertex_count) + " vertices)");
  return list;
}
}  // namespace

void read_landmark_sections(const ConfigNode& root, int vertex_count, const std::string& mesh_path,
                            std::map<std::string, int>& landmarks, EyeLandmarks& eyes) {
  if (root.has("landmarks")) {
    const ConfigNode section = root.child("landmarks");
    if (!section.is_map() && !section.is_null()) section.fail("expected a map {name: vertex index}");
    if (section.is_map())
      for (const auto& entry : section.yaml()) {
        const std::string name = entry.first.as<std::string>();
        const ConfigNode value = section.child(name);
        const int index = value.as<int>();
        if (index < 0 || index >= vertex_count)
          value.fail("vertex " + std::to_string(index) + " is out of range (" + mesh_path + " has " +
                     std::to_string(vertex_count) + " vertices)");
        landmarks[name] = index;
      }
  }
  if (root.has("eyes")) {
    const ConfigNode section = root.child("eyes");
    section.reject_unknown_keys({"left", "right"});
    eyes.left = vertex_list(section.child("left"), vertex_count, mesh_path);
    eyes.right = vertex_list(section.child("right"), vertex_count, mesh_path);
  }
}

EyeLandmarks read_eye_landmarks(const std::string& path) {
  const ConfigNode root = ConfigNode::load_file(path);
  EyeLandmarks eyes;
  eyes.left = indices(root.child("left_eye"));
  eyes.right = indices(root.child("right_eye"));
  return eyes;
}

void check_landmark_pairs(const std::vector<LandmarkPair>& pairs, int source_vertices, const std::string& source_name,
                          int target_vertices, const std::string& target_name) {
  for (size_t k = 0; k < pairs.size(); ++k) {
    auto check = [&](int index, int count, const char* side, const std::string& name) {
      if (index < 0 || index >= count)
        throw Error("landmark " + std::to_string(k), std::string(side) + " vertex " + std::to_string(index) +
                                                         " is out of range (" + name + " has " + std::to_string(count) +
                                                         " vertices)");
    };
    check(pairs[k].source, source_vertices, "source", source_name);
    check(pairs[k].target, target_vertices, "target", target_name);
  }
}

}  // namespace retarget
