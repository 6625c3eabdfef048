// read_obj on files large enough to be read in chunks on several threads: the mesh and every
// message must be the one-piece reader's (one thread).
#include "geometry/obj_reader.h"

#include <omp.h>

#include <catch2/catch.hpp>
#include <string>

#include "core/error.h"

using retarget::Error;
using retarget::Mesh;
using retarget::read_obj;

namespace {

// A grid of n x n vertices (~1 MB at n = 150) in the forms OBJ files take: comments, texture
// coordinates, v/vt/vn faces, CRLF lines, continued lines, faces that refer to vertices below them.
std::string grid_obj(int n) {
  std::string text = "# a grid\r\nmtllib grid.mtl\n";
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const int k = i * n + j;
      if (k % 97 == 5)
        text += "v " + std::to_string(0.013 * i) + " \\\n  " + std::to_string(-0.021 * j) + " 0.5\n";
      else
        text += "v " + std::to_string(0.013 * i) + " " + std::to_string(-0.021 * j) + " " +
                std::to_string(0.001 * (k % 13)) + (k % 7 == 0 ? "\r\n" : "\n");
      if (k % 50 == 0) text += "vt 0.5 0.5\n# row " + std::to_string(i) + " \\\n still the comment\n";
      // The quad above-left of this vertex once its row is written; every 40th a vertex ahead.
      if (i > 0 && j > 0) {
        const int a = (i - 1) * n + j, b = a + 1, c = k + 1, d = k;
        text += "f " + std::to_string(a) + "/1 " + std::to_string(b) + "/1/1 " + std::to_string(c) + "//1 " +
                std::to_string(d) + "\n";
      }
      if (k % 40 == 39 && k + n + 1 < n * n) text += "f 1 2 " + std::to_string(k + n + 1) + "\n";
    }
  return text;
}

// read_obj(path, text) on `threads` OpenMP threads; the message of what it threw, if it threw.
Mesh read_on(int threads, const std::string& text, std::string* message = nullptr) {
  const int before = omp_get_max_threads();
  omp_set_num_threads(threads);
  Mesh mesh;
  try {
    mesh = read_obj("grid.obj", text);
  } catch (const Error& e) {
    if (!message) {
      omp_set_num_threads(before);
      throw;
    }
    *message = e.what();
  }
  omp_set_num_threads(before);
  return mesh;
}

}  // namespace

TEST_CASE("read_obj reads a large file in chunks to the same mesh as in one piece", "[obj_reader]") {
  const std::string text = grid_obj(150);
  REQUIRE(text.size() > 3 * (size_t{256} << 10));
  const Mesh whole = read_on(1, text);
  REQUIRE(whole.vertex_count() == 150 * 150);
  size_t face_lines = 0;
  for (size_t at = text.find("\nf "); at != std::string::npos; at = text.find("\nf ", at + 1)) ++face_lines;
  REQUIRE(whole.faces.size() == static_cast<int>(face_lines));
  for (const int threads : {2, 3, 8}) {
    CAPTURE(threads);
    const Mesh chunks = read_on(threads, text);
    CHECK(chunks.vertices == whole.vertices);
    CHECK(chunks.faces.offsets == whole.faces.offsets);
    CHECK(chunks.faces.indices == whole.faces.indices);
  }
  SECTION("each read starts afresh on the reader's kept buffers, and a byte order mark is read once") {
    const std::string smaller = "\xEF\xBB\xBF" + grid_obj(120);
    const Mesh one = read_on(1, smaller), two = read_on(2, smaller), again = read_on(2, text);
    CHECK(one.vertex_count() == 120 * 120);
    CHECK(two.vertices == one.vertices);
    CHECK(two.faces.indices == one.faces.indices);
    CHECK(again.vertices == whole.vertices);
    CHECK(again.faces.offsets == whole.faces.offsets);
  }
}

TEST_CASE("read_obj in chunks: negative indices and errors are the one-piece reader's", "[obj_reader]") {
  const std::string text = grid_obj(150);
  const size_t late = text.rfind("\nf ", text.size() * 4 / 5) + 1;  // a face line in the last fifth
  SECTION("a face that counts back from its line") {
    const std::string relative = text.substr(0, late) + "f -1 -2 -3\n" + text.substr(late);
    const Mesh whole = read_on(1, relative), chunks = read_on(4, relative);
    CHECK(chunks.faces.indices == whole.faces.indices);
    CHECK(chunks.faces.offsets == whole.faces.offsets);
  }
  SECTION(
      "a malformed number, an index past the vertices, an index that counts back too far, a byte that is not text") {
    for (const std::string bad : {"v 1 2 x3\n", "f 1 2 99999999\n", "f 1 2 -99999999\n", "v 1 2 3 \x01\n"}) {
      CAPTURE(bad);
      const std::string broken = text.substr(0, late) + bad + text.substr(late);
      std::string one, several;
      read_on(1, broken, &one);
      read_on(4, broken, &several);
      REQUIRE_FALSE(one.empty());
      CHECK(several == one);
      CHECK_THAT(one, Catch::Contains("grid.obj:"));
    }
  }
}
