// OFF files, valid and hostile: every malformed input gives a retarget::Error naming file:line;
// none hangs or allocates past the file's size.
#include "geometry/off_reader.h"

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
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

const std::string kSquare = "0 0 0\n1 0 0\n1 1 0\n0 1 0\n";  // lines 3-6 after "OFF\n4 2 0\n"

}  // namespace

TEST_CASE("OFF: variants read the same square", "[mesh_io][off]") {
  const auto dir = retarget::test::scratch_dir("off_variants");
  struct Case {
    const char* name;
    std::string text;
  };
  const std::vector<Case> cases = {
      {"plain", "OFF\n4 2 0\n" + kSquare + "3 0 1 2\n3 0 2 3\n"},
      {"counts on the keyword line, no edge count", "OFF 4 2\n" + kSquare + "3 0 1 2\n3 0 2 3"},
      {"comments, blank lines, CRLF",
       "# a square\r\nOFF\r\n\r\n4 2 0 # counts\r\n0 0 0\r\n1 0 0\r\n# half way\r\n"
       "1 1 0\r\n0 1 0\r\n3 0 1 2\r\n\r\n3 0 2 3\r\n# end\r\n"},
      {"face colours", "OFF\n4 2 0\n" + kSquare + "3 0 1 2 255 0 0\n3 0 2 3 0.5 0.5 0.5 1\n"},
      {"COFF vertex colours",
       "COFF\n4 2 0\n0 0 0 1 0 0 1\n1 0 0 1 0 0 1\n1 1 0 0 1 0 1\n0 1 0 0 0 1 1\n"
       "3 0 1 2\n3 0 2 3\n"},
      {"NOFF normals", "NOFF\n4 2 0\n0 0 0 0 0 1\n1 0 0 0 0 1\n1 1 0 0 0 1\n0 1 0 0 0 1\n3 0 1 2\n3 0 2 3\n"},
      {"nOFF dimension 3", "nOFF\n3\n4 2 0\n" + kSquare + "3 0 1 2\n3 0 2 3\n"},
  };
  for (const Case& c : cases) {
    INFO(c.name);
    const Mesh mesh = retarget::read_mesh(write_file(dir / "square.off", c.text));
    REQUIRE(mesh.vertex_count() == 4);
    CHECK(mesh.vertices.row(2) == Eigen::RowVector3d(1, 1, 0));
    CHECK(mesh.faces.indices == std::vector<int>{0, 1, 2, 0, 2, 3});
    CHECK(mesh.triangle_count() == 2);
  }
}

TEST_CASE("OFF: hostile files give errors naming file:line", "[mesh_io][off][errors]") {
  const auto dir = retarget::test::scratch_dir("off_errors");
  const std::string head = "OFF\n4 2 0\n";
  const std::string faces = "3 0 1 2\n3 0 2 3\n";  // lines 7-8
  struct Case {
    const char* name;
    std::string text;
    std::vector<std::string> message;  // substrings
  };
  const std::vector<Case> cases = {
      // The input that hung OpenMesh's reader: a face line and a vertex line swapped.
      {"face line among the vertices",
       head + "0 0 0\n1 0 0\n3 0 1 2\n0 1 0\n1 1 0\n3 0 2 3\n",
       {"bad.off:5: ", "vertex 2 has 4 values; expected x y z", "is a face line among the vertices?"}},
      {"vertex line among the faces",
       head + kSquare + "3 0 1 2\n0.5 1 0\n",
       {"bad.off:8: ", "face 1: expected its vertex count, got \"0.5\" (a vertex line among the faces?)"}},
      {".nan",
       head + ".nan 1 1\n1 0 0\n1 1 0\n0 1 0\n" + faces,
       {"bad.off:3: ", "vertex 0: malformed number \".nan\""}},
      {"1e400",
       head + "0 0 0\n1e400 1 1\n1 1 0\n0 1 0\n" + faces,
       {"bad.off:4: ", "vertex 1: number \"1e400\" is out of range for a double"}},
      {"nan",
       head + "0 0 0\n1 0 0\n1 1 nan\n0 1 0\n" + faces,
       {"bad.off:5: ", "vertex 2 has a non-finite coordinate (z = nan)"}},
      {"inf", head + "0 0 0\n1 0 0\n1 1 0\ninf 1 0\n" + faces, {"bad.off:6: ", "(x = inf)"}},
      {"too few coordinates", head + "0 0 0\n1 0\n1 1 0\n0 1 0\n" + faces, {"bad.off:4: ", "vertex 1 has 2 values"}},
      {"malformed extra value",
       "COFF\n4 2 0\n0 0 0 red\n1 0 0\n1 1 0\n0 1 0\n" + faces,
       {"bad.off:3: ", "malformed number \"red\""}},
      {"index out of range",
       head + kSquare + "3 0 1 2\n3 0 2 4\n",
       {"bad.off:8: ", "face 1: vertex index 4 is out of range: the file has 4 vertices"}},
      {"negative index", head + kSquare + "3 0 1 2\n3 0 -1 3\n", {"bad.off:8: ", "vertex index -1 is out of range"}},
      {"huge index",
       head + kSquare + "3 0 1 2\n3 0 2 99999999999999999999\n",
       {"bad.off:8: ", "vertex index 99999999999999999999 is out of range"}},
      {"malformed index",
       head + kSquare + "3 0 1 2\n3 0 2 3.5\n",
       {"bad.off:8: ", "face 1: malformed vertex index \"3.5\""}},
      {"two-vertex face",
       head + kSquare + "3 0 1 2\n2 0 2\n",
       {"bad.off:8: ", "face 1 has 2 vertices; a face needs at least 3"}},
      {"degree beyond the line",
       head + kSquare + "3 0 1 2\n4 0 2 3\n",
       {"bad.off:8: ", "face 1 says 4 vertices but lists 3"}},
      {"huge degree", head + kSquare + "3 0 1 2\n4294967296 0 2 3\n", {"bad.off:8: ", "expected its vertex count"}},
      {"too many values",
       head + kSquare + "3 0 1 2\n3 0 2 3 1 1 1 1 1\n",
       {"bad.off:8: ", "more values than a colour takes"}},
      {"malformed colour",
       head + kSquare + "3 0 1 2\n3 0 2 3 blue\n",
       {"bad.off:8: ", "malformed colour value \"blue\""}},
      {"truncated",
       head + "0 0 0\n1 0 0\n# padding so the counts fit the file's length\n",
       {"bad.off:", "the file ends before vertex 2 of the 4 vertices the header declares"}},
      {"counts beyond the file",
       "OFF\n2000000000 1 0\n" + kSquare + faces,
       {"bad.off:2: ", "declares 2000000000 vertices and 1 faces, more than the", "truncated"}},
      {"count beyond int",
       "OFF\n4294967301 2 0\n" + kSquare + faces,
       {"bad.off:2: ", "\"4294967301\" is not an integer in [0, 2147483647]"}},
      {"negative count", "OFF\n-4 2 0\n" + kSquare + faces, {"bad.off:2: ", "expected the vertex and face counts"}},
      {"one count", "OFF\n4\n" + kSquare + faces, {"bad.off:2: ", "expected the vertex and face counts, got \"4\""}},
      {"data after the last face",
       head + kSquare + faces + "3 1 2 3\n",
       {"bad.off:9: ", "data after the last of the 2 faces"}},
      {"binary", "OFF BINARY\n", {"bad.off:1: ", "binary OFF is not supported"}},
      {"4D", "4OFF\n4 2 0\n", {"bad.off:1: ", "4D OFF"}},
      {"nOFF of another dimension", "nOFF\n2\n4 2 0\n", {"bad.off:2: ", "nOFF dimension \"2\""}},
      {"unknown keyword", "XOFF\n4 2 0\n", {"bad.off:1: ", "unknown keyword \"XOFF\""}},
      {"empty", "", {"bad.off: ", "not an OFF file"}},
      {"only a comment", "# nothing\n", {"not an OFF file"}},
      {"ends in the header", "OFF\n", {"bad.off:1: ", "the file ends before the OFF counts"}},
  };
  for (const Case& c : cases) {
    INFO(c.name);
    const std::string path = write_file(dir / "bad.off", c.text);
    const std::string message = error_of_reading(path);
    CHECK_THAT(message, Contains(path));
    for (const std::string& part : c.message) CHECK_THAT(message, Contains(part));
  }
}

TEST_CASE("OFF: read_off parses text in memory", "[mesh_io][off]") {
  const Mesh mesh = retarget::read_off("memory.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  CHECK(mesh.source == "memory.off");
  CHECK(mesh.faces.indices == std::vector<int>{0, 1, 2});
  CHECK_THROWS_WITH(retarget::read_off("memory.off", "OFF\n3 1 0\n0 0 0\n3 0 1 2\n1 0 0\n0 1 0\n"),
                    Contains("memory.off:4: ") && Contains("vertex 1 has 4 values"));
}
