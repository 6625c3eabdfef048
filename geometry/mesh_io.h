// Mesh files: OBJ, PLY and OFF, read with their polygons kept as written and written back
// with the same polygons.
#pragma once

#include <string>

#include "geometry/mesh.h"

namespace retarget {

// Reads a mesh; the format comes from the extension, case-insensitive: .obj, .ply, .off.
// out: vertices (#V x 3, the file's units, file order), faces (the file's polygons in file
// order, vertex indices from 0), triangles (fan triangulation), source = path.
// The result has passed require_valid_mesh(); call validate_mesh() for the counts to log.
//
// Precision: OBJ is parsed by our own reader (std::from_chars) and keeps full double
// precision. PLY and OFF are read through OpenMesh, which stores coordinates as 32-bit
// floats on the way in (even for `property double`), so they carry ~7 significant digits.
//
// Throws retarget::Error naming the path for: an unsupported extension, a missing or
// unreadable file (with the OS reason), no vertices or no faces, and every problem
// require_valid_mesh() throws for. OBJ errors name "file:line" and the fault (malformed number,
// face with fewer than 3 vertices, index 0, index out of range with the vertex count).
// PLY/OFF: throws when OpenMesh loads a different number of vertices or faces than the
// header declares: OpenMesh silently duplicates vertices of, or drops, faces it cannot add
// to a manifold mesh (non-manifold edges, repeated or out-of-range indices); such files
// load as written when converted to OBJ. OFF files with # comments or with the counts on the
// "OFF" line are refused up front, since OpenMesh misreads them without a word.
Mesh read_mesh(const std::string& path);

struct MeshWriteOptions {
  // PLY only: binary little-endian (compact, 4-byte floats) instead of ASCII. Either way
  // OpenMesh writes PLY coordinates as 32-bit floats (~7 significant digits).
  bool binary_ply = true;
};

// Writes mesh.vertices and the original polygons mesh.faces (not the triangles); the format
// comes from the extension (.obj, .ply, .off, case-insensitive). The file is replaced
// atomically: readers see the old file or the new one, never half of one; missing parent
// folders are created. OBJ and OFF are written by our own writer with the shortest digits
// that read back to the identical double (std::to_chars), so an OBJ round trip is exact.
// Throws retarget::Error naming the path for an unsupported extension, an invalid mesh (see
// require_valid_mesh), I/O failures, and for PLY a face OpenMesh cannot store (non-manifold or
// repeating a vertex; write OBJ or OFF instead).
void write_mesh(const std::string& path, const Mesh& mesh, const MeshWriteOptions& options = {});

}  // namespace retarget
