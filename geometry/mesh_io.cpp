// OpenMesh default-constructs its points uninitialised on purpose (PropertyT::push_back);
// GCC 12 flags that inside the standard library headers, so the warning is off for this file.
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"

#include "geometry/mesh_io.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/PolyMesh_ArrayKernelT.hh>
#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <limits>
#include <mutex>
#include <string_view>
#include <vector>

#include "core/atomic_file.h"
#include "core/error.h"
#include "geometry/mesh_validation.h"

namespace retarget {

namespace {

enum class Format { obj, ply, off };

Format format_of(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  if (ext == ".obj") return Format::obj;
  if (ext == ".ply") return Format::ply;
  if (ext == ".off") return Format::off;
  throw Error(path, fmt::format("unsupported mesh format \"{}\"; supported: .obj, .ply, .off",
                                ext.empty() ? "(no extension)" : ext));
}

// A whole file's bytes. Regular files are mapped (MAP_POPULATE: one call, no zero-filled
// buffer, no copy), which saved a quarter of an OBJ read's time; anything mmap refuses is
// read. Files are replaced by rename (write_file_atomically), so a mapped file does not
// change under the parser.
class FileBytes {
 public:
  explicit FileBytes(const std::string& path) {
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) throw Error(path, std::string("cannot open the mesh file: ") + std::strerror(errno));
    try {
      load(path, fd);
    } catch (...) {
      ::close(fd);
      throw;
    }
    ::close(fd);
  }
  ~FileBytes() {
    if (map_) ::munmap(map_, map_size_);
  }
  FileBytes(const FileBytes&) = delete;
  FileBytes& operator=(const FileBytes&) = delete;

  std::string_view view() const { return view_; }

 private:
  void load(const std::string& path, int fd) {
    struct stat info {};
    if (::fstat(fd, &info) != 0) throw Error(path, std::string("cannot read the mesh file: ") + std::strerror(errno));
    if (S_ISDIR(info.st_mode)) throw Error(path, "is a folder, not a mesh file");
    if (S_ISREG(info.st_mode) && info.st_size > 0) {
      map_size_ = static_cast<size_t>(info.st_size);
      void* map = ::mmap(nullptr, map_size_, PROT_READ, MAP_PRIVATE | MAP_POPULATE, fd, 0);
      if (map != MAP_FAILED) {
        map_ = map;
        view_ = std::string_view(static_cast<const char*>(map), map_size_);
        return;
      }
    }
    for (;;) {  // pipes, special files, or mmap refused
      char chunk[1 << 16];
      const ssize_t got = ::read(fd, chunk, sizeof chunk);
      if (got == 0) break;
      if (got < 0) {
        if (errno == EINTR) continue;
        throw Error(path, std::string("cannot read the mesh file: ") + std::strerror(errno));
      }
      buffer_.append(chunk, static_cast<size_t>(got));
    }
    view_ = buffer_;
  }

  void* map_ = nullptr;
  size_t map_size_ = 0;
  std::string buffer_;
  std::string_view view_;
};

// ---------------------------------------------------------------------------------------
// OBJ: one pass over the file's bytes, numbers parsed in place (std::from_chars for
// coordinates, correctly rounded); no per-line strings and no iostreams, which is what
// makes it an order of magnitude faster than OpenMesh's reader.
class ObjReader {
 public:
  ObjReader(const std::string& path, std::string_view text)
      : path_(path), p_(text.data()), end_(text.data() + text.size()) {}

  Mesh read() {
    // Upper bounds ("v 0 0 0\n" is 8 bytes, a face index at least 2), so the vectors do not
    // reallocate; untouched capacity is never paged in, and the mesh gets exact-size copies.
    // Capped so a huge file does not ask for gigabytes up front.
    const size_t bytes = static_cast<size_t>(end_ - p_), cap = size_t{1} << 23;
    coordinates_.reserve(std::min(3 * (bytes / 8 + 1), cap));
    indices_.reserve(std::min(bytes / 2 + 1, cap));
    offsets_.reserve(std::min(bytes / 6 + 2, cap));
    offsets_.push_back(0);
    // A UTF-8 byte order mark would otherwise hide a first "v" line and shift every index.
    if (end_ - p_ >= 3 && std::memcmp(p_, "\xEF\xBB\xBF", 3) == 0) p_ += 3;
    while (p_ < end_) {
      skip_blanks();
      if (p_ == end_) break;
      if (*p_ == '\n') {
        ++p_;
        ++line_;
        continue;
      }
      const char* keyword = p_;
      while (!ends_token(p_)) ++p_;
      const std::string_view word(keyword, p_ - keyword);
      if (word == "v")
        read_vertex();
      else if (word == "f")
        read_face();
      else
        next_line();  // vt, vn, vp, g, o, s, l, usemtl, mtllib, comments, ...
    }

    const int vertex_count = static_cast<int>(coordinates_.size() / 3);
    if (max_index_ >= vertex_count)
      throw Error(
          fmt::format("{}:{}", path_, max_index_line_),
          fmt::format("face vertex index {} is out of range: the file has {} vertices", max_index_ + 1, vertex_count));
    Mesh mesh;
    mesh.source = path_;
    mesh.vertices = Eigen::Map<const Positions>(coordinates_.data(), vertex_count, 3);
    mesh.faces.offsets.assign(offsets_.begin(), offsets_.end());
    mesh.faces.indices.assign(indices_.begin(), indices_.end());
    return mesh;
  }

 private:
  static bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

  // q points at a backslash. When only blanks follow it up to the newline (or the end of
  // the file), the line continues on the next one: returns the position after the newline.
  const char* continuation_end(const char* q) const {
    const char* r = q + 1;
    while (r < end_ && is_blank(*r)) ++r;
    if (r == end_) return r;
    return *r == '\n' ? r + 1 : nullptr;
  }

  bool ends_token(const char* q) const {
    return q == end_ || is_blank(*q) || *q == '\n' || *q == '#' || (*q == '\\' && continuation_end(q));
  }

  bool at_line_end() const { return p_ == end_ || *p_ == '\n' || *p_ == '#'; }

  void skip_blanks() {
    while (p_ < end_) {
      if (is_blank(*p_)) {
        ++p_;
      } else if (const char* after = *p_ == '\\' ? continuation_end(p_) : nullptr) {
        if (after[-1] == '\n') ++line_;
        p_ = after;
      } else {
        return;
      }
    }
  }

  // Moves past the current line's newline, following continuations.
  void next_line() {
    if (p_ < end_ && *p_ == '\n') {  // the usual case after a vertex or a face
      ++p_;
      ++line_;
      return;
    }
    while (p_ < end_) {
      const char* newline = static_cast<const char*>(std::memchr(p_, '\n', end_ - p_));
      if (!newline) {
        p_ = end_;
        return;
      }
      const char* last = newline;
      while (last > p_ && is_blank(last[-1])) --last;
      const bool continues = last > p_ && last[-1] == '\\';
      p_ = newline + 1;
      ++line_;
      if (!continues) return;
    }
  }

  std::string where() const { return fmt::format("{}:{}", path_, line_); }

  std::string token_at(const char* q) const {
    const char* r = q;
    while (!ends_token(r) && r - q < 40) ++r;
    return std::string(q, r);
  }

  void read_vertex() {
    for (int c = 0; c < 3; ++c) {
      skip_blanks();
      if (at_line_end())
        throw Error(where(), fmt::format("vertex has {} coordinate{}; expected x y z", c, c == 1 ? "" : "s"));
      const char* start = *p_ == '+' ? p_ + 1 : p_;  // from_chars rejects a leading '+'
      double value = 0;
      const auto [q, ec] = std::from_chars(start, end_, value);
      if (ec == std::errc::result_out_of_range)
        throw Error(where(), fmt::format("number \"{}\" is out of range for a double", token_at(p_)));
      if (ec != std::errc() || !ends_token(q) || (start != p_ && *start == '-'))
        throw Error(where(), fmt::format("malformed number \"{}\" in a vertex", token_at(p_)));
      if (!std::isfinite(value))
        throw Error(where(), fmt::format("vertex {} has a non-finite coordinate ({} = {})", coordinates_.size() / 3 + 1,
                                         "xyz"[c], value));
      coordinates_.push_back(value);
      p_ = q;
    }
    next_line();  // w, vertex colours
  }

  // [-]digits at q, inlined: std::from_chars<int> costs a third of the face parsing.
  // Returns the end, or nullptr without digits; `overflow` when it does not fit an int.
  const char* parse_index(const char* q, int& value, bool& overflow) const {
    const bool negative = q < end_ && *q == '-';
    if (negative) ++q;
    const char* digits = q;
    std::uint64_t magnitude = 0;  // wraps past 19 digits, caught by the digit count
    for (; q < end_ && static_cast<unsigned>(*q - '0') < 10; ++q) magnitude = magnitude * 10 + (*q - '0');
    if (q == digits) return nullptr;
    overflow = q - digits > 10 || magnitude > static_cast<std::uint64_t>(std::numeric_limits<int>::max());
    value = static_cast<int>(negative ? -static_cast<long long>(magnitude) : static_cast<long long>(magnitude));
    return q;
  }

  // An optional vt or vn index at q (ignored); returns the end, or nullptr when malformed.
  const char* skip_optional_index(const char* q) const {
    if (q == end_ || *q == '/' || ends_token(q)) return q;
    int ignored = 0;
    bool overflow = false;
    return parse_index(q, ignored, overflow);
  }

  void read_face() {
    const int vertex_count = static_cast<int>(coordinates_.size() / 3);
    const size_t first = indices_.size();
    for (;;) {
      skip_blanks();
      if (at_line_end()) break;
      int index = 0;
      bool overflow = false;
      const char* q = parse_index(p_, index, overflow);
      if (overflow) throw Error(where(), fmt::format("face vertex index \"{}\" is out of range", token_at(p_)));
      if (q && q < end_ && *q == '/') {
        q = skip_optional_index(q + 1);                                  // texture coordinate
        if (q && q < end_ && *q == '/') q = skip_optional_index(q + 1);  // normal
      }
      if (!q || !ends_token(q))
        throw Error(where(),
                    fmt::format("malformed face vertex \"{}\"; expected v, v/vt, v//vn or v/vt/vn", token_at(p_)));
      int resolved = 0;
      if (index == 0) {
        throw Error(where(), "face vertex index 0; OBJ indices start at 1 (or -1 for the latest vertex)");
      } else if (index < 0) {
        resolved = vertex_count + index;
        if (resolved < 0)
          throw Error(where(), fmt::format("relative face vertex index {} reaches before the first vertex: "
                                           "only {} vertices are defined above this line",
                                           index, vertex_count));
      } else {
        // Checked once the whole file is read: OBJ lets faces refer to later vertices.
        resolved = index - 1;
        if (resolved > max_index_) {
          max_index_ = resolved;
          max_index_line_ = line_;
        }
      }
      indices_.push_back(resolved);
      p_ = q;
    }
    const int degree = static_cast<int>(indices_.size() - first);
    if (degree < 3)
      throw Error(where(),
                  fmt::format("face has {} {}; a face needs at least 3", degree, degree == 1 ? "vertex" : "vertices"));
    offsets_.push_back(static_cast<int>(indices_.size()));
    next_line();
  }

  const std::string& path_;
  const char* p_;
  const char* end_;
  int line_ = 1;
  std::vector<double> coordinates_;     // x y z per vertex
  std::vector<int> offsets_, indices_;  // as in Polygons
  int max_index_ = -1;
  int max_index_line_ = 0;
};

// ---------------------------------------------------------------------------------------
// PLY and OFF through OpenMesh. Its readers and writers are shared singletons with
// per-call state, so calls are serialised.
struct DoubleTraits : OpenMesh::DefaultTraits {
  using Point = OpenMesh::Vec3d;
};
using OpenMeshPoly = OpenMesh::PolyMesh_ArrayKernelT<DoubleTraits>;
std::mutex& openmesh_mutex() {
  static std::mutex mutex;
  return mutex;
}

struct DeclaredCounts {
  long long vertices = 0;
  long long faces = 0;
};

bool parse_count(std::string_view token, long long& value) {
  const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
  return ec == std::errc() && end == token.data() + token.size() && value >= 0;
}

DeclaredCounts ply_header_counts(const std::string& path, std::string_view text) {
  if (text.substr(0, 3) != "ply") throw Error(path, "not a PLY file: it does not start with \"ply\"");
  DeclaredCounts counts;
  bool has_vertex_element = false;
  size_t pos = 0;
  while (pos < text.size()) {
    size_t end = text.find('\n', pos);
    if (end == std::string_view::npos) end = text.size();
    std::string_view line = text.substr(pos, end - pos);
    pos = end + 1;
    std::vector<std::string_view> tokens;
    for (size_t i = 0; i < line.size();) {
      while (i < line.size() && std::isspace(static_cast<unsigned char>(line[i]))) ++i;
      const size_t start = i;
      while (i < line.size() && !std::isspace(static_cast<unsigned char>(line[i]))) ++i;
      if (i > start) tokens.push_back(line.substr(start, i - start));
    }
    if (tokens.empty()) continue;
    if (tokens[0] == "end_header") {
      if (!has_vertex_element) throw Error(path, "the PLY header declares no \"element vertex\"");
      return counts;
    }
    if (tokens[0] != "element" || tokens.size() < 3) continue;
    long long count = 0;
    if (!parse_count(tokens[2], count))
      throw Error(path, fmt::format("PLY header: malformed count \"{}\" for element {}", tokens[2], tokens[1]));
    if (tokens[1] == "vertex") {
      counts.vertices = count;
      has_vertex_element = true;
    } else if (tokens[1] == "face") {
      counts.faces = count;
    }
  }
  throw Error(path, "the PLY header has no end_header line");
}

DeclaredCounts off_header_counts(const std::string& path, std::string_view text) {
  size_t pos = 0;
  // Tokens of the header, skipping blanks, newlines and # comments.
  auto next_token = [&]() -> std::string_view {
    for (;;) {
      while (pos < text.size() && std::isspace(static_cast<unsigned char>(text[pos]))) ++pos;
      if (pos < text.size() && text[pos] == '#') {
        while (pos < text.size() && text[pos] != '\n') ++pos;
        continue;
      }
      const size_t start = pos;
      while (pos < text.size() && !std::isspace(static_cast<unsigned char>(text[pos]))) ++pos;
      return text.substr(start, pos - start);
    }
  };
  const std::string_view keyword = next_token();
  if (keyword.size() < 3 || keyword.substr(keyword.size() - 3) != "OFF")
    throw Error(path, "not an OFF file: it does not start with \"OFF\"");
  const std::string_view rest_of_line = text.substr(pos, text.find('\n', pos) - pos);
  if (keyword[0] == 'n') {
    next_token();  // nOFF: the dimension
  } else if (rest_of_line.find_first_of("0123456789") != std::string_view::npos) {
    // "OFF 3 1 0" is valid OFF, but OpenMesh then reads no vertices at all.
    throw Error(path, "OpenMesh's OFF reader needs the vertex, face and edge counts on the line after \"OFF\"");
  }
  DeclaredCounts counts;
  const size_t before = pos;
  if (next_token() == "BINARY") {
    // OpenMesh's binary OFF: after the keyword line, #V #F #E as 32-bit little-endian ints.
    const size_t newline = text.find('\n', pos);
    std::int32_t raw[3];
    if (newline == std::string_view::npos || text.size() < newline + 1 + sizeof raw)
      throw Error(path, "binary OFF file ends inside its header");
    std::memcpy(raw, text.data() + newline + 1, sizeof raw);
    counts.vertices = raw[0];
    counts.faces = raw[1];
    return counts;
  }
  pos = before;
  // OpenMesh's OFF reader misreads comments silently (no vertices, or NaN coordinates).
  if (const size_t hash = text.find('#'); hash != std::string_view::npos)
    throw Error(fmt::format("{}:{}", path, 1 + std::count(text.begin(), text.begin() + hash, '\n')),
                "OpenMesh's OFF reader does not accept # comments; remove them or convert the file to OBJ");
  const std::string_view vertices = next_token(), faces = next_token();
  if (!parse_count(vertices, counts.vertices) || !parse_count(faces, counts.faces))
    throw Error(path, fmt::format("OFF header: expected the vertex and face counts, got \"{} {}\"", vertices, faces));
  return counts;
}

Mesh read_with_openmesh(const std::string& path, Format format, std::string_view text) {
  const DeclaredCounts declared = format == Format::ply ? ply_header_counts(path, text) : off_header_counts(path, text);
  // OpenMesh refuses some empty files outright; say what is wrong instead.
  if (declared.vertices == 0) throw Error(path, "the mesh has no vertices");
  if (declared.faces == 0) throw Error(path, "the mesh has no faces (a point cloud is not a mesh)");
  OpenMeshPoly om;
  {
    std::lock_guard<std::mutex> lock(openmesh_mutex());
    OpenMesh::IO::Options options;
    if (!OpenMesh::IO::read_mesh(om, path, options))
      throw Error(path, "OpenMesh could not read the file (it prints its reason on stderr)");
  }
  const long long vertices = static_cast<long long>(om.n_vertices());
  const long long faces = static_cast<long long>(om.n_faces());
  if (vertices > declared.vertices)
    throw Error(path, fmt::format("the header declares {} vertices but OpenMesh loaded {}: OpenMesh duplicates the "
                                  "vertices of faces it cannot add to a manifold mesh (non-manifold edges or "
                                  "vertices); convert the file to OBJ, which is read as written",
                                  declared.vertices, vertices));
  if (vertices < declared.vertices)
    throw Error(path, fmt::format("the header declares {} vertices but OpenMesh loaded only {}: the file is "
                                  "truncated or in a variant OpenMesh does not read; convert it to OBJ",
                                  declared.vertices, vertices));
  if (faces != declared.faces)
    throw Error(path, fmt::format("the header declares {} faces but OpenMesh loaded {}: the mesh has faces "
                                  "OpenMesh could not load (non-manifold, repeating a vertex, with an out-of-range "
                                  "index or fewer than 3 vertices); convert the file to OBJ, which is read as written",
                                  declared.faces, faces));
  Mesh mesh;
  mesh.source = path;
  mesh.vertices.resize(static_cast<Eigen::Index>(vertices), 3);
  for (const auto v : om.vertices()) {
    const auto& p = om.point(v);
    mesh.vertices.row(v.idx()) << p[0], p[1], p[2];
  }
  // OpenMesh keeps faces in insertion order and starts each at its first vertex.
  std::vector<int> polygon;
  for (const auto f : om.faces()) {
    polygon.clear();
    for (const auto v : om.fv_range(f)) polygon.push_back(v.idx());
    mesh.faces.add(polygon.data(), static_cast<int>(polygon.size()));
  }
  return mesh;
}

// ---------------------------------------------------------------------------------------
// Writers. Numbers go through std::to_chars: the shortest text that reads back to the
// same double, so OBJ and OFF round trips lose nothing.
class TextBuilder {
 public:
  explicit TextBuilder(size_t reserve) { text_.reserve(reserve); }
  TextBuilder& operator<<(double x) { return put(x); }
  TextBuilder& operator<<(int x) { return put(x); }
  TextBuilder& operator<<(char c) {
    text_ += c;
    return *this;
  }
  TextBuilder& operator<<(std::string_view s) {
    text_ += s;
    return *this;
  }
  const std::string& text() const { return text_; }

 private:
  template <typename T>
  TextBuilder& put(T x) {
    char buffer[32];
    const auto result = std::to_chars(buffer, buffer + sizeof buffer, x);
    text_.append(buffer, result.ptr);
    return *this;
  }
  std::string text_;
};

std::string obj_text(const Mesh& mesh) {
  const Polygons& faces = mesh.faces;
  TextBuilder out(mesh.vertex_count() * 64 + faces.indices.size() * 8 + faces.size() * 4);
  for (int i = 0; i < mesh.vertex_count(); ++i)
    out << "v " << mesh.vertices(i, 0) << ' ' << mesh.vertices(i, 1) << ' ' << mesh.vertices(i, 2) << '\n';
  for (int f = 0; f < faces.size(); ++f) {
    out << 'f';
    for (int k = 0; k < faces.degree(f); ++k) out << ' ' << faces.begin(f)[k] + 1;
    out << '\n';
  }
  return out.text();
}

std::string off_text(const Mesh& mesh) {
  const Polygons& faces = mesh.faces;
  TextBuilder out(mesh.vertex_count() * 64 + faces.indices.size() * 8 + faces.size() * 4 + 32);
  out << "OFF\n" << mesh.vertex_count() << ' ' << faces.size() << " 0\n";
  for (int i = 0; i < mesh.vertex_count(); ++i)
    out << mesh.vertices(i, 0) << ' ' << mesh.vertices(i, 1) << ' ' << mesh.vertices(i, 2) << '\n';
  for (int f = 0; f < faces.size(); ++f) {
    out << faces.degree(f);
    for (int k = 0; k < faces.degree(f); ++k) out << ' ' << faces.begin(f)[k];
    out << '\n';
  }
  return out.text();
}

void write_ply(const std::string& path, const Mesh& mesh, const MeshWriteOptions& options) {
  OpenMeshPoly om;
  om.reserve(mesh.vertex_count(), mesh.faces.indices.size(), mesh.faces.size());
  for (int i = 0; i < mesh.vertex_count(); ++i)
    om.add_vertex(OpenMeshPoly::Point(mesh.vertices(i, 0), mesh.vertices(i, 1), mesh.vertices(i, 2)));
  std::vector<OpenMeshPoly::VertexHandle> polygon;
  for (int f = 0; f < mesh.faces.size(); ++f) {
    polygon.clear();
    for (int k = 0; k < mesh.faces.degree(f); ++k) polygon.emplace_back(mesh.faces.begin(f)[k]);
    if (!om.add_face(polygon).is_valid())
      throw Error(path, fmt::format("cannot write as PLY: face {} (counting from 0) is non-manifold or repeats a "
                                    "vertex, and OpenMesh cannot store it; write .obj or .off instead",
                                    f));
  }
  OpenMesh::IO::Options flags;
  if (options.binary_ply) flags = OpenMesh::IO::Options(OpenMesh::IO::Options::Binary | OpenMesh::IO::Options::LSB);
  write_file_atomically(path, [&](std::ostream& out) {
    std::lock_guard<std::mutex> lock(openmesh_mutex());
    // 9 significant digits read back to the same float, which is what OpenMesh stores.
    if (!OpenMesh::IO::write_mesh(om, out, ".ply", flags, 9))
      throw Error(path, "OpenMesh could not write the PLY file (it prints its reason on stderr)");
  });
}

}  // namespace

Mesh read_mesh(const std::string& path) {
  const Format format = format_of(path);
  const FileBytes file(path);
  const std::string_view text = file.view();
  Mesh mesh = format == Format::obj ? ObjReader(path, text).read() : read_with_openmesh(path, format, text);
  triangulate(mesh);
  require_valid_mesh(mesh);
  return mesh;
}

void write_mesh(const std::string& path, const Mesh& mesh, const MeshWriteOptions& options) {
  const Format format = format_of(path);
  try {
    require_valid_mesh(mesh);
  } catch (const Error& error) {
    throw Error(path, std::string("cannot write an invalid mesh: ") + error.what());
  }
  if (format == Format::ply) return write_ply(path, mesh, options);
  const std::string text = format == Format::obj ? obj_text(mesh) : off_text(mesh);
  write_file_atomically(path,
                        [&](std::ostream& out) { out.write(text.data(), static_cast<std::streamsize>(text.size())); });
}

}  // namespace retarget
