#include "geometry/off_reader.h"

#include <fmt/format.h>

#include <cmath>
#include <limits>
#include <vector>

#include "core/error.h"
#include "core/text_bytes.h"
#include "geometry/text_lines.h"

namespace retarget {

namespace {

// Face colours after the indices: an index into a colour map, RGB or RGBA.
constexpr size_t kMaxFaceColourValues = 4;

class OffReader {
 public:
  OffReader(const std::string& path, std::string_view text) : path_(path), lines_(text, 0, 1, '#') {}

  Mesh read() {
    const bool extras = read_keyword();
    const long long vertex_count = counts_[0], face_count = counts_[1];
    if (vertex_count == 0) throw Error(where(), "the mesh has no vertices");
    if (face_count == 0) throw Error(where(), "the mesh has no faces (a point cloud is not a mesh)");
    // Every vertex and face takes a line of at least one character and its newline (the last
    // line may lack one): refuse counts the file cannot hold before allocating.
    const unsigned long long least = 2ull * static_cast<unsigned long long>(vertex_count + face_count);
    if (least > lines_.remaining_bytes() + 1)
      throw Error(where(), fmt::format("the header declares {} vertices and {} faces, more than the {} bytes after "
                                       "it can hold: the file is truncated or its counts are wrong",
                                       vertex_count, face_count, lines_.remaining_bytes()));
    Mesh mesh;
    mesh.source = path_;
    mesh.vertices.resize(vertex_count, 3);
    for (long long v = 0; v < vertex_count; ++v) {
      next_line(fmt::format("vertex {} of the {} vertices", v, vertex_count));
      const size_t expected = 3;
      if (tokens_.size() < expected || (!extras && tokens_.size() > expected))
        throw Error(where(), fmt::format("vertex {} has {} value{}; expected x y z{}", v, tokens_.size(),
                                         tokens_.size() == 1 ? "" : "s",
                                         tokens_.size() > expected ? " (plain OFF has nothing else on a vertex line; "
                                                                     "is a face line among the vertices?)"
                                                                   : ""));
      for (size_t k = 0; k < tokens_.size(); ++k) {
        double value = 0;
        const NumberStatus status = parse_real(tokens_[k], value);
        if (status == NumberStatus::out_of_range)
          throw Error(where(), fmt::format("vertex {}: number {} is out of range for a double", v,
                                           retarget::quoted(tokens_[k])));
        if (status != NumberStatus::ok)
          throw Error(where(), fmt::format("vertex {}: malformed number {}", v, retarget::quoted(tokens_[k])));
        if (k >= 3) continue;  // normals, colours, texture coordinates
        if (!std::isfinite(value))
          throw Error(where(), fmt::format("vertex {} has a non-finite coordinate ({} = {})", v, "xyz"[k], value));
        mesh.vertices(static_cast<Eigen::Index>(v), static_cast<Eigen::Index>(k)) = value;
      }
    }
    mesh.faces.offsets.reserve(static_cast<size_t>(face_count) + 1);
    std::vector<int> polygon;
    for (long long f = 0; f < face_count; ++f) {
      next_line(fmt::format("face {} of the {} faces", f, face_count));
      long long degree = 0;
      const NumberStatus status = parse_integer(tokens_[0], 0, std::numeric_limits<int>::max(), degree);
      if (status != NumberStatus::ok)
        throw Error(where(),
                    fmt::format("face {}: expected its vertex count, got {}{}", f, retarget::quoted(tokens_[0]),
                                looks_real(tokens_[0]) ? " (a vertex line among the faces?)" : ""));
      if (degree < 3)
        throw Error(where(), fmt::format("face {} has {} {}; a face needs at least 3", f, degree,
                                         degree == 1 ? "vertex" : "vertices"));
      const size_t given = tokens_.size() - 1;
      if (given < static_cast<size_t>(degree))
        throw Error(where(), fmt::format("face {} says {} vertices but lists {}", f, degree, given));
      if (given > static_cast<size_t>(degree) + kMaxFaceColourValues)
        throw Error(where(), fmt::format("face {} says {} vertices but its line has {} more values than a colour "
                                         "takes (at most {})",
                                         f, degree, given - degree, kMaxFaceColourValues));
      polygon.clear();
      for (long long k = 1; k <= degree; ++k) {
        long long index = 0;
        const NumberStatus s = parse_integer(tokens_[k], std::numeric_limits<long long>::min(),
                                             std::numeric_limits<long long>::max(), index);
        if (s == NumberStatus::malformed)
          throw Error(where(), fmt::format("face {}: malformed vertex index {}", f, retarget::quoted(tokens_[k])));
        if (s != NumberStatus::ok || index < 0 || index >= vertex_count)
          throw Error(where(), fmt::format("face {}: vertex index {} is out of range: the file has {} vertices", f,
                                           std::string(tokens_[k].substr(0, 40)), vertex_count));
        polygon.push_back(static_cast<int>(index));
      }
      for (size_t k = static_cast<size_t>(degree) + 1; k < tokens_.size(); ++k) {
        double ignored = 0;
        if (parse_real(tokens_[k], ignored) != NumberStatus::ok)
          throw Error(where(), fmt::format("face {}: malformed colour value {}", f, retarget::quoted(tokens_[k])));
      }
      mesh.faces.add(polygon.data(), static_cast<int>(polygon.size()));
    }
    if (lines_.next(tokens_))
      throw Error(where(), fmt::format("data after the last of the {} faces the header declares: the counts are "
                                       "wrong",
                                       face_count));
    return mesh;
  }

 private:
  std::string where() const { return fmt::format("{}:{}", path_, lines_.line()); }

  static bool looks_real(std::string_view token) {
    double ignored = 0;
    return parse_real(token, ignored) == NumberStatus::ok;
  }

  void next_line(const std::string& what) {
    if (!lines_.next(tokens_)) throw Error(where(), "the file ends before " + what + " the header declares");
  }

  // The keyword and the counts; true when a prefix announces values after x y z.
  bool read_keyword() {
    if (!lines_.next(tokens_)) throw Error(path_, "not an OFF file: it does not start with \"OFF\"");
    std::string_view keyword = tokens_[0];
    if (keyword.size() < 3 || keyword.substr(keyword.size() - 3) != "OFF")
      throw Error(where(), "not an OFF file: it does not start with \"OFF\"");
    std::string_view prefix = keyword.substr(0, keyword.size() - 3);
    bool extras = false, dimension = false;
    if (prefix.substr(0, 2) == "ST") prefix.remove_prefix(2), extras = true;
    if (prefix.substr(0, 1) == "C") prefix.remove_prefix(1), extras = true;
    if (prefix.substr(0, 1) == "N") prefix.remove_prefix(1), extras = true;
    if (prefix.substr(0, 1) == "4") throw Error(where(), "4D OFF (4OFF) is not supported: only 3D meshes are read");
    if (prefix.substr(0, 1) == "n") prefix.remove_prefix(1), dimension = true;
    if (!prefix.empty())
      throw Error(where(), fmt::format("not an OFF file: unknown keyword {}", retarget::quoted(keyword)));
    size_t t = 1;
    const auto next_token = [&]() -> std::string_view {
      if (t >= tokens_.size()) {
        if (!lines_.next(tokens_)) throw Error(where(), "the file ends inside the OFF header");
        t = 0;
      }
      return tokens_[t++];
    };
    if (tokens_.size() > 1 && tokens_[1] == "BINARY")
      throw Error(where(), "binary OFF is not supported; convert the file to ASCII OFF, PLY or OBJ");
    if (dimension) {
      long long d = 0;
      const std::string_view token = next_token();
      if (parse_integer(token, 0, 1000, d) != NumberStatus::ok || d != 3)
        throw Error(where(), fmt::format("nOFF dimension {}: only 3D meshes are read", retarget::quoted(token)));
    }
    // The counts: #V #F and an optional #E, on one line.
    if (t >= tokens_.size()) {
      if (!lines_.next(tokens_)) throw Error(where(), "the file ends before the OFF counts");
      t = 0;
    }
    const size_t given = tokens_.size() - t;
    if (given < 2 || given > 3)
      throw Error(where(),
                  fmt::format("OFF header: expected the vertex and face counts, got \"{}\"", join(tokens_, t)));
    for (size_t k = 0; k < given; ++k)
      if (parse_integer(tokens_[t + k], 0, std::numeric_limits<int>::max(), counts_[k]) != NumberStatus::ok)
        throw Error(where(),
                    fmt::format("OFF header: expected the vertex and face counts, got \"{}\" ({} is not an "
                                "integer in [0, {}])",
                                join(tokens_, t), retarget::quoted(tokens_[t + k]), std::numeric_limits<int>::max()));
    return extras;
  }

  static std::string join(const std::vector<std::string_view>& tokens, size_t from) {
    std::string text;
    for (size_t k = from; k < tokens.size() && text.size() < 80; ++k)
      text += (k > from ? " " : "") + std::string(tokens[k]);
    return text;
  }

  const std::string& path_;
  TextLines lines_;
  std::vector<std::string_view> tokens_;
  long long counts_[3] = {0, 0, 0};
};

}  // namespace

Mesh read_off(const std::string& path, std::string_view text) {
  require_text(text, path, "an OFF file is text", true);  // bytes 0x80 and up: a Latin-1 comment
  return OffReader(path, text).read();
}

}  // namespace retarget
