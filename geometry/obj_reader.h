// OBJ meshes read by our own parser: positions and faces; texture coordinates, normals, groups
// and materials are skipped.
#pragma once

#include <string>
#include <string_view>

#include "geometry/mesh.h"

namespace retarget {

// Parses an OBJ file's text; `path` only names the file in messages.
// out: vertices (#V x 3 from the "v" lines, the file's units, full double precision; w and
// vertex colours ignored), faces ("f" lines in file order, indices from 0; v, v/vt, v//vn and
// v/vt/vn, negative indices relative to the vertices above), source = path; triangles are left
// to triangulate(). Line continuations (a backslash before the newline) and a UTF-8 byte order
// mark are accepted.
// Outside an OpenMP parallel region, a file of 256 KB or more is read in chunks of whole lines on
// up to omp_get_max_threads() threads (BM_ReadObj, an ICT face of 0.9 MB on 2 cores: 1.25 -> 1.07
// ms); the mesh and every message are the one-piece reader's. The parser's buffers are kept by the
// calling thread for its next file (up to 64 MB), so a stream of frames does not page in new memory
// each time.
// Throws retarget::Error naming "path:line" for a malformed, out-of-range or non-finite number,
// a face with fewer than 3 vertices, index 0, and an index outside the vertices.
Mesh read_obj(const std::string& path, std::string_view text);

}  // namespace retarget
