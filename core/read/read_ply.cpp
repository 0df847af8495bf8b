// read_ply.cpp — Stanford PLY 1.0, ASCII or binary of either byte order: the vertex element's x,
// y and z, the face element's index list (vertex_indices or vertex_index) or the triangle strips
// of a tristrips element; every other property and element is skipped.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>

#include "core/read/format_reader.h"

namespace vdb_shell::read_detail {
namespace {

const char* const kFix = "re-export the mesh (a complete PLY file)";

enum class Type { kInt8, kUint8, kInt16, kUint16, kInt32, kUint32, kFloat32, kFloat64 };

bool type_of(std::string_view word, Type& type) {
  static const struct {
    const char* names[2];
    Type type;
  } kTypes[] = {{{"char", "int8"}, Type::kInt8},        {{"uchar", "uint8"}, Type::kUint8},
                {{"short", "int16"}, Type::kInt16},     {{"ushort", "uint16"}, Type::kUint16},
                {{"int", "int32"}, Type::kInt32},       {{"uint", "uint32"}, Type::kUint32},
                {{"float", "float32"}, Type::kFloat32}, {{"double", "float64"}, Type::kFloat64}};
  for (const auto& t : kTypes)
    if (word == t.names[0] || word == t.names[1]) {
      type = t.type;
      return true;
    }
  return false;
}

std::size_t size_of(Type t) {
  switch (t) {
    case Type::kInt8:
    case Type::kUint8:
      return 1;
    case Type::kInt16:
    case Type::kUint16:
      return 2;
    case Type::kInt32:
    case Type::kUint32:
    case Type::kFloat32:
      return 4;
    case Type::kFloat64:
      return 8;
  }
  return 8;
}

struct Property {
  std::string name;
  Type type = Type::kFloat32;
  bool list = false;
  Type count_type = Type::kUint8;  ///< lists only
};

struct Element {
  std::string name;
  long long count = 0;
  std::vector<Property> properties;
};

struct Header {
  enum class Format { kAscii, kLittle, kBig } format = Format::kAscii;
  std::vector<Element> elements;
  std::size_t body = 0;       ///< the byte after end_header's line
  std::size_t body_line = 1;  ///< its line number
  long long count(const std::string& name) const {
    for (const Element& e : elements)
      if (e.name == name) return e.count;
    return 0;
  }
};

/// The header, checked: "ply", a known format, elements with counts >= 0, properties of known
/// types, end_header, and element counts the body's bytes can hold (in binary the exact smallest
/// size of an element; in ASCII 2 bytes a value).
Header read_header(std::string_view bytes, const std::string& name) {
  Header header;
  Lines lines(bytes);
  const auto fail_at = [&](const std::string& what) {
    fail(name, "PLY header line " + std::to_string(lines.line_no()) + ": " + what, kFix);
  };
  bool has_format = false;
  for (std::string_view line; lines.next(line);) {
    const std::vector<std::string_view> w = words(line, '\0');
    if (lines.line_no() == 1) {
      if (w.size() != 1 || w[0] != "ply") fail_at("not 'ply'");
      continue;
    }
    if (w.empty() || w[0] == "comment" || w[0] == "obj_info") continue;
    if (w[0] == "end_header") {
      if (!has_format) fail_at("no format line before end_header");
      header.body = lines.offset();
      header.body_line = lines.line_no() + 1;
      const bool ascii = header.format == Header::Format::kAscii;
      long double least = 0;
      for (const Element& e : header.elements) {
        std::size_t item = 0;
        for (const Property& p : e.properties)
          item += ascii ? 2 : size_of(p.list ? p.count_type : p.type);
        least += static_cast<long double>(e.count) * item;
      }
      if (least > static_cast<long double>(bytes.size() - header.body) + 1)
        fail_at("its element counts are more than the file's " + std::to_string(bytes.size()) +
                " bytes can hold");
      return header;
    }
    if (w[0] == "format") {
      if (w.size() != 3 || w[2] != "1.0")
        fail_at("unknown format " + quoted(line, 60) + " (PLY 1.0 is read)");
      if (w[1] == "ascii")
        header.format = Header::Format::kAscii;
      else if (w[1] == "binary_little_endian")
        header.format = Header::Format::kLittle;
      else if (w[1] == "binary_big_endian")
        header.format = Header::Format::kBig;
      else
        fail_at("unknown format " + quoted(line, 60));
      has_format = true;
    } else if (w[0] == "element") {
      long long count = -1;
      if (w.size() != 3 || !parse_integer(w[2], count) || count < 0)
        fail_at("an element needs a name and a count >= 0: " + quoted(line, 60));
      header.elements.push_back({std::string(w[1]), count, {}});
    } else if (w[0] == "property") {
      Property p;
      const bool scalar = w.size() == 3 && type_of(w[1], p.type);
      p.list = w.size() == 5 && w[1] == "list" && type_of(w[2], p.count_type) &&
               type_of(w[3], p.type) && p.count_type != Type::kFloat32 &&
               p.count_type != Type::kFloat64;
      if (header.elements.empty() || !(scalar || p.list))
        fail_at("not a property of a known type: " + quoted(line, 60));
      p.name = std::string(w.back());
      header.elements.back().properties.push_back(p);
    } else {
      fail_at("unknown keyword " + quoted(w[0]));
    }
  }
  fail_at("the file ends before end_header");
  return header;
}

/// An ASCII value `v` is one of type `t` (integers whole and in range).
bool fits(Type t, double v) {
  const auto whole_in = [&](double lo, double hi) {
    return v == std::floor(v) && v >= lo && v <= hi;
  };
  switch (t) {
    case Type::kInt8:
      return whole_in(-128, 127);
    case Type::kUint8:
      return whole_in(0, 255);
    case Type::kInt16:
      return whole_in(-32768, 32767);
    case Type::kUint16:
      return whole_in(0, 65535);
    case Type::kInt32:
      return whole_in(-2147483648.0, 2147483647.0);
    case Type::kUint32:
      return whole_in(0, 4294967295.0);
    case Type::kFloat32:
    case Type::kFloat64:
      return true;  // NaN and Inf are caught as coordinates
  }
  return true;
}

/// The value of type T in the first bytes of `b` (host order).
template <class T>
double as(const unsigned char* b) {
  T v;
  std::memcpy(&v, b, sizeof v);
  return static_cast<double>(v);
}

/// The values of a PLY body, one at a time, as doubles (every PLY type fits one exactly).
class Body {
 public:
  Body(std::string_view bytes, const Header& header, const std::string& name)
      : bytes_(bytes),
        pos_(header.body),
        format_(header.format),
        tokens_(bytes, header.body, header.body_line),
        name_(name),
        header_(header) {}

  /// Where the values being read belong, for messages.
  void at(const Element& e, long long item) {
    element_ = &e;
    item_ = item;
  }

  double value(Type type) {
    if (format_ == Header::Format::kAscii) {
      std::string_view word;
      if (!tokens_.next(word)) truncated();
      double v = 0;
      if (!parse_number(word, v) || !fits(type, v))
        fail(name_,
             where() + " (line " + std::to_string(tokens_.line_no()) + "): " + quoted(word) +
                 " is not a value of its property's type",
             kFix);
      return v;
    }
    const std::size_t n = size_of(type);
    if (bytes_.size() - pos_ < n) truncated();
    unsigned char b[8] = {};
    std::memcpy(b, bytes_.data() + pos_, n);
    pos_ += n;
    if (format_ == Header::Format::kBig) std::reverse(b, b + n);
    switch (type) {
      case Type::kInt8:
        return as<std::int8_t>(b);
      case Type::kUint8:
        return as<std::uint8_t>(b);
      case Type::kInt16:
        return as<std::int16_t>(b);
      case Type::kUint16:
        return as<std::uint16_t>(b);
      case Type::kInt32:
        return as<std::int32_t>(b);
      case Type::kUint32:
        return as<std::uint32_t>(b);
      case Type::kFloat32:
        return as<float>(b);
      case Type::kFloat64:
        return as<double>(b);
    }
    return 0;
  }

  /// A list's length, checked against the bytes left (1 or 2 bytes an entry at the least).
  std::size_t list_length(const Property& p) {
    const double n = value(p.count_type);
    const double least = format_ == Header::Format::kAscii ? 2.0 : double(size_of(p.type));
    const double left = double(bytes_.size() - std::min(bytes_.size(), pos_));
    if (!(n >= 0) || n != std::floor(n))
      fail(
          name_,
          where() + ": its list " + quoted(p.name) + " announces " + std::to_string(n) + " entries",
          kFix);
    if (n * least > left + 1)
      truncated(" (its list " + quoted(p.name) + " announces " +
                std::to_string(static_cast<long long>(n)) + " entries)");
    return static_cast<std::size_t>(n);
  }

  /// One vertex index.
  std::int64_t index(Type type) {
    const double v = value(type);
    // Indices beyond +-2^53 cannot name a vertex (and would not convert exactly).
    if (v != std::floor(v) || std::abs(v) > 9007199254740992.0)
      fail(name_, where() + ": vertex index " + std::to_string(v) + " is not an integer index",
           kFix);
    return static_cast<std::int64_t>(v);
  }

  std::string where() const {
    return "element " + quoted(element_->name) + " " + std::to_string(item_);
  }

 private:
  [[noreturn]] void truncated(const std::string& detail = "") const {
    const long long faces = header_.count("face");
    fail(name_,
         "truncated: the header announces " + std::to_string(header_.count("vertex")) +
             " vertices and " +
             (faces > 0 || header_.count("tristrips") == 0
                  ? std::to_string(faces) + " faces"
                  : std::to_string(header_.count("tristrips")) + " triangle strips") +
             ", the file ends inside " + where() + detail,
         kFix);
  }

  std::string_view bytes_;
  std::size_t pos_;  ///< binary
  Header::Format format_;
  Tokens tokens_;  ///< ASCII
  const std::string& name_;
  const Header& header_;
  const Element* element_ = nullptr;
  long long item_ = 0;
};

/// The property of `e` read as its index list: vertex_indices, vertex_index, or the first list.
const Property* index_list(const Element& e) {
  const Property* first = nullptr;
  for (const Property& p : e.properties) {
    if (!p.list) continue;
    if (p.name == "vertex_indices" || p.name == "vertex_index") return &p;
    if (!first) first = &p;
  }
  return first;
}

/// Triangle i of a strip is (s_i, s_i+1, s_i+2), every other one reversed to keep the
/// orientation; -1 restarts the strip; triangles with a repeated index are skipped.
void strip_triangles(const std::vector<std::int64_t>& strip,
                     std::vector<std::vector<std::int64_t>>& out) {
  std::size_t start = 0;
  for (std::size_t end = 0; end <= strip.size(); ++end) {
    if (end < strip.size() && strip[end] >= 0) continue;
    for (std::size_t k = start; k + 2 < end; ++k) {
      std::vector<std::int64_t> t = {strip[k], strip[k + 1], strip[k + 2]};
      if ((k - start) % 2 == 1) std::swap(t[0], t[1]);
      if (t[0] != t[1] && t[1] != t[2] && t[0] != t[2]) out.push_back(std::move(t));
    }
    start = end + 1;
  }
}

}  // namespace

PolygonSoup read_ply(std::string_view bytes, const std::string& name) {
  const Header header = read_header(bytes, name);
  PolygonSoup soup;
  Body body(bytes, header, name);
  BadCoordinates bad;
  for (const Element& e : header.elements) {
    const bool vertex = e.name == "vertex", face = e.name == "face", strips = e.name == "tristrips";
    int axis[3] = {-1, -1, -1};  // the x, y, z properties of a vertex
    for (std::size_t k = 0; vertex && k < e.properties.size(); ++k)
      for (int a = 0; a < 3; ++a)
        if (!e.properties[k].list && e.properties[k].name == std::string(1, char('x' + a)))
          axis[a] = static_cast<int>(k);
    if (vertex)
      for (int a = 0; a < 3; ++a)
        if (axis[a] < 0)
          fail(name,
               "PLY element 'vertex' has no scalar property '" + std::string(1, 'x' + a) + "'",
               kFix);
    const Property* indices = face || strips ? index_list(e) : nullptr;
    if ((face || strips) && !indices)
      fail(name, "PLY element " + quoted(e.name) + " has no list of vertex indices", kFix);
    if (vertex) soup.points.reserve(static_cast<std::size_t>(e.count));
    if (face) soup.polygons.reserve(static_cast<std::size_t>(e.count));
    std::vector<std::int64_t> list;
    for (long long i = 0; i < e.count; ++i) {
      body.at(e, i);
      Vec3d p;
      for (std::size_t k = 0; k < e.properties.size(); ++k) {
        const Property& prop = e.properties[k];
        if (!prop.list) {
          const double v = body.value(prop.type);
          for (int a = 0; a < 3; ++a)
            if (axis[a] == static_cast<int>(k)) p[a] = v;
          continue;
        }
        const std::size_t n = body.list_length(prop);
        const bool wanted = &prop == indices;
        if (wanted) list.resize(n);
        for (std::size_t j = 0; j < n; ++j) {
          if (wanted)
            list[j] = body.index(prop.type);
          else
            body.value(prop.type);
        }
        if (wanted && face) soup.polygons.push_back(list);
        if (wanted && strips) strip_triangles(list, soup.polygons);
      }
      if (vertex) {
        bad.check(true, p, "vertex " + std::to_string(i),
                  std::to_string(p.x) + " " + std::to_string(p.y) + " " + std::to_string(p.z));
        soup.points.push_back(p);
      }
    }
  }
  bad.throw_if_any(name);
  return soup;
}

}  // namespace vdb_shell::read_detail
