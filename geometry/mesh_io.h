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
// Precision: OBJ, OFF and ASCII PLY are parsed by our own readers (parse_double: std::from_chars's values) and keep
// full double precision; binary PLY values are widened from their declared type (OpenMesh writes
// 32-bit floats, ~7 significant digits).
//
// Throws retarget::Error naming the path for: a path that does not exist ("No such file or
// directory", whatever the extension), an unsupported extension, an unreadable file (with the OS
// reason), no vertices or no faces, and every problem require_valid_mesh() throws for. Parse
// errors come from read_obj(), read_ply() and read_off() (obj_reader.h, ply_reader.h,
// off_reader.h): "file:line" (binary PLY: the element and byte offset) and the fault. No input
// hangs or allocates more than a small multiple of the file's size: counts are checked against
// the file's length first.
Mesh read_mesh(const std::string& path);

struct MeshWriteOptions {
  // PLY only: binary little-endian (compact, 4-byte floats) instead of ASCII. Either way
  // OpenMesh (our PLY writer) writes PLY coordinates as 32-bit floats (~7 significant digits).
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
