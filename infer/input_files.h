// The mesh files a retarget-infer run reads, from what the user named: files, folders and glob
// patterns, each expanded in natural order so that a frame sequence keeps its order
// (frame_2.obj before frame_10.obj).
#pragma once

#include <string>
#include <vector>

namespace retarget {

// One file to read, or an input that gave none (problem says why, for the run's failure list).
struct InputFile {
  std::string path;     // the file; for a problem, the input as the user wrote it
  std::string problem;  // empty: read `path`
};

// Expands the inputs in the order given:
//   - a folder: the .obj, .ply and .off files directly inside it (extension case-insensitive, no
//     recursion), in natural order of their names; none -> one entry with a problem;
//   - a pattern with *, ? or [ that names no existing file: glob(3), the matching mesh files
//     (folders and other extensions skipped) in natural order; none -> one entry with a problem;
//   - a path that does not exist (no glob characters): one entry with the problem "no such file
//     or folder: the path does not exist";
//   - anything else: that path as it is (reading it reports an unreadable file).
std::vector<InputFile> expand_inputs(const std::vector<std::string>& inputs);

// Natural order: runs of digits compare by their numeric value ("frame_2" < "frame_10"; with
// equal values fewer leading zeros first), everything else byte by byte; a full tie falls back to
// plain string order, so the order is total.
bool natural_less(const std::string& a, const std::string& b);

// True for the extensions read_mesh() reads: .obj, .ply, .off (case-insensitive).
bool is_mesh_file(const std::string& path);

}  // namespace retarget
