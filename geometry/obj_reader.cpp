#include "geometry/obj_reader.h"

#include <fmt/format.h>
#include <omp.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <optional>
#include <utility>
#include <vector>

#include "core/error.h"
#include "core/parse_double.h"
#include "core/text_bytes.h"

namespace retarget {

namespace {

bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

// What a reader collects, kept by the calling thread from one file to the next (one set per
// chunk): a stream of frames is read into the same pages instead of fresh ones (in a VM the page faults of new buffers
// cost three times the parsing: 4.7 against 1.4 ms for an 11k-vertex frame). Past kKeptBytes of capacity the buffers
// are released after the read, so one huge file does not pin its memory.
struct ObjBuffers {
  std::vector<double> coordinates;    // x y z per vertex
  std::vector<int> offsets, indices;  // as in Polygons

  void clear() {
    coordinates.clear();
    offsets.clear();
    indices.clear();
  }
  void release_if_large() {
    constexpr size_t kKeptBytes = size_t{64} << 20;
    if (coordinates.capacity() * sizeof(double) + (offsets.capacity() + indices.capacity()) * sizeof(int) > kKeptBytes)
      *this = ObjBuffers();
  }
};

// The calling thread's buffers: one set per chunk of a file (a single piece uses the first).
std::vector<ObjBuffers>& thread_buffers(size_t sets) {
  thread_local std::vector<ObjBuffers> buffers;
  if (buffers.size() < sets) buffers.resize(sets);
  return buffers;
}

// OBJ: one pass over the file's bytes, numbers parsed in place (parse_double for
// coordinates, correctly rounded); no per-line strings and no iostreams, which is what
// makes it an order of magnitude faster than OpenMesh's reader.
class ObjReader {
 public:
  // Collects into `buffers` (cleared first; one reader on them at a time).
  ObjReader(const std::string& path, std::string_view text, ObjBuffers& buffers)
      : path_(path),
        p_(text.data()),
        end_(text.data() + text.size()),
        buffers_(buffers),
        coordinates_(buffers.coordinates),
        offsets_(buffers.offsets),
        indices_(buffers.indices) {
    buffers_.clear();
  }
  ~ObjReader() { buffers_.release_if_large(); }
  ObjReader(const ObjReader&) = delete;
  ObjReader& operator=(const ObjReader&) = delete;

  // A chunk of the file, from a line's start to a line's end (`file_start`: the file's first).
  // Its line numbers count from the chunk's start, so whatever it would report makes the caller
  // read the whole file (NeedsWholeFile and Error alike). parse() throws NeedsWholeFile at a
  // negative index (it counts back over vertices of the chunks before) and at bytes that are
  // not text.
  ObjReader(const std::string& path, std::string_view chunk, ObjBuffers& buffers, bool file_start)
      : ObjReader(path, chunk, buffers) {
    chunk_ = true;
    file_start_ = file_start;
  }

  struct NeedsWholeFile {};

  Mesh read() {
    parse();
    return mesh();
  }

  // The lines' vertices and faces, appended to the reader's buffers (nothing is checked across lines).
  void parse() {
    // Upper bounds ("v 0 0 0\n" is 8 bytes, a face index at least 2), so the vectors do not
    // reallocate; untouched capacity is never paged in, and the mesh gets exact-size copies.
    // Capped so a huge file does not ask for gigabytes up front.
    const size_t bytes = static_cast<size_t>(end_ - p_), cap = size_t{1} << 23;
    if (chunk_ && first_non_text_byte(std::string_view(p_, bytes), true) != std::string_view::npos)
      throw NeedsWholeFile{};
    coordinates_.reserve(std::min(3 * (bytes / 8 + 1), cap));
    indices_.reserve(std::min(bytes / 2 + 1, cap));
    offsets_.reserve(std::min(bytes / 6 + 2, cap));
    offsets_.push_back(0);
    // A UTF-8 byte order mark would otherwise hide a first "v" line and shift every index.
    if (file_start_ && end_ - p_ >= 3 && std::memcmp(p_, "\xEF\xBB\xBF", 3) == 0) p_ += 3;
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
  }

  // The mesh parse() found, once every face index is checked against the vertices.
  Mesh mesh() const {
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
      const char* start = *p_ == '+' ? p_ + 1 : p_;  // from_chars (and parse_double) reject a leading '+'
      double value = 0;
      const auto [q, ec] = parse_double(start, end_, value);
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
        if (chunk_) throw NeedsWholeFile{};
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
  ObjBuffers& buffers_;
  std::vector<double>& coordinates_;     // x y z per vertex
  std::vector<int>&offsets_, &indices_;  // as in Polygons
  int max_index_ = -1;
  int max_index_line_ = 0;
  bool chunk_ = false, file_start_ = true;

  friend std::optional<Mesh> read_obj_in_chunks(const std::string& path, std::string_view text, int chunks);
};

// Where `text` splits into up to `chunks` runs of whole lines of about equal size: each cut is
// just after a newline that does not end a continued line (a backslash and blanks before it).
std::vector<size_t> chunk_cuts(std::string_view text, int chunks) {
  std::vector<size_t> cuts{0};
  for (int i = 1; i < chunks; ++i) {
    size_t at = std::max(cuts.back(), text.size() * static_cast<size_t>(i) / static_cast<size_t>(chunks));
    for (bool continued = true; continued && at < text.size();) {
      const size_t newline = std::min(text.find('\n', at), text.size() - 1);
      size_t last = newline;
      while (last > 0 && is_blank(text[last - 1])) --last;
      at = newline + 1;
      continued = last > 0 && text[last - 1] == '\\';
    }
    if (at >= text.size()) break;
    cuts.push_back(at);
  }
  cuts.push_back(text.size());
  return cuts;
}

constexpr size_t kChunkBytes = size_t{128} << 10;  // smaller files, or smaller shares, are read whole

// Each chunk on an OpenMP thread of its own (its text checked there too), then joined in order.
// nullopt when a chunk cannot be read alone (a negative index) or finds anything wrong, or a
// face's index lies past the vertices: the caller reads the whole file as one piece, so that
// results and messages (with their line numbers) are the one-piece reader's.
std::optional<Mesh> read_obj_in_chunks(const std::string& path, std::string_view text, int chunks) {
  const std::vector<size_t> cuts = chunk_cuts(text, chunks);
  const int n = static_cast<int>(cuts.size()) - 1;
  std::vector<ObjBuffers>& buffers = thread_buffers(static_cast<size_t>(n));
  std::vector<std::optional<ObjReader>> readers(n);
  bool whole_file = false;
#pragma omp parallel for num_threads(n) schedule(static, 1) reduction(|| : whole_file)
  for (int c = 0; c < n; ++c) {
    try {
      readers[c].emplace(path, text.substr(cuts[c], cuts[c + 1] - cuts[c]), buffers[c], c == 0);
      readers[c]->parse();
    } catch (...) {  // ObjReader::NeedsWholeFile, or an error the one-piece reader names in order
      whole_file = true;
    }
  }
  if (whole_file) return std::nullopt;
  ObjReader& all = *readers[0];
  for (int c = 1; c < n; ++c) {
    const ObjReader& chunk = *readers[c];
    const int base = static_cast<int>(all.indices_.size());
    all.coordinates_.insert(all.coordinates_.end(), chunk.coordinates_.begin(), chunk.coordinates_.end());
    for (size_t f = 1; f < chunk.offsets_.size(); ++f) all.offsets_.push_back(base + chunk.offsets_[f]);
    all.indices_.insert(all.indices_.end(), chunk.indices_.begin(), chunk.indices_.end());
    all.max_index_ = std::max(all.max_index_, chunk.max_index_);
  }
  if (all.max_index_ >= static_cast<int>(all.coordinates_.size() / 3)) return std::nullopt;
  return all.mesh();
}

}  // namespace

Mesh read_obj(const std::string& path, std::string_view text) {
  const int chunks =
      omp_in_parallel() ? 1 : std::min<int>(omp_get_max_threads(), static_cast<int>(text.size() / kChunkBytes));
  if (chunks > 1)
    if (std::optional<Mesh> mesh = read_obj_in_chunks(path, text, chunks)) return std::move(*mesh);
  // Control bytes say "binary file" (bytes 0x80 and up may be a Latin-1 comment).
  require_text(text, path, "an OBJ file is text", true);
  return ObjReader(path, text, thread_buffers(1).front()).read();
}

}  // namespace retarget
