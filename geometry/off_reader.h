// OFF meshes (Geomview's Object File Format, ASCII) read by our own parser.
#pragma once

#include <string>
#include <string_view>

#include "geometry/mesh.h"

namespace retarget {

// Parses an OFF file's text; `path` only names the file in messages.
// Accepted: the keyword OFF with Geomview's optional prefixes (ST, C, N, and nOFF with dimension
// 3), the counts "#V #F [#E]" on the keyword's line or on the next one, # comments and blank
// lines anywhere, one vertex per line ("x y z", plus the normals, colours or texture coordinates
// a prefix announces), one face per line ("n i0 ... i(n-1)" with indices from 0, then an optional
// colour of up to 4 numbers).
// out: vertices (#V x 3, the file's units and order, parsed as doubles), faces (file order),
// source = path; triangles are left to triangulate().
//
// Counts are checked against the file's length before anything is allocated. Throws
// retarget::Error naming "path:line" for: a missing or unknown keyword, binary or 4D OFF,
// malformed counts, a vertex line with a malformed, out-of-range or non-finite number or the
// wrong number of values (plain OFF: exactly 3, so a face line among the vertices is caught),
// a face with fewer than 3 vertices, an index outside [0, #V), a face line with too few or too
// many values, a file that ends early, and data after the last face. Vertex and face numbers
// in messages count from 0, as OFF indices do.
Mesh read_off(const std::string& path, std::string_view text);

}  // namespace retarget
