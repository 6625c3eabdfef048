#include "geometry/ply_reader.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <vector>

#include "core/error.h"
#include "geometry/text_lines.h"

namespace retarget {

namespace {

// PLY's scalar types, with both spellings (the 1994 names and the sized ones).
enum class Type { int8, uint8, int16, uint16, int32, uint32, float32, float64 };

struct TypeInfo {
  Type type;
  std::string_view name, sized_name;
  int size;
  bool integer;
  long long min, max;  // integers only
};

constexpr TypeInfo kTypes[] = {
    {Type::int8, "char", "int8", 1, true, INT8_MIN, INT8_MAX},
    {Type::uint8, "uchar", "uint8", 1, true, 0, UINT8_MAX},
    {Type::int16, "short", "int16", 2, true, INT16_MIN, INT16_MAX},
    {Type::uint16, "ushort", "uint16", 2, true, 0, UINT16_MAX},
    {Type::int32, "int", "int32", 4, true, INT32_MIN, INT32_MAX},
    {Type::uint32, "uint", "uint32", 4, true, 0, UINT32_MAX},
    {Type::float32, "float", "float32", 4, false, 0, 0},
    {Type::float64, "double", "float64", 8, false, 0, 0},
};

const TypeInfo& info(Type type) { return kTypes[static_cast<int>(type)]; }

bool type_named(std::string_view name, Type& type) {
  for (const TypeInfo& t : kTypes)
    if (name == t.name || name == t.sized_name) {
      type = t.type;
      return true;
    }
  return false;
}

struct Property {
  std::string name;
  bool list = false;
  Type count_type = Type::uint8;  // lists only
  Type type = Type::float32;      // the value, or a list's items
};

struct Element {
  std::string name;
  long long count = 0;
  int line = 0;  // of its header line
  std::vector<Property> properties;
};

enum class Encoding { ascii, little_endian, big_endian };

struct Header {
  Encoding encoding = Encoding::ascii;
  std::vector<Element> elements;
  size_t body = 0;  // byte offset of the first byte after end_header's newline
  int body_line = 0;
  int vertex = -1, face = -1;  // elements
  int axis[3] = {-1, -1, -1};  // x, y, z properties of the vertex element
  int indices = -1;            // the face element's index list
};

std::string property_names(const Element& element) {
  std::string names;
  for (const Property& p : element.properties) names += (names.empty() ? "" : " ") + p.name + (p.list ? "[]" : "");
  return names;
}

class PlyReader {
 public:
  PlyReader(const std::string& path, std::string_view bytes) : path_(path), bytes_(bytes) {}

  Mesh read() {
    read_header();
    const Element& vertex = header_.elements[header_.vertex];
    const long long faces = header_.face >= 0 ? header_.elements[header_.face].count : 0;
    if (vertex.count == 0) throw Error(path_, "the mesh has no vertices");
    if (faces == 0) throw Error(path_, "the mesh has no faces (a point cloud is not a mesh)");
    check_sizes();
    vertex_count_ = static_cast<int>(vertex.count);
    coordinates_.resize(static_cast<size_t>(vertex.count) * 3);
    offsets_.reserve(static_cast<size_t>(faces) + 1);
    offsets_.push_back(0);
    if (header_.encoding == Encoding::ascii)
      read_ascii();
    else
      read_binary();
    Mesh mesh;
    mesh.source = path_;
    mesh.vertices = Eigen::Map<const Positions>(coordinates_.data(), vertex_count_, 3);
    mesh.faces.offsets = std::move(offsets_);
    mesh.faces.indices = std::move(indices_);
    return mesh;
  }

 private:
  // ---- header ----------------------------------------------------------------------------
  [[noreturn]] void header_error(int line, const std::string& what) const {
    throw Error(fmt::format("{}:{}", path_, line), what);
  }

  void read_header() {
    size_t pos = 0;
    int line = 0;
    bool has_format = false;
    std::vector<std::string_view> tokens;
    for (;;) {
      if (pos >= bytes_.size()) {
        if (line == 0) throw Error(path_, "not a PLY file: it does not start with \"ply\"");
        throw Error(path_, "the PLY header has no end_header line");
      }
      const void* newline = std::memchr(bytes_.data() + pos, '\n', bytes_.size() - pos);
      const size_t end = newline ? static_cast<const char*>(newline) - bytes_.data() : bytes_.size();
      const std::string_view text = bytes_.substr(pos, end - pos);
      pos = end + 1;
      ++line;
      tokens.clear();
      for (size_t i = 0; i < text.size();) {
        while (i < text.size() && std::isspace(static_cast<unsigned char>(text[i]))) ++i;
        const size_t first = i;
        while (i < text.size() && !std::isspace(static_cast<unsigned char>(text[i]))) ++i;
        if (i > first) tokens.push_back(text.substr(first, i - first));
      }
      if (line == 1) {
        if (tokens.size() != 1 || tokens[0] != "ply")
          throw Error(path_, "not a PLY file: it does not start with \"ply\"");
        continue;
      }
      if (tokens.empty()) continue;
      const std::string_view keyword = tokens[0];
      if (keyword == "comment" || keyword == "obj_info") continue;
      if (keyword == "end_header") {
        if (!has_format) header_error(line, "the PLY header has no format line before end_header");
        header_.body = std::min(pos, bytes_.size());
        header_.body_line = line + 1;
        break;
      }
      if (keyword == "format") {
        if (has_format) header_error(line, "a second format line");
        if (tokens.size() != 3)
          header_error(line, "expected \"format ascii|binary_little_endian|binary_big_endian 1.0\"");
        if (tokens[1] == "ascii")
          header_.encoding = Encoding::ascii;
        else if (tokens[1] == "binary_little_endian")
          header_.encoding = Encoding::little_endian;
        else if (tokens[1] == "binary_big_endian")
          header_.encoding = Encoding::big_endian;
        else
          header_error(line, fmt::format("unknown PLY format {}; expected ascii, binary_little_endian or "
                                         "binary_big_endian",
                                         retarget::quoted(tokens[1])));
        if (tokens[2] != "1.0" && tokens[2] != "1")
          header_error(line, fmt::format("unsupported PLY version {}; expected 1.0", retarget::quoted(tokens[2])));
        has_format = true;
      } else if (keyword == "element") {
        if (tokens.size() != 3) header_error(line, "expected \"element NAME COUNT\"");
        Element element;
        element.name = std::string(tokens[1]);
        element.line = line;
        const NumberStatus status = parse_integer(tokens[2], 0, std::numeric_limits<int>::max(), element.count);
        if (status != NumberStatus::ok)
          header_error(line, fmt::format("element {}: count {} is not an integer in [0, {}]", element.name,
                                         retarget::quoted(tokens[2]), std::numeric_limits<int>::max()));
        for (const Element& other : header_.elements)
          if (other.name == element.name)
            header_error(line, fmt::format("a second element named {} (the first is on line {})",
                                           retarget::quoted(element.name), other.line));
        header_.elements.push_back(std::move(element));
      } else if (keyword == "property") {
        if (header_.elements.empty()) header_error(line, "a property before any element");
        Property property;
        if (tokens.size() >= 2 && tokens[1] == "list") {
          if (tokens.size() != 5) header_error(line, "expected \"property list COUNT_TYPE ITEM_TYPE NAME\"");
          if (!type_named(tokens[2], property.count_type) || !info(property.count_type).integer)
            header_error(line, fmt::format("list count type {} is not an integer type (uchar, ushort, uint, ...)",
                                           retarget::quoted(tokens[2])));
          if (!type_named(tokens[3], property.type))
            header_error(line, fmt::format("unknown property type {}", retarget::quoted(tokens[3])));
          property.list = true;
          property.name = std::string(tokens[4]);
        } else {
          if (tokens.size() != 3) header_error(line, "expected \"property TYPE NAME\"");
          if (!type_named(tokens[1], property.type))
            header_error(line, fmt::format("unknown property type {}; expected char, uchar, short, ushort, int, "
                                           "uint, float, double or their sized names (int8, ..., float64)",
                                           retarget::quoted(tokens[1])));
          property.name = std::string(tokens[2]);
        }
        Element& element = header_.elements.back();
        for (const Property& other : element.properties)
          if (other.name == property.name)
            header_error(line, fmt::format("element {} has a second property named {}", element.name,
                                           retarget::quoted(property.name)));
        element.properties.push_back(std::move(property));
      } else {
        header_error(line, fmt::format("unknown PLY header keyword {}", retarget::quoted(keyword)));
      }
    }

    for (int e = 0; e < static_cast<int>(header_.elements.size()); ++e) {
      const Element& element = header_.elements[e];
      if (element.name == "vertex") header_.vertex = e;
      if (element.name == "face") header_.face = e;
    }
    if (header_.vertex < 0) throw Error(path_, "the PLY header declares no \"element vertex\"");
    const Element& vertex = header_.elements[header_.vertex];
    for (int a = 0; a < 3; ++a) {
      const char* name = a == 0 ? "x" : a == 1 ? "y" : "z";
      for (int k = 0; k < static_cast<int>(vertex.properties.size()); ++k)
        if (vertex.properties[k].name == name) header_.axis[a] = k;
      if (header_.axis[a] < 0)
        header_error(vertex.line, fmt::format("the vertex element has no property {} (properties: {})", name,
                                              property_names(vertex)));
      if (vertex.properties[header_.axis[a]].list)
        header_error(vertex.line, fmt::format("the vertex property {} is a list; expected a number", name));
    }
    if (header_.face >= 0) {
      const Element& face = header_.elements[header_.face];
      for (int k = 0; k < static_cast<int>(face.properties.size()); ++k)
        if (face.properties[k].name == "vertex_indices" || face.properties[k].name == "vertex_index")
          header_.indices = k;
      if (header_.indices < 0 || !face.properties[header_.indices].list ||
          !info(face.properties[header_.indices].type).integer)
        header_error(face.line, fmt::format("the face element has no integer list vertex_indices or vertex_index "
                                            "(properties: {})",
                                            property_names(face)));
    }
  }

  // Counts against the bytes after the header, before anything is allocated: an ASCII element
  // takes a line of at least one character, a binary one its fixed-size values and list counts.
  void check_sizes() const {
    const unsigned long long available = bytes_.size() - header_.body;
    // ASCII: a character and a newline per element, the file's last line may lack its newline.
    unsigned long long left = header_.encoding == Encoding::ascii ? available + 1 : available;
    for (const Element& element : header_.elements) {
      if (element.properties.empty()) continue;
      unsigned long long least = 0;
      if (header_.encoding == Encoding::ascii) {
        least = 2;
      } else {
        for (const Property& p : element.properties) least += info(p.list ? p.count_type : p.type).size;
      }
      const unsigned long long count = static_cast<unsigned long long>(element.count);
      if (count > left / least)
        header_error(element.line, fmt::format("the header declares {} {} elements of at least {} byte{} each, "
                                               "more than the {} bytes after the header hold: the file is "
                                               "truncated or its header is wrong",
                                               element.count, element.name, least, least == 1 ? "" : "s", available));
      left -= count * least;
    }
  }

  // ---- ASCII body --------------------------------------------------------------------------
  void read_ascii() {
    TextLines lines(bytes_, header_.body, header_.body_line, '\0');
    std::vector<std::string_view> tokens;
    for (int e = 0; e < static_cast<int>(header_.elements.size()); ++e) {
      const Element& element = header_.elements[e];
      if (element.properties.empty()) continue;
      for (long long i = 0; i < element.count; ++i) {
        if (!lines.next(tokens))
          throw Error(fmt::format("{}:{}", path_, lines.line()),
                      fmt::format("the file ends after {} of the {} {} elements the header declares", i, element.count,
                                  element.name));
        const std::string where = fmt::format("{}:{}", path_, lines.line());
        const auto too_few = [&] {
          throw Error(where,
                      fmt::format("{} {} has {} value{} on its line, too few for its properties ({})", element.name, i,
                                  tokens.size(), tokens.size() == 1 ? "" : "s", property_names(element)));
        };
        size_t t = 0;
        for (int k = 0; k < static_cast<int>(element.properties.size()); ++k) {
          const Property& property = element.properties[k];
          if (!property.list) {
            if (t >= tokens.size()) too_few();
            const double value = ascii_value(tokens[t++], property.type, property.name, where);
            if (e == header_.vertex) store_coordinate(static_cast<int>(i), k, value, where);
            continue;
          }
          if (t >= tokens.size()) too_few();
          const long long n =
              static_cast<long long>(ascii_value(tokens[t++], property.count_type, property.name, where));
          if (n < 0)
            throw Error(where, fmt::format("{} {}: negative list length {} for {}", element.name, i, n, property.name));
          if (static_cast<unsigned long long>(n) > tokens.size() - t)
            throw Error(where, fmt::format("{} {}: the list {} says {} values but the line has only {} after it",
                                           element.name, i, property.name, n, tokens.size() - t));
          const bool face_indices = e == header_.face && k == header_.indices;
          if (face_indices) begin_face(static_cast<int>(i), n, where);
          for (long long j = 0; j < n; ++j) {
            const double value = ascii_value(tokens[t++], property.type, property.name, where);
            if (face_indices) add_index(static_cast<int>(i), value, where);
          }
          if (face_indices) offsets_.push_back(static_cast<int>(indices_.size()));
        }
        if (t != tokens.size())
          throw Error(where, fmt::format("{} {} has {} values on its line, {} more than its properties ({}) take; "
                                         "is a line missing or out of place?",
                                         element.name, i, tokens.size(), tokens.size() - t, property_names(element)));
      }
    }
    if (lines.next(tokens))
      throw Error(fmt::format("{}:{}", path_, lines.line()),
                  "data after the last element the header declares: the header's counts are wrong");
  }

  double ascii_value(std::string_view token, Type type, const std::string& name, const std::string& where) const {
    const TypeInfo& t = info(type);
    if (t.integer) {
      long long value = 0;
      const NumberStatus status = parse_integer(token, t.min, t.max, value);
      if (status == NumberStatus::out_of_range)
        throw Error(where, fmt::format("{} {} is out of range for its type {}", name, retarget::quoted(token), t.name));
      if (status != NumberStatus::ok)
        throw Error(where, fmt::format("{}: malformed integer {} (type {})", name, retarget::quoted(token), t.name));
      return static_cast<double>(value);
    }
    double value = 0;
    NumberStatus status = parse_real(token, value);
    if (status == NumberStatus::ok && type == Type::float32 && std::isfinite(value) && std::fabs(value) > FLT_MAX)
      status = NumberStatus::out_of_range;
    if (status == NumberStatus::out_of_range)
      throw Error(where,
                  fmt::format("{}: number {} is out of range for its type {}", name, retarget::quoted(token), t.name));
    if (status != NumberStatus::ok)
      throw Error(where, fmt::format("{}: malformed number {}", name, retarget::quoted(token)));
    return value;
  }

  // ---- binary body -------------------------------------------------------------------------
  void read_binary() {
    const unsigned char* const begin = reinterpret_cast<const unsigned char*>(bytes_.data());
    const unsigned char* p = begin + header_.body;
    const unsigned char* const end = begin + bytes_.size();
    for (int e = 0; e < static_cast<int>(header_.elements.size()); ++e) {
      const Element& element = header_.elements[e];
      if (element.properties.empty()) continue;
      for (long long i = 0; i < element.count; ++i) {
        const std::string where = path_;
        const auto suffix = [&] { return fmt::format(" (byte {} of the file)", p - begin); };
        const auto need = [&](unsigned long long bytes) {
          if (bytes > static_cast<unsigned long long>(end - p))
            throw Error(where, fmt::format("the file ends inside {} {} of {}: it is truncated{}", element.name, i,
                                           element.count, suffix()));
        };
        for (int k = 0; k < static_cast<int>(element.properties.size()); ++k) {
          const Property& property = element.properties[k];
          if (!property.list) {
            need(info(property.type).size);
            const double value = binary_value(p, property.type);
            if (e == header_.vertex) store_coordinate(static_cast<int>(i), k, value, where, suffix());
            p += info(property.type).size;
            continue;
          }
          need(info(property.count_type).size);
          const double count = binary_value(p, property.count_type);
          if (count < 0)
            throw Error(where, fmt::format("{} {}: negative list length {} for {}{}", element.name, i,
                                           static_cast<long long>(count), property.name, suffix()));
          p += info(property.count_type).size;
          const unsigned long long n = static_cast<unsigned long long>(count);
          const int size = info(property.type).size;
          if (n > static_cast<unsigned long long>(end - p) / size)
            throw Error(where, fmt::format("{} {}: the list {} says {} values but only {} bytes are left: the file "
                                           "is truncated or its header is wrong{}",
                                           element.name, i, property.name, n, end - p, suffix()));
          const bool face_indices = e == header_.face && k == header_.indices;
          if (face_indices) {
            begin_face(static_cast<int>(i), static_cast<long long>(n), where, suffix());
            for (unsigned long long j = 0; j < n; ++j)
              add_index(static_cast<int>(i), binary_value(p + j * size, property.type), where, suffix());
            offsets_.push_back(static_cast<int>(indices_.size()));
          }
          p += n * size;
        }
      }
    }
    if (p != end)
      throw Error(path_, fmt::format("{} bytes after the last element the header declares (byte {} of the file): "
                                     "the header's counts or types are wrong",
                                     end - p, p - begin));
  }

  double binary_value(const unsigned char* p, Type type) const {
    const int size = info(type).size;
    unsigned char raw[8];
    std::memcpy(raw, p, size);
    const bool swap = header_.encoding == Encoding::big_endian;  // the host is little-endian
    if (swap) std::reverse(raw, raw + size);
    const auto as = [&raw](auto value) {
      std::memcpy(&value, raw, sizeof value);
      return static_cast<double>(value);
    };
    switch (type) {
      case Type::int8:
        return as(int8_t{});
      case Type::uint8:
        return as(uint8_t{});
      case Type::int16:
        return as(int16_t{});
      case Type::uint16:
        return as(uint16_t{});
      case Type::int32:
        return as(int32_t{});
      case Type::uint32:
        return as(uint32_t{});
      case Type::float32:
        return as(float{});
      case Type::float64:
        return as(double{});
    }
    return 0;
  }

  // ---- what both encodings share -----------------------------------------------------------
  void store_coordinate(int vertex, int property, double value, const std::string& where,
                        const std::string& suffix = "") {
    for (int a = 0; a < 3; ++a) {
      if (header_.axis[a] != property) continue;
      if (!std::isfinite(value))
        throw Error(where,
                    fmt::format("vertex {} has a non-finite coordinate ({} = {}){}", vertex, "xyz"[a], value, suffix));
      coordinates_[static_cast<size_t>(vertex) * 3 + a] = value;
    }
  }

  void begin_face(int face, long long degree, const std::string& where, const std::string& suffix = "") const {
    if (degree < 3)
      throw Error(where, fmt::format("face {} has {} {}; a face needs at least 3{}", face, degree,
                                     degree == 1 ? "vertex" : "vertices", suffix));
  }

  void add_index(int face, double index, const std::string& where, const std::string& suffix = "") {
    if (!(index >= 0 && index < vertex_count_))
      throw Error(where, fmt::format("face {}: vertex index {} is out of range: the file has {} vertices{}", face,
                                     static_cast<long long>(index), vertex_count_, suffix));
    indices_.push_back(static_cast<int>(index));
  }

  const std::string& path_;
  std::string_view bytes_;
  Header header_;
  int vertex_count_ = 0;
  std::vector<double> coordinates_;  // x y z per vertex
  std::vector<int> offsets_, indices_;
};

}  // namespace

Mesh read_ply(const std::string& path, std::string_view bytes) { return PlyReader(path, bytes).read(); }

}  // namespace retarget
