#include "geometry/face_folder.h"

#include <catch2/catch.hpp>
#include <fstream>

#include "core/error.h"
#include "geometry/mesh_io.h"
#include "test_support.h"

using namespace retarget;
namespace fs = std::filesystem;

namespace {

Mesh grid() { return test::quad_grid(2, 2, 1.0, 1.0); }  // 9 vertices

// <dir>/<subject>/<expression>.obj for every pair, each a slightly moved grid.
void write_folder(const fs::path& dir, const std::vector<std::string>& subjects,
                  const std::vector<std::string>& expressions) {
  const Mesh g = grid();
  int k = 0;
  for (const std::string& s : subjects)
    for (const std::string& e : expressions) {
      Positions p = g.vertices;
      p.col(2).array() += 0.01 * ++k;
      write_mesh((dir / s / (e + ".obj")).string(), with_positions(g, p));
    }
}

}  // namespace

TEST_CASE("a face folder lists subjects and expressions, the neutral first", "[face_folder]") {
  const auto dir = test::scratch_dir("face_folder_ok");
  write_folder(dir, {"bob", "alice"}, {"smile", "neutral", "frown"});
  std::ofstream(dir / "alice" / "notes.txt") << "not a mesh";  // other files are ignored
  const FaceFolder faces = open_face_folder(dir.string());
  CHECK(faces.subjects == std::vector<std::string>{"alice", "bob"});
  CHECK(faces.expressions == std::vector<std::string>{"neutral", "frown", "smile"});
  CHECK(faces.neutral == 0);
  CHECK(faces.subject_index("bob") == 1);
  CHECK(faces.expression_index("smile") == 2);
  CHECK(faces.expression_index("pout") == -1);
  CHECK(fs::path(faces.path(1, 2)) == dir / "bob" / "smile.obj");
  CHECK(faces.topology.vertex_count() == 9);
  const Positions p = faces.read(1, 2);
  CHECK(p.rows() == 9);
  CHECK(p(0, 2) == Approx(read_mesh((dir / "bob" / "smile.obj").string()).vertices(0, 2)));

  // Another neutral name, or none.
  FaceFolderOptions options;
  options.neutral = "smile";
  const FaceFolder by_smile = open_face_folder(dir.string(), options);
  CHECK(by_smile.expressions.front() == "smile");
  CHECK(by_smile.neutral == 0);
  options.neutral = "rest";
  CHECK(open_face_folder(dir.string(), options).neutral == -1);
  options.neutral = "";
  CHECK(open_face_folder(dir.string(), options).expressions.front() == "frown");
}

TEST_CASE("a face folder whose subjects differ says what is missing where", "[face_folder]") {
  const auto dir = test::scratch_dir("face_folder_missing");
  write_folder(dir, {"a", "c"}, {"neutral", "smile", "frown"});
  write_folder(dir, {"b"}, {"neutral"});
  write_folder(dir, {"c"}, {"pout"});
  CHECK_THROWS_WITH(open_face_folder(dir.string()),
                    Catch::Contains("face_folder_missing") && Catch::Contains("same expressions") &&
                        Catch::Contains("a lacks pout") && Catch::Contains("b lacks frown, pout, smile") &&
                        Catch::Contains("2 of 3 subjects") && !Catch::Contains("c lacks"));
}

TEST_CASE("a face folder mesh of another topology names the file and the counts", "[face_folder]") {
  const auto dir = test::scratch_dir("face_folder_topology");
  write_folder(dir, {"a", "b"}, {"neutral", "smile"});
  write_mesh((dir / "b" / "smile.obj").string(), test::quad_grid(3, 2, 1.0, 1.0));  // 12 vertices
  const FaceFolder faces = open_face_folder(dir.string());
  CHECK_NOTHROW(faces.read(1, 0));
  CHECK_THROWS_WITH(faces.read(1, 1), Catch::Contains((dir / "b" / "smile.obj").string()) &&
                                          Catch::Contains("12 vertices") && Catch::Contains("has 9") &&
                                          Catch::Contains((dir / "a" / "neutral.obj").string()));
}

TEST_CASE("bad face folders are refused with the reason", "[face_folder]") {
  const auto dir = test::scratch_dir("face_folder_errors");
  CHECK_THROWS_WITH(open_face_folder((dir / "nowhere").string()),
                    Catch::Contains("nowhere") && Catch::Contains("not found"));
  CHECK_THROWS_WITH(open_face_folder(dir.string()), Catch::Contains("no subject folders"));
  fs::create_directories(dir / "empty_subject");
  CHECK_THROWS_WITH(open_face_folder(dir.string()),
                    Catch::Contains("empty_subject") && Catch::Contains("no mesh files"));
  fs::remove_all(dir / "empty_subject");
  write_folder(dir, {"a"}, {"neutral", "smile"});
  write_mesh((dir / "a" / "smile.off").string(), grid());
  CHECK_THROWS_WITH(open_face_folder(dir.string()), Catch::Contains("two meshes for expression \"smile\"") &&
                                                        Catch::Contains("smile.obj") && Catch::Contains("smile.off"));
}
