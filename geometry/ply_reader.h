// PLY meshes read by our own parser: ASCII, binary little-endian and binary big-endian.
#pragma once

#include <string>
#include <string_view>

#include "geometry/mesh.h"

namespace retarget {

// Parses a PLY file's bytes; `path` only names the file in messages.
// out: vertices (#V x 3, the file's units and order; ASCII values parsed as doubles, binary ones
// widened from their declared type), faces (the face element's vertex_indices or vertex_index
// lists in file order, indices from 0), source = path; triangles are left to triangulate().
// Other properties (normals, colours, texture coordinates, flags) and other elements (edges,
// materials) are checked against their declared types and skipped.
//
// Every header line and value is checked before it is used, and every count against the bytes
// that follow the header before anything is allocated, so no input hangs or over-reads. Throws
// retarget::Error for: a malformed header ("path:line": unknown keyword or type, a property
// outside an element, a missing format line, no end_header, no vertex element or no x/y/z, a
// face element without an integer index list), a count the file cannot hold, and in the body
// malformed or out-of-range numbers, non-finite coordinates, a face with fewer than 3 vertices,
// a vertex index outside [0, #V), a line with too few or too many values, a truncated file and
// data after the last element. ASCII body errors name "path:line"; binary ones name the element
// (counting from 0, as PLY indices do) and its byte offset in the file.
Mesh read_ply(const std::string& path, std::string_view bytes);

}  // namespace retarget
