// PLY files, valid and hostile: every malformed input gives a retarget::Error naming the file and
// the line (ASCII) or the element and byte (binary); none hangs or allocates past the file's size.
#include "geometry/ply_reader.h"

#include <algorithm>
#include <catch2/catch.hpp>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include "core/error.h"
#include "geometry/mesh_io.h"
#include "test_support.h"

namespace fs = std::filesystem;
using Catch::Contains;
using retarget::Error;
using retarget::Mesh;
using retarget::test::error_of;
using retarget::test::error_of_reading;
using retarget::test::write_file;

namespace {

const std::string kHeader =
    "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
    "element face 2\nproperty list uchar int vertex_indices\nend_header\n";  // 9 lines
const std::string kVertices = "0 0 0\n1 0 0\n1 1 0\n0 1 0\n";                // lines 10-13
const std::string kFaces = "3 0 1 2\n3 0 2 3\n";                             // lines 14-15

// Appends `value` in the given byte order.
template <typename T>
void put(std::string& bytes, T value, bool big_endian) {
  char raw[sizeof(T)];
  std::memcpy(raw, &value, sizeof(T));
  if (big_endian) std::reverse(raw, raw + sizeof(T));
  bytes.append(raw, sizeof(T));
}

// A binary square with normals (double x, float normals, uchar colour) and uchar/uint lists.
std::string binary_square(bool big_endian, int bad_index = -1, float z3 = 0) {
  std::string bytes = std::string("ply\nformat ") + (big_endian ? "binary_big_endian" : "binary_little_endian") +
                      " 1.0\ncomment made by a test\nelement vertex 4\nproperty double x\nproperty double y\n"
                      "property float z\nproperty float nx\nproperty float ny\nproperty float nz\n"
                      "property uchar red\nelement face 2\nproperty list uchar uint vertex_indices\n"
                      "property uint16 flags\nend_header\n";
  const double xy[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  for (int v = 0; v < 4; ++v) {
    put(bytes, xy[v][0], big_endian);
    put(bytes, xy[v][1], big_endian);
    put(bytes, v == 3 ? z3 : 0.0f, big_endian);
    for (float n : {0.0f, 0.0f, 1.0f}) put(bytes, n, big_endian);
    put(bytes, static_cast<uint8_t>(200), big_endian);
  }
  const uint32_t faces[2][3] = {{0, 1, 2}, {0, 2, bad_index >= 0 ? static_cast<uint32_t>(bad_index) : 3u}};
  for (const auto& face : faces) {
    put(bytes, static_cast<uint8_t>(3), big_endian);
    for (uint32_t index : face) put(bytes, index, big_endian);
    put(bytes, static_cast<uint16_t>(7), big_endian);
  }
  return bytes;
}

void check_square(const Mesh& mesh) {
  REQUIRE(mesh.vertex_count() == 4);
  CHECK(mesh.vertices.row(2) == Eigen::RowVector3d(1, 1, 0));
  CHECK(mesh.faces.indices == std::vector<int>{0, 1, 2, 0, 2, 3});
  CHECK(mesh.faces.offsets == std::vector<int>{0, 3, 6});
  CHECK(mesh.triangle_count() == 2);
}

}  // namespace

TEST_CASE("PLY: ASCII and binary variants read the same square", "[mesh_io][ply]") {
  const auto dir = retarget::test::scratch_dir("ply_variants");
  struct Case {
    const char* name;
    std::string bytes;
  };
  const std::vector<Case> cases = {
      {"plain", kHeader + kVertices + kFaces},
      {"CRLF and blank lines",
       "ply\r\nformat ascii 1.0\r\nelement vertex 4\r\nproperty float x\r\nproperty float y\r\n"
       "property float z\r\nelement face 2\r\nproperty list uchar int vertex_indices\r\n"
       "end_header\r\n0 0 0\r\n1 0 0\r\n\r\n1 1 0\r\n0 1 0\r\n3 0 1 2\r\n3 0 2 3"},
      {"normals, colours, uchar uint lists, a face flag, an edge element and sized type names",
       "ply\nformat ascii 1.0\ncomment exported\nobj_info by hand\nelement vertex 4\nproperty float32 x\n"
       "property float32 y\nproperty float32 z\nproperty float nx\nproperty float ny\nproperty float nz\n"
       "property uchar red\nproperty uchar green\nproperty uchar blue\nproperty uchar alpha\n"
       "element face 2\nproperty list uint8 uint32 vertex_index\nproperty int flags\n"
       "element edge 1\nproperty int vertex1\nproperty int vertex2\nend_header\n"
       "0 0 0 0 0 1 255 0 0 255\n1 0 0 0 0 1 0 255 0 255\n1 1 0 0 0 1 0 0 255 255\n0 1 0 0 0 1 9 9 9 9\n"
       "3 0 1 2 -1\n3 0 2 3 0\n0 1\n"},
      {"faces before vertices, double coordinates",
       "ply\nformat ascii 1.0\nelement face 2\n"
       "property list ushort short vertex_indices\nelement vertex 4\n"
       "property double x\nproperty double y\nproperty double z\n"
       "end_header\n" +
           kFaces + kVertices},
      {"binary little-endian", binary_square(false)},
      {"binary big-endian", binary_square(true)},
  };
  for (const Case& c : cases) {
    INFO(c.name);
    check_square(retarget::read_mesh(write_file(dir / "square.ply", c.bytes)));
  }
}

TEST_CASE("PLY: hostile ASCII files give errors naming file:line", "[mesh_io][ply][errors]") {
  const auto dir = retarget::test::scratch_dir("ply_ascii_errors");
  const std::string vertex_header = "ply\nformat ascii 1.0\nelement vertex 4\n";
  const std::string xyz = "property float x\nproperty float y\nproperty float z\n";
  const std::string face_header = "element face 2\nproperty list uchar int vertex_indices\nend_header\n";
  struct Case {
    const char* name;
    std::string text;
    std::vector<std::string> message;  // substrings
  };
  const std::vector<Case> cases = {
      // The inputs that hung OpenMesh's reader.
      {".nan", kHeader + ".nan 1 1\n1 0 0\n1 1 0\n0 1 0\n" + kFaces, {"bad.ply:10: ", "x: malformed number \".nan\""}},
      {"1e400",
       kHeader + "0 0 0\n1e400 1 1\n1 1 0\n0 1 0\n" + kFaces,
       {"bad.ply:11: ", "x: number \"1e400\" is out of range for its type float"}},
      {"beyond float",
       kHeader + "0 0 0\n1 0 0\n1 1 1e39\n0 1 0\n" + kFaces,
       {"bad.ply:12: ", "\"1e39\" is out of range"}},
      {"nan",
       kHeader + "0 0 0\n1 0 0\n1 nan 0\n0 1 0\n" + kFaces,
       {"bad.ply:12: ", "vertex 2 has a non-finite coordinate (y = nan)"}},
      {"inf", kHeader + "0 0 0\n1 0 0\n1 1 0\n0 1 -inf\n" + kFaces, {"bad.ply:13: ", "(z = -inf)"}},
      {"face line among the vertices",
       kHeader + "0 0 0\n1 0 0\n3 0 1 2\n0 1 0\n1 1 0\n3 0 2 3\n",
       {"bad.ply:12: ", "vertex 2 has 4 values on its line, 1 more than its properties (x y z) take"}},
      {"vertex line among the faces",
       kHeader + kVertices + "3 0 1 2\n1 1 0\n",
       {"bad.ply:15: ", "face 1 has 1 vertex; a face needs at least 3"}},
      {"list longer than its line",
       kHeader + kVertices + "3 0 1 2\n4 0 2 3\n",
       {"bad.ply:15: ", "face 1: the list vertex_indices says 4 values but the line has only 3 after it"}},
      {"too few values",
       kHeader + "0 0 0\n1 0\n1 1 0\n0 1 0\n" + kFaces,
       {"bad.ply:11: ", "vertex 1 has 2 values on its line, too few for its properties (x y z)"}},
      {"truncated",
       kHeader + kVertices + "3 0 1 2\n",
       {"bad.ply:", "the file ends after 1 of the 2 face elements the header declares"}},
      {"data after the last element",
       kHeader + kVertices + kFaces + "3 1 2 3\n",
       {"bad.ply:16: ", "data after the last element"}},
      {"index out of range",
       kHeader + kVertices + "3 0 1 2\n3 0 2 4\n",
       {"bad.ply:15: ", "face 1: vertex index 4 is out of range: the file has 4 vertices"}},
      {"negative index",
       kHeader + kVertices + "3 0 1 2\n3 0 -2 3\n",
       {"bad.ply:15: ", "vertex index -2 is out of range"}},
      {"two-vertex face", kHeader + kVertices + "3 0 1 2\n2 0 2\n", {"bad.ply:15: ", "face 1 has 2 vertices"}},
      {"list count beyond uchar",
       kHeader + kVertices + "3 0 1 2\n300 0 2 3\n",
       {"bad.ply:15: ", "vertex_indices \"300\" is out of range for its type uchar"}},
      {"index beyond int",
       kHeader + kVertices + "3 0 1 2\n3 0 2 4294967296\n",
       {"bad.ply:15: ", "\"4294967296\" is out of range for its type int"}},
      {"malformed index", kHeader + kVertices + "3 0 1 2\n3 0 2 x\n", {"bad.ply:15: ", "malformed integer \"x\""}},
      {"float index", kHeader + kVertices + "3 0 1 2\n3 0 2 3.0\n", {"bad.ply:15: ", "malformed integer \"3.0\""}},
      {"huge vertex count",
       "ply\nformat ascii 1.0\nelement vertex 2000000000\n" + xyz + face_header + kVertices,
       {"bad.ply:3: ", "declares 2000000000 vertex elements", "truncated"}},
      {"count beyond int",
       "ply\nformat ascii 1.0\nelement vertex 4294967301\n" + xyz + face_header,
       {"bad.ply:3: ", "count \"4294967301\" is not an integer in [0, 2147483647]"}},
      {"negative count",
       "ply\nformat ascii 1.0\nelement vertex -1\n" + xyz + face_header,
       {"bad.ply:3: ", "count \"-1\""}},
      {"unknown type", vertex_header + "property float128 x\n", {"bad.ply:4: ", "unknown property type \"float128\""}},
      {"float list count",
       vertex_header + xyz + "element face 2\nproperty list float int vertex_indices\nend_header\n",
       {"bad.ply:8: ", "list count type \"float\" is not an integer type"}},
      {"float indices",
       vertex_header + xyz + "element face 2\nproperty list uchar float vertex_indices\nend_header\n",
       {"bad.ply:7: ", "no integer list vertex_indices"}},
      {"no index list",
       vertex_header + xyz + "element face 2\nproperty int flags\nend_header\n",
       {"bad.ply:7: ", "no integer list vertex_indices or vertex_index (properties: flags)"}},
      {"property before element",
       "ply\nformat ascii 1.0\nproperty float x\n",
       {"bad.ply:3: ", "a property before any element"}},
      {"no z",
       vertex_header + "property float x\nproperty float y\n" + face_header,
       {"bad.ply:3: ", "the vertex element has no property z (properties: x y)"}},
      {"duplicate property",
       vertex_header + xyz + "property float x\n",
       {"bad.ply:7: ", "a second property named \"x\""}},
      {"unknown keyword",
       "ply\nformat ascii 1.0\nelemnt vertex 4\n",
       {"bad.ply:3: ", "unknown PLY header keyword \"elemnt\""}},
      {"unknown format", "ply\nformat utf8 1.0\n", {"bad.ply:2: ", "unknown PLY format \"utf8\""}},
      {"version", "ply\nformat ascii 2.0\n", {"bad.ply:2: ", "unsupported PLY version \"2.0\""}},
      {"no format", "ply\nelement vertex 4\n" + xyz + face_header, {"bad.ply:8: ", "no format line"}},
      {"no vertex element",
       "ply\nformat ascii 1.0\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n",
       {"bad.ply: ", "declares no \"element vertex\""}},
      {"empty file", "", {"bad.ply: ", "not a PLY file"}},
  };
  for (const Case& c : cases) {
    INFO(c.name);
    const std::string path = write_file(dir / "bad.ply", c.text);
    const std::string message = error_of_reading(path);
    CHECK_THAT(message, Contains(path));
    for (const std::string& part : c.message) CHECK_THAT(message, Contains(part));
  }
}

TEST_CASE("PLY: hostile binary files give errors naming the element and byte", "[mesh_io][ply][errors]") {
  const auto dir = retarget::test::scratch_dir("ply_binary_errors");
  const std::string header =
      "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
  std::string triangle = header;
  for (float v : {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f}) put(triangle, v, false);
  struct Case {
    const char* name;
    std::string bytes;
    std::vector<std::string> message;
  };
  std::string huge_list = triangle;
  put(huge_list, static_cast<uint8_t>(255), false);
  put(huge_list, int32_t{0}, false);
  std::string trailing = triangle;
  put(trailing, static_cast<uint8_t>(3), false);
  for (int32_t k : {0, 1, 2}) put(trailing, k, false);
  trailing += "junk";
  const std::vector<Case> cases = {
      {"index out of range",
       binary_square(false, 9),
       {"face 1: vertex index 9 is out of range: the file has 4 vertices", "(byte "}},
      {"big-endian index out of range", binary_square(true, 4), {"vertex index 4 is out of range"}},
      {"nan coordinate",
       binary_square(false, -1, std::numeric_limits<float>::quiet_NaN()),
       {"vertex 3 has a non-finite coordinate (z = nan)"}},
      {"truncated vertices",
       header + std::string(20, '\0'),
       {"bad.ply:3: ", "declares 3 vertex elements of at least 12 bytes each, more than the 20 bytes"}},
      {"list longer than the file",
       huge_list,
       {"face 0: the list vertex_indices says 255 values but only 4 bytes are left",
        "(byte " + std::to_string(header.size() + 37) + " of the file)"}},
      {"bytes after the last element",
       trailing,
       {"4 bytes after the last element", "(byte " + std::to_string(header.size() + 49) + " of the file)"}},
      {"huge count",
       "ply\nformat binary_big_endian 1.0\nelement vertex 2147483647\nproperty double x\n"
       "property double y\nproperty double z\nelement face 1\nproperty list uchar int vertex_indices\n"
       "end_header\n" +
           std::string(64, '\0'),
       {"bad.ply:3: ", "declares 2147483647 vertex elements of at least 24 bytes each"}},
  };
  for (const Case& c : cases) {
    INFO(c.name);
    const std::string path = write_file(dir / "bad.ply", c.bytes);
    const std::string message = error_of_reading(path);
    CHECK_THAT(message, Contains(path));
    for (const std::string& part : c.message) CHECK_THAT(message, Contains(part));
  }
}

TEST_CASE("PLY: read_ply parses bytes in memory", "[mesh_io][ply]") {
  const Mesh mesh = retarget::read_ply("memory.ply", kHeader + kVertices + kFaces);
  CHECK(mesh.source == "memory.ply");
  CHECK(mesh.faces.indices == std::vector<int>{0, 1, 2, 0, 2, 3});
  CHECK(mesh.triangle_count() == 0);  // left to triangulate()
  CHECK_THROWS_WITH(retarget::read_ply("memory.ply", kHeader + kVertices), Contains("memory.ply:") && Contains("ends"));
}
