#include "geometry/mesh_io.h"

#include <sys/stat.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "core/error.h"
#include "geometry/mesh_validation.h"
#include "test_support.h"

namespace fs = std::filesystem;
using Catch::Contains;
using retarget::Error;
using retarget::Mesh;
using retarget::test::error_of;
using retarget::test::write_file;

namespace {

std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

std::vector<std::string> folder_entries(const fs::path& folder) {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(folder)) names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

// Triangles, quads and a pentagon, manifold so OpenMesh can store it too: a closed
// sphere (triangle fans at the poles, quads between) with irrational coordinates.
Mesh mixed_mesh() {
  Mesh mesh = retarget::test::uv_sphere(5, 7, 1.37);
  mesh.vertices.col(0) *= M_PI;  // digits that a short decimal cannot carry
  return mesh;
}

Mesh house() {  // a pentagon with a triangle and a quad attached
  Mesh mesh;
  mesh.vertices.resize(8, 3);
  mesh.vertices << 0, 0, 0, 1, 0, 0, 1, 1, 0, 0.5, 1.5, 0, 0, 1, 0, 2, 0, 0, 2, 1, 0, 0.5, -1, 0.25;
  const int pentagon[5] = {0, 1, 2, 3, 4}, quad[4] = {1, 5, 6, 2}, triangle[3] = {0, 7, 1};
  mesh.faces.add(pentagon, 5);
  mesh.faces.add(quad, 4);
  mesh.faces.add(triangle, 3);
  retarget::triangulate(mesh);
  return mesh;
}

void check_same_faces(const Mesh& read, const Mesh& written) {
  CHECK(read.faces.offsets == written.faces.offsets);
  CHECK(read.faces.indices == written.faces.indices);
  CHECK(read.triangles == written.triangles);
  CHECK(read.triangle_face == written.triangle_face);
}

}  // namespace

TEST_CASE("OBJ round trip keeps faces and positions exactly", "[mesh_io]") {
  const auto dir = retarget::test::scratch_dir("mesh_io_obj_round_trip");
  for (const Mesh& mesh : {mixed_mesh(), house()}) {
    const std::string path = (dir / "mesh.obj").string();
    retarget::write_mesh(path, mesh);
    const Mesh read = retarget::read_mesh(path);
    CHECK(read.source == path);
    CHECK(read.vertices == mesh.vertices);  // shortest round-trip digits: bit-exact
    check_same_faces(read, mesh);
  }
}

TEST_CASE("files read one after another on a thread each come back whole (the reader keeps its memory)", "[mesh_io]") {
  const auto dir = retarget::test::scratch_dir("mesh_io_kept_memory");
  const Mesh large = retarget::test::uv_sphere(120, 160, 1.0), small = house();
  const std::string large_path = (dir / "large.obj").string(), small_path = (dir / "small.obj").string(),
                    off_path = (dir / "small.off").string();
  retarget::write_mesh(large_path, large);
  retarget::write_mesh(small_path, small);
  retarget::write_mesh(off_path, small);
  for (const std::string& path : {large_path, small_path, off_path, large_path, small_path}) {
    CAPTURE(path);
    const Mesh read = retarget::read_mesh(path);
    const Mesh& written = path == large_path ? large : small;
    CHECK(read.vertices == written.vertices);
    check_same_faces(read, written);
  }
}

TEST_CASE("PLY and OFF round trips keep faces exactly and positions to float precision", "[mesh_io]") {
  const auto dir = retarget::test::scratch_dir("mesh_io_ply_off_round_trip");
  struct Case {
    std::string file;
    bool binary_ply;
  };
  for (const Case& c : {Case{"mesh.ply", true}, Case{"ascii.ply", false}, Case{"mesh.off", true}}) {
    for (const Mesh& mesh : {mixed_mesh(), house()}) {
      INFO(c.file);
      const std::string path = (dir / c.file).string();
      retarget::write_mesh(path, mesh, retarget::MeshWriteOptions{c.binary_ply});
      const Mesh read = retarget::read_mesh(path);
      CHECK(read.source == path);
      REQUIRE(read.vertex_count() == mesh.vertex_count());
      // OpenMesh writes PLY coordinates as 32-bit floats.
      CHECK((read.vertices - mesh.vertices).cwiseAbs().maxCoeff() <= 1e-6 * mesh.vertices.cwiseAbs().maxCoeff());
      check_same_faces(read, mesh);
    }
  }
  CHECK_THAT(read_text(dir / "mesh.ply"), Contains("format binary_little_endian"));
  CHECK_THAT(read_text(dir / "ascii.ply"), Contains("format ascii"));
}

TEST_CASE("OFF is written with full double precision", "[mesh_io]") {
  const auto dir = retarget::test::scratch_dir("mesh_io_off_text");
  const Mesh mesh = house();
  retarget::write_mesh((dir / "house.off").string(), mesh);
  std::istringstream text(read_text(dir / "house.off"));
  std::string keyword;
  int nv = 0, nf = 0, ne = 0;
  text >> keyword >> nv >> nf >> ne;
  CHECK(keyword == "OFF");
  CHECK(nv == 8);
  CHECK(nf == 3);
  for (int i = 0; i < nv; ++i)
    for (int c = 0; c < 3; ++c) {
      double value = 0;
      text >> value;
      CHECK(value == mesh.vertices(i, c));
    }
  int degree = 0;
  text >> degree;
  CHECK(degree == 5);
}

TEST_CASE("extensions are case-insensitive", "[mesh_io]") {
  const auto dir = retarget::test::scratch_dir("mesh_io_case");
  const Mesh mesh = house();
  for (const char* name : {"HOUSE.OBJ", "House.Ply", "house.OFF"}) {
    INFO(name);
    const std::string path = (dir / name).string();
    retarget::write_mesh(path, mesh);
    CHECK(retarget::read_mesh(path).faces.indices == mesh.faces.indices);
  }
}

TEST_CASE("OBJ variants read the same faces", "[mesh_io]") {
  const auto dir = retarget::test::scratch_dir("mesh_io_obj_variants");
  const std::string square = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n";
  struct Case {
    const char* name;
    std::string text;
  };
  const std::vector<Case> cases = {
      {"plain", square + "f 1 2 3 4\n"},
      {"v/vt", square + "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nf 1/1 2/2 3/3 4/4\n"},
      {"v//vn", square + "vn 0 0 1\nf 1//1 2//1 3//1 4//1\n"},
      {"v/vt/vn", square + "vt 0 0\nvn 0 0 1\nf 1/1/1 2/1/1 3/1/1 4/1/1\n"},
      {"negative vt/vn", square + "vt 0 0\nvn 0 0 1\nf 1/-1/-1 2/-1/-1 3/-1/-1 4/-1/-1\n"},
      {"relative indices", square + "f -4 -3 -2 -1\n"},
      {"CRLF", "v 0 0 0\r\nv 1 0 0\r\nv 1 1 0\r\nv 0 1 0\r\nf 1 2 3 4\r\n"},
      {"tabs and trailing spaces", "v\t0\t0\t0   \nv 1 0 0\t\nv  1  1  0\nv 0 1 0 \n\tf 1\t2 3  4  \n"},
      {"comments and other keywords", "# a comment\n\nmtllib face.mtl\no face\ng skin\ns 1\nusemtl skin\n" + square +
                                          "vp 0.5\n# f 9 9 9\nl 1 2\nf 1 2 3 4 # trailing comment\n"},
      {"continuation", square + "f 1 2 \\\n  3 4\n"},
      {"continuation with CRLF and spaces after the backslash", square + "f 1 2\\  \r\n3 4\r\n"},
      {"continued vertex", "v 0 \\\n0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n"},
      {"extra vertex values (w, colours)", "v 0 0 0 1\nv 1 0 0 0.5 0.5 0.5\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n"},
      {"leading plus and exponents", "v +0 0e0 0\nv 1.0E+0 0 0\nv 1 1 -0\nv 0 1 0.\nf 1 2 3 4\n"},
      {"faces before vertices", "f 1 2 3 4\n" + square},
      {"no final newline", square + "f 1 2 3 4"},
      {"byte order mark", "\xEF\xBB\xBF" + square + "f 1 2 3 4\n"},
  };
  for (const Case& c : cases) {
    INFO(c.name);
    const Mesh mesh = retarget::read_mesh(write_file(dir / "variant.obj", c.text));
    REQUIRE(mesh.vertex_count() == 4);
    CHECK(mesh.vertices.row(2) == Eigen::RowVector3d(1, 1, 0));
    CHECK(mesh.faces.indices == std::vector<int>{0, 1, 2, 3});
    CHECK(mesh.faces.offsets == std::vector<int>{0, 4});
    CHECK(mesh.triangle_count() == 2);
  }
}

TEST_CASE("OBJ relative indices refer to the vertices above the face", "[mesh_io]") {
  const auto dir = retarget::test::scratch_dir("mesh_io_obj_relative");
  const Mesh mesh = retarget::read_mesh(
      write_file(dir / "relative.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\nv 1 1 0\nf -3 -1 -2\nf 2 4 -2\n"));
  CHECK(mesh.faces.indices == std::vector<int>{0, 1, 2, 1, 3, 2, 1, 3, 2});
}

TEST_CASE("OBJ read errors name file:line and the fault", "[mesh_io]") {
  const auto dir = retarget::test::scratch_dir("mesh_io_obj_errors");
  const std::string triangle = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
  struct Case {
    const char* name;
    std::string text;
    std::vector<std::string> message;  // substrings
  };
  const std::vector<Case> cases = {
      {"malformed number", "v 0 0 0\nv 1.0 abc 2\n", {"bad.obj:2: ", "malformed number \"abc\""}},
      {"decimal comma", "v 0 0 0\n\nv 1,5 0 0\n", {"bad.obj:3: ", "malformed number \"1,5\""}},
      {"number glued to text", "v 1.5x 0 0\n", {"bad.obj:1: ", "\"1.5x\""}},
      {"too few coordinates", "v 1 2\n", {"bad.obj:1: ", "vertex has 2 coordinates; expected x y z"}},
      {"out-of-range double", "v 1e999 0 0\n", {"bad.obj:1: ", "\"1e999\" is out of range"}},
      {"nan", triangle + "v 0 nan 0\nf 1 2 3\n", {"bad.obj:4: ", "vertex 4 has a non-finite coordinate (y = nan)"}},
      {"inf", triangle + "v inf 0 0\nf 1 2 3\n", {"bad.obj:4: ", "(x = inf)"}},
      {"two-vertex face", triangle + "f 1 2\n", {"bad.obj:4: ", "face has 2 vertices; a face needs at least 3"}},
      {"index 0", triangle + "f 0 1 2\n", {"bad.obj:4: ", "index 0"}},
      {"index out of range",
       triangle + "# comment\nf 1 2 3\nf 1 2 9\n",
       {"bad.obj:6: ", "face vertex index 9 is out of range: the file has 3 vertices"}},
      {"relative index out of range", triangle + "f -1 -2 -4\n", {"bad.obj:4: ", "-4", "only 3 vertices"}},
      {"malformed face vertex", triangle + "f 1 2 x\n", {"bad.obj:4: ", "malformed face vertex \"x\""}},
      {"malformed slashes", triangle + "f 1/a 2 3\n", {"bad.obj:4: ", "\"1/a\""}},
      {"line count follows continuations", triangle + "f 1 2 \\\n 3\nf 1 2\n", {"bad.obj:6: ", "face has 2"}},
      {"index overflow", triangle + "f 1 2 99999999999\n", {"bad.obj:4: ", "\"99999999999\" is out of range"}},
      {"binary junk",
       std::string("\x7f"
                   "ELF\x02\x01\x01\0\0\0",
                   10),
       {"bad.obj: line 1, column 1: byte 0x7F is not text; an OBJ file is text (is this a binary file?)"}},
      {"a NUL inside a number",
       triangle + std::string("v 0.\0"
                              "5 0 0\n",
                              11),
       {"bad.obj: line 4, column 5: byte 0x00"}},
  };
  // A Latin-1 comment (bytes 0x80 and up that are not UTF-8) is still an OBJ file.
  CHECK(retarget::read_mesh(write_file(dir / "latin1.obj", "# cr\xe9\xe9 par Blender\n" + triangle + "f 1 2 3\n"))
            .vertex_count() == 3);
  for (const Case& c : cases) {
    INFO(c.name);
    const std::string path = write_file(dir / "bad.obj", c.text);
    const std::string message = error_of([&] { retarget::read_mesh(path); });
    CHECK_THAT(message, Contains(path));
    for (const std::string& part : c.message) CHECK_THAT(message, Contains(part));
  }
}

TEST_CASE("missing, unreadable and unsupported files name the path and the reason", "[mesh_io]") {
  const auto dir = retarget::test::scratch_dir("mesh_io_file_errors");

  const std::string missing = (dir / "missing.obj").string();
  CHECK_THAT(error_of([&] { retarget::read_mesh(missing); }),
             Contains(missing) && Contains("cannot open") && Contains("No such file or directory"));

  fs::create_directories(dir / "folder.obj");
  CHECK_THAT(error_of([&] { retarget::read_mesh((dir / "folder.obj").string()); }), Contains("is a folder"));

  const std::string stl = write_file(dir / "mesh.stl", "solid x\n");
  CHECK_THAT(error_of([&] { retarget::read_mesh(stl); }),
             Contains(stl) && Contains("unsupported mesh format \".stl\"") && Contains(".obj, .ply, .off"));
  CHECK_THAT(error_of([&] { retarget::write_mesh((dir / "out.stl").string(), house()); }),
             Contains("unsupported mesh format \".stl\""));
  const std::string no_extension = write_file(dir / "noextension", "v 0 0 0\n");
  CHECK_THAT(error_of([&] { retarget::read_mesh(no_extension); }), Contains("(no extension)"));
  // A path that does not exist says so, not that its (missing) extension is unsupported.
  for (const fs::path& absent : {dir / "no_such_folder", dir / "no_such_folder" / "face.obj", dir / "gone.stl"}) {
    INFO(absent);
    CHECK_THAT(error_of([&] { retarget::read_mesh(absent.string()); }),
               Contains(absent.string()) && Contains("No such file or directory") &&
                   Contains("no file or folder exists at this path") && !Contains("unsupported"));
  }

  if (::geteuid() != 0) {  // root reads anything
    const std::string locked = write_file(dir / "locked.obj", "v 0 0 0\n");
    ::chmod(locked.c_str(), 0);
    CHECK_THAT(error_of([&] { retarget::read_mesh(locked); }), Contains(locked) && Contains("Permission denied"));
  }
}

TEST_CASE("empty meshes are rejected with the file name", "[mesh_io]") {
  const auto dir = retarget::test::scratch_dir("mesh_io_empty");
  struct Case {
    const char* file;
    std::string text;
    const char* message;
  };
  const std::vector<Case> cases = {
      {"empty.obj", "", "no vertices"},
      {"comments.obj", "# nothing here\n\n", "no vertices"},
      {"points.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n", "no faces"},
      {"empty.off", "OFF\n0 0 0\n", "no vertices"},
      {"points.off", "OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0\n", "no faces"},
      {"points.ply",
       "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
       "element face 0\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n",
       "no faces"},
  };
  for (const Case& c : cases) {
    INFO(c.file);
    const std::string path = write_file(dir / c.file, c.text);
    CHECK_THAT(error_of([&] { retarget::read_mesh(path); }), Contains(path) && Contains(c.message));
  }
}

TEST_CASE("PLY and OFF files are read as written, faces OpenMesh could not store included", "[mesh_io]") {
  const auto dir = retarget::test::scratch_dir("mesh_io_as_written");
  const std::string ply_header =
      "ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 3\nproperty list uchar int vertex_indices\nend_header\n";
  const std::string five_vertices = "0 0 0\n1 0 0\n0 1 0\n0 -1 0\n0 0 1\n";

  SECTION("three faces on one edge") {
    const Mesh mesh =
        retarget::read_mesh(write_file(dir / "fin.ply", ply_header + five_vertices + "3 0 1 2\n3 1 0 3\n3 0 1 4\n"));
    CHECK(mesh.vertex_count() == 5);
    CHECK(mesh.faces.indices == std::vector<int>{0, 1, 2, 1, 0, 3, 0, 1, 4});
    CHECK(retarget::validate_mesh(mesh).nonmanifold_edges == 1);
  }
  SECTION("a face repeating a vertex is kept (and counted as degenerate)") {
    const Mesh mesh =
        retarget::read_mesh(write_file(dir / "repeat.off", "OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 1 1\n"));
    CHECK(mesh.faces.size() == 2);
    CHECK(retarget::validate_mesh(mesh).degenerate_faces == 1);
  }
  SECTION("OFF forms OpenMesh misread: comments, counts on the keyword line") {
    for (const std::string& text :
         {std::string("OFF\n3 1 0\n0 0 0\n# the second vertex\n1 0 0\n0 1 0\n3 0 1 2\n"),
          std::string("OFF 3 1 0\n0 0 0\n1 0 0 # x\n\n0 1 0\n3 0 1 2\n"),
          std::string("# made by hand\nOFF\n3 1\r\n0 0 0\r\n1 0 0\r\n0 1 0\r\n3 0 1 2 0.5 0.5 0.5\r\n")}) {
      INFO(text);
      const Mesh mesh = retarget::read_mesh(write_file(dir / "variant.off", text));
      CHECK(mesh.vertices.row(1) == Eigen::RowVector3d(1, 0, 0));
      CHECK(mesh.faces.indices == std::vector<int>{0, 1, 2});
    }
  }
  SECTION("out-of-range indices and truncated files name the line") {
    const std::string range =
        write_file(dir / "range.off", "OFF\n4 2 0\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n3 0 1 2\n3 1 3 7\n");
    CHECK_THAT(error_of([&] { retarget::read_mesh(range); }),
               Contains(range + ":8: ") && Contains("face 1: vertex index 7 is out of range: the file has 4 vertices"));
    const std::string truncated = write_file(dir / "truncated.off", "OFF\n4 1 0\n0 0 0\n1 0 0\n");
    CHECK_THAT(error_of([&] { retarget::read_mesh(truncated); }),
               Contains(truncated + ":4: ") && Contains("the file ends before vertex 2 of the 4 vertices"));
  }
  SECTION("the same fin as OBJ writes back to OBJ and OFF, but not to PLY (OpenMesh cannot store it)") {
    const std::string path =
        write_file(dir / "fin.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nf 1 2 3\nf 2 1 4\nf 1 2 5\n");
    const Mesh mesh = retarget::read_mesh(path);
    retarget::write_mesh((dir / "fin_copy.obj").string(), mesh);
    CHECK(retarget::read_mesh((dir / "fin_copy.obj").string()).faces.indices == mesh.faces.indices);
    retarget::write_mesh((dir / "fin_copy.off").string(), mesh);
    CHECK(retarget::read_mesh((dir / "fin_copy.off").string()).faces.indices == mesh.faces.indices);
    CHECK_THAT(error_of([&] { retarget::write_mesh((dir / "fin_copy.ply").string(), mesh); }),
               Contains("fin_copy.ply") && Contains("cannot write as PLY") && Contains("face 2"));
    CHECK_FALSE(fs::exists(dir / "fin_copy.ply"));
  }
  SECTION("headers that are not PLY or OFF") {
    const std::string ply = write_file(dir / "text.ply", "hello\n");
    CHECK_THAT(error_of([&] { retarget::read_mesh(ply); }), Contains(ply) && Contains("not a PLY file"));
    const std::string no_end = write_file(dir / "no_end.ply", "ply\nformat ascii 1.0\nelement vertex 3\n");
    CHECK_THAT(error_of([&] { retarget::read_mesh(no_end); }), Contains("no end_header"));
    const std::string off = write_file(dir / "text.off", "hello\n");
    CHECK_THAT(error_of([&] { retarget::read_mesh(off); }), Contains(off) && Contains("not an OFF file"));
    const std::string counts = write_file(dir / "counts.off", "OFF\nthree 1 0\n");
    CHECK_THAT(error_of([&] { retarget::read_mesh(counts); }), Contains("expected the vertex and face counts"));
  }
}

TEST_CASE("PLY/OFF non-finite coordinates name the file and the vertex", "[mesh_io]") {
  const auto dir = retarget::test::scratch_dir("mesh_io_ply_validation");
  std::string ply =
      "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
  const float xyz[9] = {0, 0, 0, 1, 0, 0, 0, 1, std::numeric_limits<float>::infinity()};
  ply.append(reinterpret_cast<const char*>(xyz), sizeof xyz);
  const unsigned char degree = 3;
  const std::int32_t face[3] = {0, 1, 2};
  ply.append(reinterpret_cast<const char*>(&degree), 1);
  ply.append(reinterpret_cast<const char*>(face), sizeof face);
  const std::string path = write_file(dir / "inf.ply", ply);
  CHECK_THAT(error_of([&] { retarget::read_mesh(path); }),
             Contains(path) && Contains("vertex 2 has a non-finite coordinate (z = inf)"));
}

TEST_CASE("writing replaces the file atomically and leaves no temporary file", "[mesh_io]") {
  const auto dir = retarget::test::scratch_dir("mesh_io_atomic");
  for (const char* name : {"mesh.obj", "mesh.off", "mesh.ply"}) {
    INFO(name);
    const fs::path path = dir / name;
    write_file(path, "old contents\n");
    retarget::write_mesh(path.string(), house());
    CHECK(retarget::read_mesh(path.string()).faces.indices == house().faces.indices);
    retarget::write_mesh(path.string(), mixed_mesh());
    CHECK(retarget::read_mesh(path.string()).vertex_count() == mixed_mesh().vertex_count());

    // A mesh that cannot be written leaves the old file as it was.
    Mesh bad = house();
    bad.vertices(3, 1) = std::nan("");
    const std::string before = read_text(path);
    CHECK_THAT(error_of([&] { retarget::write_mesh(path.string(), bad); }),
               Contains(path.string()) && Contains("cannot write an invalid mesh") &&
                   Contains("vertex 3 has a non-finite coordinate (y = nan)"));
    CHECK(read_text(path) == before);
  }
  CHECK(folder_entries(dir) == std::vector<std::string>{"mesh.obj", "mesh.off", "mesh.ply"});

  // Missing parent folders are created.
  const fs::path nested = dir / "a" / "b" / "mesh.obj";
  retarget::write_mesh(nested.string(), house());
  CHECK(fs::exists(nested));
  CHECK(folder_entries(nested.parent_path()) == std::vector<std::string>{"mesh.obj"});
}
