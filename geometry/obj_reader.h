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
// Throws retarget::Error naming "path:line" for a malformed, out-of-range or non-finite number,
// a face with fewer than 3 vertices, index 0, and an index outside the vertices.
Mesh read_obj(const std::string& path, std::string_view text);

}  // namespace retarget
