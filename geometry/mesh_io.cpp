// OpenMesh default-constructs its points uninitialised on purpose (PropertyT::push_back);
// GCC 12 flags that inside the standard library headers, so the warning is off for this file.
#if defined(__GNUC__) && !defined(__clang__)  // clang has no such warning (the fuzzing build)
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif

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
#include <memory>
#include <mutex>
#include <string_view>
#include <vector>

#include "core/atomic_file.h"
#include "core/error.h"
#include "geometry/mesh_validation.h"
#include "geometry/obj_reader.h"
#include "geometry/off_reader.h"
#include "geometry/ply_reader.h"

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

// The bytes of the files a thread reads, in memory it keeps from one file to the next (files up
// to kKeptBytes): a stream of frames is read into the same pages. Reading into fresh memory
// page-faults on every page, and mapping the file (MAP_POPULATE) costs a TLB shootdown on every
// core at each munmap; in a VM both cost more than the copy (an 11k-vertex frame read on each of
// two threads at once: 1.7-1.9 ms mapped, 1.1-1.3 kept;
// docs/experiments/2026-11-29-frames-read-into-kept-memory.md).
constexpr size_t kKeptBytes = size_t{64} << 20;
struct KeptBytes {
  std::unique_ptr<char[]> data;
  size_t capacity = 0;
};
KeptBytes& kept_bytes() {
  thread_local KeptBytes bytes;
  return bytes;
}

// A whole file's bytes. Regular files up to kKeptBytes are read into the thread's kept memory
// (one reader per thread at a time), larger ones are mapped (MAP_POPULATE: no zero-filled
// buffer), and anything else (pipes, special files, or mmap refused) is read into a string.
// Files are replaced by rename (write_file_atomically), so a file does not change under the
// parser.
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
    if (S_ISREG(info.st_mode) && info.st_size > 0 && static_cast<size_t>(info.st_size) <= kKeptBytes &&
        read_kept(path, fd, static_cast<size_t>(info.st_size)))
      return;
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

  // The file's `size` bytes into the thread's kept memory; false (nothing kept) when the file
  // turns out to be shorter or longer than its size said.
  bool read_kept(const std::string& path, int fd, size_t size) {
    KeptBytes& kept = kept_bytes();
    if (kept.capacity < size + 1) {
      kept.data.reset(new char[size + 1]);
      kept.capacity = size + 1;
    }
    size_t got = 0;
    while (got <= size) {  // one byte past the size: a file that grew is read another way
      const ssize_t n = ::read(fd, kept.data.get() + got, size + 1 - got);
      if (n == 0) break;
      if (n < 0) {
        if (errno == EINTR) continue;
        throw Error(path, std::string("cannot read the mesh file: ") + std::strerror(errno));
      }
      got += static_cast<size_t>(n);
    }
    if (got != size) {
      if (::lseek(fd, 0, SEEK_SET) != 0)
        throw Error(path, std::string("cannot read the mesh file: ") + std::strerror(errno));
      return false;
    }
    view_ = std::string_view(kept.data.get(), size);
    return true;
  }

  void* map_ = nullptr;
  size_t map_size_ = 0;
  std::string buffer_;
  std::string_view view_;
};

// ---------------------------------------------------------------------------------------
// PLY writing through OpenMesh. Its writers are shared singletons with per-call state, so
// calls are serialised.
struct DoubleTraits : OpenMesh::DefaultTraits {
  using Point = OpenMesh::Vec3d;
};
using OpenMeshPoly = OpenMesh::PolyMesh_ArrayKernelT<DoubleTraits>;
std::mutex& openmesh_mutex() {
  static std::mutex mutex;
  return mutex;
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
  // A path that does not exist says so, whatever its extension (a mistyped folder has none).
  struct stat info {};
  if (::stat(path.c_str(), &info) != 0 && errno == ENOENT)
    throw Error(path, "cannot open the mesh file: No such file or directory (no file or folder exists at this path)");
  const Format format = format_of(path);
  const FileBytes file(path);
  const std::string_view text = file.view();
  Mesh mesh = format == Format::obj   ? read_obj(path, text)
              : format == Format::ply ? read_ply(path, text)
                                      : read_off(path, text);
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
