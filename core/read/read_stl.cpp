// read_stl.cpp — STL, binary (an 80-byte header, a triangle count, 50 bytes a triangle) or ASCII
// (solid / facet normal / outer loop / vertex ... / endloop / endfacet / endsolid). A file is
// binary when its size is exactly what its count announces, else ASCII when it starts with
// "solid". Corners are welded by exact position, in order of first appearance.
#include <algorithm>
#include <cctype>
#include <cstring>
#include <string>

#include "core/read/format_reader.h"

namespace vdb_shell::read_detail {
namespace {

const char* const kFix = "re-export the mesh (a complete STL file)";

bool same_word(std::string_view word, const char* keyword) {
  const std::size_t n = std::strlen(keyword);
  if (word.size() != n) return false;
  for (std::size_t i = 0; i < n; ++i)
    if (std::tolower(static_cast<unsigned char>(word[i])) != keyword[i]) return false;
  return true;
}

float little_float(const char* p) {
  const auto* b = reinterpret_cast<const unsigned char*>(p);
  const std::uint32_t w = std::uint32_t(b[0]) | std::uint32_t(b[1]) << 8 |
                          std::uint32_t(b[2]) << 16 | std::uint32_t(b[3]) << 24;
  float f;
  std::memcpy(&f, &w, 4);
  return f;
}

PolygonSoup read_binary_stl(std::string_view bytes, std::uint32_t n, const std::string& name) {
  PolygonSoup soup;
  PositionWelder weld(soup.points);
  BadCoordinates bad;
  soup.polygons.reserve(n);
  for (std::uint32_t t = 0; t < n; ++t) {
    const char* facet = bytes.data() + 84 + 50 * std::size_t(t);
    std::vector<std::int64_t> triangle(3);
    for (int c = 0; c < 3; ++c) {
      Vec3d p;
      for (int k = 0; k < 3; ++k) p[k] = little_float(facet + 12 + 12 * c + 4 * k);
      bad.check(true, p, "triangle " + std::to_string(t) + " corner " + std::to_string(c),
                "binary");
      triangle[static_cast<std::size_t>(c)] = weld.index(p);
    }
    soup.polygons.push_back(std::move(triangle));
  }
  bad.throw_if_any(name);
  return soup;
}

PolygonSoup read_ascii_stl(std::string_view bytes, const std::string& name,
                           const std::string& not_binary) {
  PolygonSoup soup;
  PositionWelder weld(soup.points);
  BadCoordinates bad;
  Tokens tokens(bytes);
  std::string_view word;
  const auto fail_at = [&](const std::string& what) {
    fail(name, what + " (line " + std::to_string(tokens.line_no()) + ")" + not_binary, kFix);
  };
  const auto number = [&](double& v) {
    if (!tokens.next(word))
      fail_at("truncated: the file ends inside facet " + std::to_string(soup.polygons.size()));
    return parse_number(word, v);
  };
  std::vector<std::int64_t> loop;
  bool in_loop = false, in_solid = false;
  while (tokens.next(word)) {
    const std::string facet = "facet " + std::to_string(soup.polygons.size());
    if (same_word(word, "solid")) {
      if (in_solid) fail_at("'solid' inside a solid");
      in_solid = true;
      tokens.skip_line();  // the solid's name
    } else if (!in_solid) {
      fail_at("not an ASCII STL: " + quoted(word) + " where 'solid' starts the file");
    } else if (same_word(word, "endsolid")) {
      if (in_loop) fail_at(facet + " has no 'endloop'");
      in_solid = false;
      tokens.skip_line();
    } else if (same_word(word, "facet")) {
      if (in_loop) fail_at(facet + " has no 'endloop'");
      double n[3];
      if (!tokens.next(word) || !same_word(word, "normal"))
        fail_at(facet + ": 'facet' without 'normal'");
      for (double& v : n)
        if (!number(v)) fail_at(facet + ": unreadable normal " + quoted(word));
    } else if (same_word(word, "outer")) {
      if (!tokens.next(word) || !same_word(word, "loop"))
        fail_at(facet + ": 'outer' without 'loop'");
      if (in_loop) fail_at(facet + " has no 'endloop'");
      in_loop = true;
      loop.clear();
    } else if (same_word(word, "vertex")) {
      if (!in_loop) fail_at(facet + ": 'vertex' outside 'outer loop'");
      Vec3d p;
      bool readable = true;
      std::string text;
      for (int k = 0; k < 3; ++k) {
        readable = number(p[k]) && readable;
        text += (k ? " " : "") + std::string(word);
      }
      bad.check(readable, p, facet + " (line " + std::to_string(tokens.line_no()) + ")", text);
      loop.push_back(weld.index(p));
    } else if (same_word(word, "endloop")) {
      if (!in_loop) fail_at(facet + ": 'endloop' without 'outer loop'");
      if (loop.size() < 3)
        fail_at(facet + " has " + std::to_string(loop.size()) + " vertices, a facet needs 3");
      in_loop = false;
      soup.polygons.push_back(loop);
    } else if (same_word(word, "endfacet")) {
      if (in_loop) fail_at(facet + " has no 'endloop'");
    } else {
      fail_at("unexpected " + quoted(word) +
              " (an ASCII STL has solid, facet normal, outer loop, vertex, endloop, endfacet, "
              "endsolid)");
    }
  }
  if (in_loop || in_solid)
    fail_at("truncated: the file ends inside " +
            (in_loop ? "facet " + std::to_string(soup.polygons.size()) : std::string("a solid")) +
            ", before 'endsolid'");
  bad.throw_if_any(name);
  return soup;
}

}  // namespace

PolygonSoup read_stl(std::string_view bytes, const std::string& name) {
  std::uint32_t n = 0;
  if (bytes.size() >= 84) std::memcpy(&n, bytes.data() + 80, 4);  // little-endian hosts
  const std::uintmax_t want = 84 + 50ull * n;
  if (bytes.size() >= 84 && bytes.size() == want) return read_binary_stl(bytes, n, name);
  const std::size_t first = std::min(bytes.size(), bytes.find_first_not_of(" \t\r\n"));
  const bool ascii = same_word(bytes.substr(first, 5), "solid");
  const std::string as_binary =
      bytes.size() < 84
          ? std::to_string(bytes.size()) + " bytes, less than the 84-byte header"
          : "its header announces " + std::to_string(n) + " triangles (" + std::to_string(want) +
                " bytes) but the file has " + std::to_string(bytes.size()) + " bytes";
  if (!ascii) fail(name, "binary STL is truncated or corrupt: " + as_binary, kFix);
  // A binary STL whose header starts with "solid" fails as ASCII: say what it is as binary too.
  const bool has_nul = bytes.find('\0') != std::string_view::npos;
  return read_ascii_stl(bytes, name, has_nul ? "; as a binary STL, " + as_binary : "");
}

}  // namespace vdb_shell::read_detail
