// read_off.cpp — Object File Format: the keyword (OFF with the prefixes of its variants: ST, C, N,
// 4, n), the counts, one vertex per line, one face per line ("n i0 ... i(n-1)" and optional
// colours); or, after "OFF BINARY", the same in big-endian 32-bit integers and floats.
#include <algorithm>
#include <cctype>
#include <cstring>
#include <string>

#include "core/read/format_reader.h"

namespace vdb_shell::read_detail {
namespace {

const char* const kFix = "re-export the mesh (a complete OFF file)";

/// What the keyword's prefixes add to each vertex.
struct OffLayout {
  bool homogeneous = false;  ///< 4OFF: x y z w
  bool dimension = false;    ///< nOFF: the dimension precedes the counts
  int extra_floats = 0;      ///< binary: normals (N: 3), colour (C: 4), texture (ST: 2)
};

/// Big-endian 32-bit values of a binary OFF body.
class BigEndian {
 public:
  BigEndian(std::string_view bytes, std::size_t offset, const std::string& name)
      : bytes_(bytes), pos_(offset), name_(name) {}
  std::size_t left() const { return bytes_.size() - pos_; }
  std::uint32_t word(const char* what) {
    if (left() < 4) fail(name_, "truncated: the file ends inside " + std::string(what), kFix);
    const auto* b = reinterpret_cast<const unsigned char*>(bytes_.data() + pos_);
    pos_ += 4;
    return std::uint32_t(b[0]) << 24 | std::uint32_t(b[1]) << 16 | std::uint32_t(b[2]) << 8 |
           std::uint32_t(b[3]);
  }
  std::int32_t integer(const char* what) { return static_cast<std::int32_t>(word(what)); }
  float real(const char* what) {
    const std::uint32_t w = word(what);
    float f;
    std::memcpy(&f, &w, 4);
    return f;
  }

 private:
  std::string_view bytes_;
  std::size_t pos_;
  const std::string& name_;
};

PolygonSoup read_binary_off(std::string_view bytes, std::size_t body, const OffLayout& layout,
                            const std::string& name) {
  BigEndian in(bytes, body, name);
  const long long nv = in.integer("the counts"), nf = in.integer("the counts");
  in.integer("the counts");  // edges
  if (nv < 0 || nf < 0)
    fail(name,
         "the binary header's counts (" + std::to_string(nv) + " vertices, " + std::to_string(nf) +
             " faces) are not numbers of elements >= 0",
         kFix);
  const int floats = 3 + layout.homogeneous + layout.extra_floats;
  if (static_cast<long double>(nv) * 4 * floats + static_cast<long double>(nf) * 16 > in.left())
    fail(name,
         "truncated: the binary header announces " + std::to_string(nv) + " vertices and " +
             std::to_string(nf) + " faces, more than the file's " + std::to_string(bytes.size()) +
             " bytes can hold",
         kFix);
  PolygonSoup soup;
  soup.points.resize(static_cast<std::size_t>(nv));
  BadCoordinates bad;
  for (long long v = 0; v < nv; ++v) {
    Vec3d& p = soup.points[static_cast<std::size_t>(v)];
    for (int k = 0; k < 3; ++k) p[k] = in.real("a vertex");
    const double w = layout.homogeneous ? in.real("a vertex") : 1.0;
    p = p / w;
    for (int k = 0; k < layout.extra_floats; ++k) in.real("a vertex");
    bad.check(true, p, "vertex " + std::to_string(v), "binary");
  }
  bad.throw_if_any(name);
  soup.polygons.reserve(static_cast<std::size_t>(nf));
  for (long long f = 0; f < nf; ++f) {
    const long long n = in.integer("a face");
    if (n < 3)
      fail(name,
           "face " + std::to_string(f) + " announces " + std::to_string(n) +
               " corners (a face needs 3 or more)",
           kFix);
    if (static_cast<long double>(n) * 4 > in.left())
      fail(name,
           "truncated: face " + std::to_string(f) + " announces " + std::to_string(n) +
               " corners, more than the " + std::to_string(in.left()) + " bytes left hold",
           kFix);
    std::vector<std::int64_t> polygon(static_cast<std::size_t>(n));
    for (std::int64_t& i : polygon) {
      i = in.integer("a face");
      if (i < 0 || i >= nv)
        fail(name,
             "face " + std::to_string(f) + ": out-of-range vertex index " + std::to_string(i) +
                 " (the file has " + std::to_string(nv) + " vertices, numbered from 0)",
             kFix);
    }
    const long long colours = in.integer("a face");
    if (colours < 0 || colours > 4)
      fail(name,
           "face " + std::to_string(f) + " has " + std::to_string(colours) +
               " colour components (0 to 4)",
           kFix);
    for (long long c = 0; c < colours; ++c) in.real("a face");
    soup.polygons.push_back(std::move(polygon));
  }
  return soup;
}

}  // namespace

PolygonSoup read_off(std::string_view bytes, const std::string& name) {
  Lines lines(bytes);
  std::string_view line;
  const auto next_content_line = [&] {  // skips blank and comment lines
    while (lines.next(line))
      if (!words(line, '#', 1).empty()) return true;
    return false;
  };
  if (!next_content_line()) fail(name, "not an OFF file: it holds no keyword", kFix);
  // The keyword: OFF with its variants' prefixes; counts may follow on its line, even glued to
  // it ("OFF8 6 0", as some exporters write).
  std::vector<std::string_view> header = words(line);
  const std::string_view key = header[0];
  const std::size_t off = key.find("OFF");
  const std::string_view prefix = key.substr(0, off);
  const bool glued = key.size() > off + 3;
  if (off == std::string_view::npos ||
      prefix.find_first_not_of("STCN4n") != std::string_view::npos ||
      (glued && !std::isdigit(static_cast<unsigned char>(key[off + 3]))))
    fail(name,
         "not an OFF file: line " + std::to_string(lines.line_no()) + " starts with " +
             quoted(key, 20),
         kFix);
  OffLayout layout;
  layout.homogeneous = prefix.find('4') != std::string_view::npos;
  layout.dimension = prefix.find('n') != std::string_view::npos;
  layout.extra_floats = 3 * (prefix.find('N') != std::string_view::npos) +
                        4 * (prefix.find('C') != std::string_view::npos) +
                        2 * (prefix.find("ST") != std::string_view::npos);
  std::vector<std::string_view> numbers;
  if (glued) numbers.push_back(key.substr(off + 3));
  numbers.insert(numbers.end(), header.begin() + 1, header.end());
  if (!numbers.empty() && numbers[0] == "BINARY") {
    if (layout.dimension) fail(name, "binary nOFF files are not read", "write an ASCII OFF file");
    return read_binary_off(bytes, lines.offset(), layout, name);
  }
  const std::size_t wanted = 2 + layout.dimension;  // [dimension] vertices faces [edges]
  while (numbers.size() < wanted && next_content_line()) {
    const std::vector<std::string_view> w = words(line);
    numbers.insert(numbers.end(), w.begin(), w.end());
  }
  if (numbers.size() < wanted)
    fail(name,
         "truncated: the header has no vertex and face counts (line " +
             std::to_string(lines.line_no()) + ")",
         kFix);
  long long count[3] = {3, 0, 0};
  const char* const what[3] = {"dimension", "vertex count", "face count"};
  for (std::size_t k = 0; k < wanted; ++k) {
    const std::size_t slot = k + !layout.dimension;
    if (!parse_integer(numbers[k], count[slot]) || count[slot] < 0)
      fail(name,
           std::string("the header's ") + what[slot] + " " + quoted(numbers[k]) + " (line " +
               std::to_string(lines.line_no()) + ") is not a number of elements >= 0",
           kFix);
  }
  if (count[0] != 3)
    fail(name, "the header's dimension is " + std::to_string(count[0]) + ", not 3",
         "write the mesh in 3 dimensions");
  const long long nv = count[1], nf = count[2];
  // "0 0 0\n" per vertex, "3 0 1 2" per face, at the least.
  if (6.0L * nv + 4.0L * nf > static_cast<long double>(bytes.size()))
    fail(name,
         "truncated: the header (line " + std::to_string(lines.line_no()) + ") announces " +
             std::to_string(nv) + " vertices and " + std::to_string(nf) +
             " faces, more than the file's " + std::to_string(bytes.size()) + " bytes can hold",
         kFix);
  const auto next_element = [&](const char* element, long long index, long long total) {
    if (!next_content_line())
      fail(name,
           "truncated: the header announces " + std::to_string(total) + " " + element +
               ", the file ends after " + std::to_string(index),
           kFix);
  };
  PolygonSoup soup;
  soup.points.resize(static_cast<std::size_t>(nv));
  BadCoordinates bad;
  const std::size_t coords = 3 + layout.homogeneous;
  for (long long v = 0; v < nv; ++v) {
    next_element("vertices", v, nv);
    const std::vector<std::string_view> w = words(line, '#', coords);
    const std::string where =
        "vertex " + std::to_string(v) + " (line " + std::to_string(lines.line_no()) + ")";
    if (w.size() < coords)
      fail(name, where + " has fewer than " + std::to_string(coords) + " coordinates", kFix);
    Vec3d& p = soup.points[static_cast<std::size_t>(v)];
    double h = 1.0;
    bool readable = true;
    for (int k = 0; k < 3; ++k) readable = parse_number(w[k], p[k]) && readable;
    if (layout.homogeneous) readable = parse_number(w[3], h) && readable;
    p = p / h;
    bad.check(readable, p, where, line.substr(static_cast<std::size_t>(w[0].data() - line.data())));
  }
  bad.throw_if_any(name);
  soup.polygons.reserve(static_cast<std::size_t>(nf));
  for (long long f = 0; f < nf; ++f) {
    next_element("faces", f, nf);
    const std::vector<std::string_view> w = words(line);
    const std::string where =
        "face " + std::to_string(f) + " (line " + std::to_string(lines.line_no()) + ")";
    long long corners = 0;
    if (!leading_integer(w[0], corners) || corners < 3 ||
        corners > static_cast<long long>(w.size()) - 1)
      fail(name,
           where + " announces " + quoted(w[0]) + " corners but lists " +
               std::to_string(w.size() - 1) + " numbers (a face needs 3 or more)",
           kFix);
    std::vector<std::int64_t> polygon(static_cast<std::size_t>(corners));
    for (std::size_t k = 0; k < polygon.size(); ++k) {
      long long index = -1;
      if (!parse_integer(w[k + 1], index) || index < 0 || index >= nv)
        fail(name,
             where + ": out-of-range vertex index " + quoted(w[k + 1]) + " (the file has " +
                 std::to_string(nv) + " vertices, numbered from 0)",
             kFix);
      polygon[k] = index;
    }
    soup.polygons.push_back(std::move(polygon));  // numbers after the corners: a colour
  }
  return soup;
}

}  // namespace vdb_shell::read_detail
