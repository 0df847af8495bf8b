// polygon_soup.cpp — OpenMesh-backed reader that keeps the file's polygons as written.
#include "core/read/polygon_soup.h"

#include <OpenMesh/Core/IO/IOManager.hh>
#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/IO/importer/BaseImporter.hh>
#include <OpenMesh/Core/System/omstream.hh>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <mutex>
#include <sstream>

#include "core/base/errors.h"
#include "core/base/file_name.h"

namespace vdb_shell {
namespace {

namespace om = OpenMesh;
using om::EdgeHandle;
using om::FaceHandle;
using om::HalfedgeHandle;
using om::VertexHandle;

/// BaseImporter that records positions and polygons and ignores every attribute.
class SoupImporter final : public om::IO::BaseImporter {
 public:
  explicit SoupImporter(PolygonSoup& soup) : soup_(soup) {}

  VertexHandle add_vertex(const om::Vec3f& p) override {
    return add_vertex(om::Vec3d(p[0], p[1], p[2]));
  }
  VertexHandle add_vertex(const om::Vec3d& p) override {
    soup_.points.push_back({p[0], p[1], p[2]});
    return VertexHandle(static_cast<int>(soup_.points.size()) - 1);
  }
  VertexHandle add_vertex() override { return add_vertex(om::Vec3d(0, 0, 0)); }
  FaceHandle add_face(const VHandles& indices) override {
    std::vector<std::int64_t> poly;
    poly.reserve(indices.size());
    for (const VertexHandle& vh : indices) poly.push_back(vh.idx());
    soup_.polygons.push_back(std::move(poly));
    return FaceHandle(static_cast<int>(soup_.polygons.size()) - 1);
  }
  void set_point(VertexHandle vh, const om::Vec3f& p) override {
    if (vh.is_valid() && static_cast<std::size_t>(vh.idx()) < soup_.points.size())
      soup_.points[static_cast<std::size_t>(vh.idx())] = {p[0], p[1], p[2]};
  }
  size_t n_vertices() const override { return soup_.points.size(); }
  size_t n_faces() const override { return soup_.polygons.size(); }
  size_t n_edges() const override { return 0; }

  // Everything below carries attributes vdb_shell does not use.
  HalfedgeHandle add_edge(VertexHandle, VertexHandle) override { return HalfedgeHandle(); }
  FaceHandle add_face(HalfedgeHandle) override { return FaceHandle(); }
  void add_face_texcoords(FaceHandle, VertexHandle, const std::vector<om::Vec2f>&) override {}
  void add_face_texcoords(FaceHandle, VertexHandle, const std::vector<om::Vec3f>&) override {}
  void set_face_texindex(FaceHandle, int) override {}
  void set_halfedge(VertexHandle, HalfedgeHandle) override {}
  void set_normal(VertexHandle, const om::Vec3f&) override {}
  void set_normal(VertexHandle, const om::Vec3d&) override {}
  void set_color(VertexHandle, const om::Vec3uc&) override {}
  void set_color(VertexHandle, const om::Vec4uc&) override {}
  void set_color(VertexHandle, const om::Vec3f&) override {}
  void set_color(VertexHandle, const om::Vec4f&) override {}
  void set_texcoord(VertexHandle, const om::Vec2f&) override {}
  void set_status(VertexHandle, const om::Attributes::StatusInfo&) override {}
  void set_next(HalfedgeHandle, HalfedgeHandle) override {}
  void set_face(HalfedgeHandle, FaceHandle) override {}
  void request_face_texcoords2D() override {}
  void set_texcoord(HalfedgeHandle, const om::Vec2f&) override {}
  void set_texcoord(VertexHandle, const om::Vec3f&) override {}
  void set_texcoord(HalfedgeHandle, const om::Vec3f&) override {}
  void set_status(HalfedgeHandle, const om::Attributes::StatusInfo&) override {}
  void set_color(EdgeHandle, const om::Vec3uc&) override {}
  void set_color(EdgeHandle, const om::Vec4uc&) override {}
  void set_color(EdgeHandle, const om::Vec3f&) override {}
  void set_color(EdgeHandle, const om::Vec4f&) override {}
  void set_status(EdgeHandle, const om::Attributes::StatusInfo&) override {}
  void set_normal(FaceHandle, const om::Vec3f&) override {}
  void set_normal(FaceHandle, const om::Vec3d&) override {}
  void set_color(FaceHandle, const om::Vec3uc&) override {}
  void set_color(FaceHandle, const om::Vec4uc&) override {}
  void set_color(FaceHandle, const om::Vec3f&) override {}
  void set_color(FaceHandle, const om::Vec4f&) override {}
  void set_status(FaceHandle, const om::Attributes::StatusInfo&) override {}
  void add_texture_information(int, std::string) override {}

 private:
  PolygonSoup& soup_;
};

/// OpenMesh's diagnostics of one read, as a string. Its error stream is routed, once for the
/// process, into one buffer (its log and output streams are muted): OpenMesh 9's
/// multiplex_streambuf::disconnect() does not free what connect() allocated, so connecting per
/// read leaked. Reads take turns on the buffer (OpenMesh's streams are global anyway).
class CaptureOpenMeshLog {
 public:
  CaptureOpenMeshLog() : lock_(mutex()) { buffer().str(""); }
  std::string text() {
    ::omerr().flush();
    std::string s = buffer().str();
    std::replace(s.begin(), s.end(), '\n', ' ');
    while (!s.empty() && s.back() == ' ') s.pop_back();
    return s;
  }

 private:
  static std::mutex& mutex() {
    static std::mutex m;
    return m;
  }
  static std::ostringstream& buffer() {
    static std::ostringstream* const b = [] {
      auto* s = new std::ostringstream;  // lives as long as OpenMesh's streams refer to it
      ::omerr().disconnect(std::cerr);
      ::omlog().disconnect(std::cerr);
      ::omout().disconnect(std::cout);
      ::omerr().connect(*s);
      return s;
    }();
    return *b;
  }
  std::lock_guard<std::mutex> lock_;
};

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

/// A binary STL must be exactly 84 + 50 * n bytes; OpenMesh would otherwise misread a
/// truncated one as ASCII. Returns an empty string when the file looks sound.
std::string check_stl_size(const std::string& path, std::uintmax_t size) {
  std::ifstream in(path, std::ios::binary);
  char head[84] = {};
  in.read(head, sizeof head);
  const std::streamsize got = in.gcount();
  const bool ascii_start = got >= 5 && lower(std::string(head, 5)) == "solid";
  // An ASCII STL (or a binary one whose header starts with "solid"): OpenMesh tells them apart
  // and its parser reports its own errors.
  if (ascii_start) return {};
  if (got < 84)
    return "binary STL is truncated: " + std::to_string(size) +
           " bytes, less than the 84-byte header";
  std::uint32_t n = 0;
  std::memcpy(&n, head + 80, 4);
  const std::uintmax_t want = 84 + 50ull * n;
  if (size != want)
    return "binary STL is truncated or corrupt: its header announces " + std::to_string(n) +
           " triangles (" + std::to_string(want) + " bytes) but the file has " +
           std::to_string(size) + " bytes";
  return {};
}

/// Vertex positions of an ASCII OBJ or OFF file, parsed in double precision (OpenMesh's readers
/// store floats and skip coordinates they cannot parse, such as "nan").
struct AsciiVertices {
  std::vector<Vec3d> points;
  std::vector<std::string> bad;  ///< "vertex 3 (line 5): 'nan 0 1'"
  bool parsed = false;           ///< false when the format is not one we scan
};

bool parse_xyz(const std::string& text, Vec3d& p) {
  const char* s = text.c_str();
  for (int k = 0; k < 3; ++k) {
    char* end = nullptr;
    const double v = std::strtod(s, &end);
    if (end == s) return false;
    p[k] = v;
    s = end;
  }
  return is_finite(p);
}

AsciiVertices scan_ascii_vertices(const std::string& path, const std::string& ext) {
  AsciiVertices out;
  std::ifstream in(path);
  std::string line;
  std::size_t line_no = 0;
  auto add = [&](const std::string& coords) {
    Vec3d p;
    if (!parse_xyz(coords, p) && out.bad.size() < 3)
      out.bad.push_back("vertex " + std::to_string(out.points.size()) + " (line " +
                        std::to_string(line_no) + "): '" + coords.substr(0, 60) + "'");
    out.points.push_back(p);
  };
  if (ext == ".obj") {
    while (std::getline(in, line)) {
      ++line_no;
      std::size_t i = line.find_first_not_of(" \t");
      if (i != std::string::npos && line.compare(i, 2, "v ") == 0) add(line.substr(i + 2));
      if (i != std::string::npos && line.compare(i, 2, "v\t") == 0) add(line.substr(i + 2));
    }
    out.parsed = true;
    return out;
  }
  // OFF: header keyword (OFF, COFF, NOFF, ...), counts, then one vertex per line.
  std::vector<std::string> header;
  long long nv = -1;
  while (nv < 0 && std::getline(in, line)) {
    ++line_no;
    const std::size_t hash = line.find('#');
    std::istringstream words(line.substr(0, hash));
    std::string w;
    while (words >> w) header.push_back(w);
    if (!header.empty() && header[0].find("OFF") == std::string::npos) return out;
    if (!header.empty() && line.find("BINARY") != std::string::npos) return out;
    if (header.size() >= 4) nv = std::atoll(header[1].c_str());
  }
  while (nv > 0 && static_cast<long long>(out.points.size()) < nv && std::getline(in, line)) {
    ++line_no;
    const std::size_t first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    add(line.substr(first));
  }
  out.parsed = true;
  return out;
}

/// The integer at the start of `text` (after blanks), or false when there is none or it does not
/// fit a long long.
bool leading_integer(const char*& text, long long& value) {
  while (*text == ' ' || *text == '\t' || *text == '\r') ++text;
  char* end = nullptr;
  errno = 0;
  value = std::strtoll(text, &end, 10);
  if (end == text || errno == ERANGE) return false;
  text = end;
  return true;
}

/// The words of `line` before a '#', at most `max` of them.
std::vector<std::string> words(const std::string& line, std::size_t max = SIZE_MAX) {
  std::istringstream in(line.substr(0, line.find('#')));
  std::vector<std::string> out;
  for (std::string w; out.size() < max && in >> w;) out.push_back(w);
  return out;
}

/// An ASCII OFF file's counts and face lines against the file itself, before OpenMesh (which
/// reserves what the header announces) reads it: counts that are numbers >= 0 and fit the file
/// (at least 6 bytes a vertex, 4 a face), every announced line present, every face line with
/// the corners it announces. Throws InputError naming the line.
void check_off_structure(const std::string& path, std::uintmax_t size) {
  std::ifstream in(path);
  std::string line;
  std::size_t line_no = 0;
  const auto fail = [&](const std::string& what) {
    throw InputError(path + ": " + what + " — fix: re-export the mesh (a complete OFF file)");
  };
  // The header: the keyword alone on its line (OpenMesh reads no counts there), then the counts.
  std::vector<std::string> header;
  while (header.size() < 3 && std::getline(in, line)) {
    ++line_no;
    const std::vector<std::string> w = words(line);
    if (header.empty() && w.size() > 1 && w[1] != "BINARY")
      fail("the counts must be on the line after the keyword, not on line " +
           std::to_string(line_no));
    header.insert(header.end(), w.begin(), w.end());
    // The keyword: OFF with the prefixes of its variants (ST, C, N, 4, n: STCNOFF, 4OFF, ...).
    const std::string& k = header.empty() ? line : header[0];
    if (!header.empty() && (k.size() < 3 || k.compare(k.size() - 3, 3, "OFF") != 0 ||
                            k.find_first_not_of("STCN4n") < k.size() - 3))
      fail("not an OFF file: line 1 starts with '" + k.substr(0, 20) + "'");
    if (line.find("BINARY") != std::string::npos) return;  // binary counts: OpenMesh's checks
  }
  if (header.size() < 3)
    fail("truncated: the header has no vertex and face counts (line " + std::to_string(line_no) +
         ")");
  long long count[2] = {0, 0};
  for (int k = 0; k < 2; ++k) {
    const char* text = header[1 + k].c_str();
    if (!leading_integer(text, count[k]) || *text != '\0' || count[k] < 0)
      fail(std::string("the header's ") + (k ? "face" : "vertex") + " count '" +
           header[1 + k].substr(0, 24) + "' (line " + std::to_string(line_no) +
           ") is not a number of elements >= 0");
  }
  const long long nv = count[0], nf = count[1];
  const long double least = 6.0L * nv + 4.0L * nf;  // "0 0 0\n" per vertex, "3 0 1 2" per face
  if (least > static_cast<long double>(size))
    fail("truncated: the header (line " + std::to_string(line_no) + ") announces " +
         std::to_string(nv) + " vertices and " + std::to_string(nf) +
         " faces, more than the file's " + std::to_string(size) + " bytes can hold");
  const auto next_line = [&](const char* what, long long index, long long total) {
    while (std::getline(in, line)) {
      ++line_no;
      if (!words(line, 1).empty()) return;
    }
    fail("truncated: the header announces " + std::to_string(total) + " " + what +
         ", the file ends after " + std::to_string(index));
  };
  for (long long v = 0; v < nv; ++v) {
    next_line("vertices", v, nv);
    if (words(line, 3).size() < 3)
      fail("vertex " + std::to_string(v) + " (line " + std::to_string(line_no) +
           ") has fewer than 3 coordinates");
  }
  for (long long f = 0; f < nf; ++f) {
    next_line("faces", f, nf);
    const std::vector<std::string> w = words(line);
    const char* text = w[0].c_str();
    long long corners = 0;
    if (!leading_integer(text, corners) || corners < 3 ||
        corners > static_cast<long long>(w.size()) - 1)
      fail("face " + std::to_string(f) + " (line " + std::to_string(line_no) + ") announces '" +
           w[0].substr(0, 24) + "' corners but lists " + std::to_string(w.size() - 1) +
           " numbers (a face needs 3 or more)");
    for (long long k = 1; k <= corners; ++k) {  // OpenMesh reads exactly these as indices
      const char* index_text = w[static_cast<std::size_t>(k)].c_str();
      long long index = -1;
      if (!leading_integer(index_text, index) || *index_text != '\0' || index < 0 || index >= nv)
        fail("face " + std::to_string(f) + " (line " + std::to_string(line_no) +
             "): out-of-range vertex index '" + w[static_cast<std::size_t>(k)].substr(0, 24) +
             "' (the file has " + std::to_string(nv) + " vertices, numbered from 0)");
    }
  }
}

/// Every face index of an OBJ file in range: 1..n, or -1..-(vertices so far), n the file's
/// vertex count (OpenMesh drops a face with a bad index without a word). Throws InputError
/// naming the line.
void check_obj_indices(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  const auto keyword = [&](const char* k) {  // the line starts with k and a blank
    const std::size_t i = line.find_first_not_of(" \t");
    const std::size_t n = std::strlen(k);
    return i != std::string::npos && line.compare(i, n, k) == 0 && line.size() > i + n &&
           (line[i + n] == ' ' || line[i + n] == '\t');
  };
  long long total = 0;
  while (std::getline(in, line)) total += keyword("v");
  in.clear();
  in.seekg(0);
  long long so_far = 0, face = 0;
  std::size_t line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (keyword("v")) ++so_far;
    if (!keyword("f")) continue;
    const char* text = line.c_str() + line.find('f') + 1;
    int corners = 0;
    for (;; ++corners) {  // v, v/vt, v//vn or v/vt/vn: the vertex index comes first
      while (*text == ' ' || *text == '\t' || *text == '\r') ++text;
      if (*text == '\0' || *text == '#') break;
      const char* word = text;
      long long index = 0;
      const bool number = leading_integer(text, index);
      while (*text != '\0' && *text != ' ' && *text != '\t' && *text != '\r') ++text;
      if (number && ((index > 0 && index <= total) || (index < 0 && -index <= so_far))) continue;
      throw InputError(
          path + ": face " + std::to_string(face) + " (line " + std::to_string(line_no) +
          "): out-of-range vertex index '" +
          std::string(word, static_cast<std::size_t>(std::min<std::ptrdiff_t>(text - word, 24))) +
          "' (the file has " + std::to_string(total) +
          " vertices, numbered from 1, or back from -1) — fix: the file is corrupt "
          "or truncated; re-export the mesh");
    }
    if (corners < 3)
      throw InputError(path + ": face " + std::to_string(face) + " (line " +
                       std::to_string(line_no) + ") has " + std::to_string(corners) +
                       " corners, a face needs 3 (a file cut short ends so) — fix: re-export the "
                       "mesh");
    ++face;
  }
}

/// A PLY header: its format, elements and where its body starts.
struct PlyHeader {
  struct Property {
    std::string type, count_type;  ///< count_type: non-empty for a list
  };
  struct Element {
    std::string name;
    long long count = 0;
    std::vector<Property> properties;
  };
  std::string format;
  std::vector<Element> elements;
  std::streamoff body = 0;  ///< the byte after end_header's line
  /// The count of element `name`, or -1 without one.
  long long count(const std::string& name) const {
    for (const Element& e : elements)
      if (e.name == name) return e.count;
    return -1;
  }
};

/// The header of the PLY file `path` (`size` bytes), one OpenMesh can be trusted with: "ply", a
/// known format, element lines with counts >= 0, property lines with known types, end_header,
/// and element counts the file's bytes can hold (a vertex takes at least 3 bytes, a face or strip
/// 2), elements among vertex, face, tristrips and edge. OpenMesh loops forever on a property
/// line cut short and on some unknown elements. Throws InputError naming the line.
PlyHeader read_ply_header(const std::string& path, std::uintmax_t size) {
  std::ifstream in(path, std::ios::binary);
  PlyHeader header;
  std::string line;
  std::size_t line_no = 0;
  const auto fail = [&](const std::string& what) {
    throw InputError(path + ": PLY header line " + std::to_string(line_no) + ": " + what +
                     " — fix: re-export the mesh (a complete PLY file)");
  };
  static const char* const kTypes[] = {"char",  "uchar",  "short",   "ushort", "int",   "uint",
                                       "float", "double", "int8",    "uint8",  "int16", "uint16",
                                       "int32", "uint32", "float32", "float64"};
  const auto known = [](const std::string& t) {
    return std::find(std::begin(kTypes), std::end(kTypes), t) != std::end(kTypes);
  };
  long double least = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const std::vector<std::string> w = words(line);
    if (line_no == 1) {
      if (w.size() != 1 || w[0] != "ply") fail("not 'ply'");
      continue;
    }
    if (w.empty() || w[0] == "comment" || w[0] == "obj_info") continue;
    if (w[0] == "end_header") {
      if (least > static_cast<long double>(size))
        fail("its element counts are more than the file's " + std::to_string(size) +
             " bytes can hold");
      header.body = in.tellg();
      return header;
    }
    if (w[0] == "format") {
      if (w.size() != 3 || w[2] != "1.0" ||
          (w[1] != "ascii" && w[1] != "binary_little_endian" && w[1] != "binary_big_endian"))
        fail("unknown format '" + line.substr(0, 60) + "'");
      header.format = w[1];
    } else if (w[0] == "element") {
      const char* text = w.size() == 3 ? w[2].c_str() : "";
      long long count = -1;
      if (w.size() != 3 || !leading_integer(text, count) || *text != '\0' || count < 0)
        fail("an element needs a name and a count >= 0: '" + line.substr(0, 60) + "'");
      // OpenMesh's parser hangs on some elements it does not know: only what a mesh needs.
      if (w[1] != "vertex" && w[1] != "face" && w[1] != "tristrips" && w[1] != "edge")
        fail("element '" + w[1].substr(0, 24) +
             "' is none of vertex, face, tristrips, edge (the ones read)");
      least += static_cast<long double>(count) * (w[1] == "vertex" ? 3 : 2);
      header.elements.push_back({w[1], count, {}});
    } else if (w[0] == "property") {
      const bool list = w.size() == 5 && w[1] == "list" && known(w[2]) && known(w[3]);
      if (header.elements.empty() || !(list || (w.size() == 3 && known(w[1]))))
        fail("not a property of a known type: '" + line.substr(0, 60) + "'");
      header.elements.back().properties.push_back(list ? PlyHeader::Property{w[3], w[2]}
                                                       : PlyHeader::Property{w[1], ""});
    } else {
      fail("unknown keyword '" + w[0].substr(0, 24) + "'");
    }
  }
  fail("the file ends before end_header");
  return header;
}

/// The triangles of a PLY file's `tristrips` element (OpenMesh reads only `face`): each strip a
/// list of vertex indices, -1 restarting it; triangle i of a strip is (s_i, s_i+1, s_i+2), every
/// other one reversed to keep the orientation; triangles with a repeated index are skipped.
/// ASCII and binary (either byte order). Empty when the file has no tristrips element.
/// Throws InputError for a file that ends early or a type it does not know.
std::vector<std::vector<std::int64_t>> read_ply_tristrips(const std::string& path,
                                                          const PlyHeader& header) {
  std::ifstream in(path, std::ios::binary);
  in.seekg(header.body);
  using Element = PlyHeader::Element;
  using Property = PlyHeader::Property;
  const std::vector<Element>& elements = header.elements;
  const std::string& format = header.format;
  std::string line;
  std::vector<std::vector<std::int64_t>> triangles;
  const auto strips = std::find_if(elements.begin(), elements.end(),
                                   [](const Element& e) { return e.name == "tristrips"; });
  if (strips == elements.end()) return triangles;
  const auto fail = [&](const std::string& what) {
    throw InputError(path + ": " + what + " (PLY element 'tristrips') — fix: re-export the mesh");
  };
  const auto size_of = [&](const std::string& t) -> int {
    if (t == "char" || t == "uchar" || t == "int8" || t == "uint8") return 1;
    if (t == "short" || t == "ushort" || t == "int16" || t == "uint16") return 2;
    if (t == "int" || t == "uint" || t == "float" || t == "int32" || t == "uint32" ||
        t == "float32")
      return 4;
    if (t == "double" || t == "float64") return 8;
    fail("unknown property type '" + t.substr(0, 16) + "'");
    return 0;
  };
  const bool ascii = format == "ascii";
  const bool swap = format == "binary_big_endian";
  // One binary value of type t as a double.
  const auto binary = [&](const std::string& t) {
    unsigned char b[8] = {};
    const int n = size_of(t);
    if (!in.read(reinterpret_cast<char*>(b), n)) fail("the file ends inside an element");
    if (swap) std::reverse(b, b + n);
    const bool is_signed = t[0] != 'u';
    const bool real = t.find("float") == 0 || t == "double";
    if (real) {
      if (n == 4) {
        float f;
        std::memcpy(&f, b, 4);
        return double(f);
      }
      double d;
      std::memcpy(&d, b, 8);
      return d;
    }
    std::uint64_t u = 0;
    std::memcpy(&u, b, static_cast<std::size_t>(n));
    if (is_signed && n < 8 && (u >> (8 * n - 1)) & 1) u |= ~std::uint64_t{0} << (8 * n);
    return is_signed ? double(static_cast<std::int64_t>(u)) : double(u);
  };
  std::istringstream row;
  const auto value = [&](const std::string& t) {
    if (!ascii) return binary(t);
    double v = 0;
    if (!(row >> v)) fail("a line ends early");
    return v;
  };
  for (const Element& e : elements) {
    const bool wanted = &e == &*strips;
    for (long long i = 0; i < e.count; ++i) {
      if (ascii) {
        do {
          if (!std::getline(in, line)) fail("the file ends before its last element");
        } while (words(line, 1).empty());
        row.clear();
        row.str(line);
      }
      for (const Property& p : e.properties) {
        if (p.count_type.empty()) {
          value(p.type);
          continue;
        }
        const double n = value(p.count_type);
        if (!(n >= 0) || n > 1e9) fail("a list announces " + std::to_string(n) + " entries");
        std::vector<std::int64_t> strip;
        const auto emit = [&] {  // the triangles of the strip so far
          for (std::size_t k = 0; k + 2 < strip.size(); ++k) {
            std::vector<std::int64_t> t = {strip[k], strip[k + 1], strip[k + 2]};
            if (k % 2 == 1) std::swap(t[0], t[1]);
            if (t[0] != t[1] && t[1] != t[2] && t[0] != t[2]) triangles.push_back(t);
          }
          strip.clear();
        };
        for (long long k = 0; k < static_cast<long long>(n); ++k) {
          const auto v = static_cast<std::int64_t>(value(p.type));
          if (!wanted) continue;
          if (v >= 0) strip.push_back(v);
          if (v < 0) emit();  // -1: the next strip starts
        }
        if (wanted) emit();
      }
    }
    if (wanted) break;
  }
  return triangles;
}

}  // namespace

const std::vector<std::string>& supported_surface_extensions() {
  static const std::vector<std::string> exts = {".obj", ".off", ".ply", ".stl"};
  return exts;
}

PolygonSoup read_polygon_soup(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::exists(path, ec)) throw InputError(path + ": no such file; check the path");
  if (fs::is_directory(path, ec))
    throw InputError(path + ": is a directory, not a surface mesh file");
  const std::string ext = lower_extension(path);
  const auto& exts = supported_surface_extensions();
  if (std::find(exts.begin(), exts.end(), ext) == exts.end())
    throw InputError(path + ": unknown surface format '" + ext + "'; use .obj, .off, .ply or .stl");
  const std::uintmax_t size = fs::file_size(path, ec);
  if (ec) throw InputError(path + ": cannot read (" + ec.message() + ")");
  if (size == 0) throw InputError(path + ": the file is empty (0 bytes)");
  {
    std::ifstream probe(path, std::ios::binary);
    if (!probe) throw InputError(path + ": cannot open for reading; check its permissions");
  }
  if (ext == ".stl") {
    const std::string problem = check_stl_size(path, size);
    if (!problem.empty()) throw InputError(path + ": " + problem);
  }
  if (ext == ".off") check_off_structure(path, size);
  const PlyHeader ply = ext == ".ply" ? read_ply_header(path, size) : PlyHeader{};
  if (ext == ".obj") check_obj_indices(path);

  PolygonSoup soup;
  SoupImporter importer(soup);
  om::IO::Options opt;
  bool ok = false;
  std::string log;
  {
    CaptureOpenMeshLog capture;
    ok = om::IO::IOManager().read(path, importer, opt);
    log = capture.text();
  }
  if (ok && ext == ".ply" && soup.polygons.empty()) {
    soup.polygons = read_ply_tristrips(path, ply);  // OpenMesh skips that element
    if (!soup.polygons.empty()) log.clear();        // its complaint was about the tristrips
  }
  if (ok && ext == ".ply") {  // OpenMesh stops quietly where a file ends early
    const long long vertices = ply.count("vertex"), faces = ply.count("face");
    if (vertices > static_cast<long long>(soup.points.size()) ||
        faces > static_cast<long long>(soup.polygons.size()))
      throw InputError(path + ": truncated: the header announces " + std::to_string(vertices) +
                       " vertices and " + std::to_string(std::max(faces, 0LL)) +
                       " faces, the file holds " + std::to_string(soup.points.size()) + " and " +
                       std::to_string(soup.polygons.size()) + " — fix: re-export the mesh");
  }
  const std::string detail = log.empty() ? "" : " (OpenMesh: " + log + ")";
  if (!ok)
    throw InputError(path + ": not a readable " + ext.substr(1) + " file" + detail +
                     "; check that it is a complete, uncorrupted mesh file");
  if (ext == ".obj" || ext == ".off") {
    // Keep the file's double-precision coordinates and name unparsable ones.
    AsciiVertices exact = scan_ascii_vertices(path, ext);
    if (!exact.bad.empty()) {
      std::string list;
      for (const std::string& b : exact.bad) list += (list.empty() ? "" : "; ") + b;
      throw InputError(path + ": NaN/Inf or unreadable vertex coordinates, first: " + list +
                       " — fix: re-export the mesh with finite coordinates");
    }
    if (exact.parsed && exact.points.size() == soup.points.size()) soup.points = exact.points;
  }
  if (soup.polygons.empty())
    throw InputError(path + ": holds no faces (" + std::to_string(soup.points.size()) +
                     " vertices)" + detail + "; vdb_shell needs a closed triangle surface");
  return soup;
}

}  // namespace vdb_shell
