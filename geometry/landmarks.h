// Landmark files: vertex correspondences for deformation transfer and the eye landmarks of
// the paper's unit convention, read from YAML (JSON is valid YAML too).
#pragma once

#include <map>
#include <string>
#include <vector>

#include "core/config.h"
#include "geometry/deformation_transfer.h"
#include "geometry/metrics.h"

namespace retarget {

// Reads landmark pairs from one of these forms (vertex indices from 0):
//   pairs: [[source, target], ...]
//   source: [...]          target: [...]        (equal lengths)
//   same: [...]            (identical indices on both meshes, for one topology)
// `key`, if not empty, names a list inside the file to use as `same` (e.g. the ICT
// model's "idx_to_landmark_verts"). Throws retarget::Error naming the file, key path and
// entry for anything malformed (a non-integer, a negative index, unequal lengths).
std::vector<LandmarkPair> read_landmark_pairs(const std::string& path, const std::string& key = "");

// Reads `left_eye: [...]` and `right_eye: [...]` vertex lists from a YAML file.
EyeLandmarks read_eye_landmarks(const std::string& path);

// Reads the optional `landmarks: {name: vertex, ...}` and `eyes: {left: [...], right: [...]}`
// sections of a rig.yaml or face_model.yaml `root` into `landmarks` and `eyes`, checking every
// index against `vertex_count` (the mesh at `mesh_path`, named in the errors with file:line and
// key path). Absent sections leave the outputs untouched.
void read_landmark_sections(const ConfigNode& root, int vertex_count, const std::string& mesh_path,
                            std::map<std::string, int>& landmarks, EyeLandmarks& eyes);

// Throws retarget::Error if any pair's index is outside its mesh ("landmark 7: source vertex
// 12000 is out of range (face.obj has 11248 vertices)").
void check_landmark_pairs(const std::vector<LandmarkPair>& pairs, int source_vertices, const std::string& source_name,
                          int target_vertices, const std::string& target_name);

}  // namespace retarget
