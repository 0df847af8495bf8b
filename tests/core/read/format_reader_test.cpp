// format_reader_test.cpp — the surface readers (core/read/read_*.cpp) on every variant of their
// formats, checked against the tetrahedron each file spells out, and on the inputs the fuzz
// targets once found (tests/fuzz/regressions).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "core/base/errors.h"
#include "core/read/load_surface.h"
#include "core/read/polygon_soup.h"

namespace vdb_shell {
namespace {

// A tetrahedron with corners 0, 2x, 2y, 2z, outward faces (0-based).
const double kCorners[4][3] = {{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {0, 0, 2}};
const int kFaces[4][3] = {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {2, 0, 3}};

/// The message of the InputError parsing `bytes` as `ext` throws ("" when it parses).
std::string parse_error(const std::string& bytes, const std::string& ext) {
  try {
    parse_polygon_soup(bytes, ext, "t" + ext);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

bool contains(const std::string& s, const std::string& part) {
  return s.find(part) != std::string::npos;
}

/// `soup` is the tetrahedron: its corners (in any order, welded or not) and an enclosed volume
/// of 8/6, computed here from the polygons.
void expect_tetrahedron(const PolygonSoup& soup, const std::string& what) {
  ASSERT_EQ(soup.polygons.size(), 4u) << what;
  double volume = 0;
  for (const auto& f : soup.polygons) {
    ASSERT_EQ(f.size(), 3u) << what;
    const Vec3d& a = soup.points.at(static_cast<std::size_t>(f[0]));
    const Vec3d& b = soup.points.at(static_cast<std::size_t>(f[1]));
    const Vec3d& c = soup.points.at(static_cast<std::size_t>(f[2]));
    volume += dot(a, cross(b, c)) / 6.0;
  }
  EXPECT_NEAR(volume, 8.0 / 6.0, 1e-12) << what;
}

std::string big_endian(const void* p, std::size_t n) {
  std::string s(static_cast<const char*>(p), n);
  std::reverse(s.begin(), s.end());
  return s;
}

TEST(Readers, OffVariants) {
  std::string body;
  for (const auto& c : kCorners)
    body += std::to_string(c[0]) + " " + std::to_string(c[1]) + " " + std::to_string(c[2]) + "\n";
  std::string faces;
  for (const auto& f : kFaces)
    faces += "3 " + std::to_string(f[0]) + " " + std::to_string(f[1]) + " " + std::to_string(f[2]) +
             " 255 0 0\n";  // with a colour
  expect_tetrahedron(parse_polygon_soup("OFF\n4 4 6\n" + body + faces, ".off", "t"), "OFF");
  expect_tetrahedron(parse_polygon_soup("nOFF\n3\n4 4 6\n" + body + faces, ".off", "t"), "nOFF");
  // 4OFF: homogeneous coordinates, every corner given with w = 2 at twice its size.
  std::string homogeneous;
  for (const auto& c : kCorners)
    homogeneous += std::to_string(2 * c[0]) + " " + std::to_string(2 * c[1]) + " " +
                   std::to_string(2 * c[2]) + " 2\n";
  expect_tetrahedron(parse_polygon_soup("4OFF\n4 4 6\n" + homogeneous + faces, ".off", "t"),
                     "4OFF");
  EXPECT_TRUE(contains(parse_error("nOFF\n4\n4 4 6\n" + body + faces, ".off"), "dimension is 4"));
  // Binary OFF: big-endian 32-bit counts, floats and face records (with 0 colour components).
  std::string binary = "OFF BINARY\n";
  const auto put_int = [&](std::int32_t i) { binary += big_endian(&i, 4); };
  const auto put_float = [&](float f) { binary += big_endian(&f, 4); };
  put_int(4);
  put_int(4);
  put_int(6);
  for (const auto& c : kCorners)
    for (const double v : c) put_float(static_cast<float>(v));
  for (const auto& f : kFaces) {
    put_int(3);
    for (const int i : f) put_int(i);
    put_int(0);
  }
  expect_tetrahedron(parse_polygon_soup(binary, ".off", "t"), "binary OFF");
  EXPECT_TRUE(contains(parse_error(binary.substr(0, binary.size() - 6), ".off"), "truncated"));
  std::string huge = binary;
  huge.replace(11, 4, big_endian("\x00\x00\x00\x7f", 4));  // 2^31 - 2^24 vertices
  EXPECT_TRUE(contains(parse_error(huge, ".off"), "more than the file's"))
      << parse_error(huge, ".off");
}

TEST(Readers, ObjCornersAndIgnoredLines) {
  std::string text = "# comment\nmtllib t.mtl\no tet\n";
  for (const auto& c : kCorners)
    text += "v " + std::to_string(c[0]) + " " + std::to_string(c[1]) + " " + std::to_string(c[2]) +
            " 1.0 0.5 0.5\n";  // a colour after the position
  text += "vt 0 0\nvn 0 0 1\ng side\nusemtl red\ns off\n";
  text += "f 1/1/1 3/1/1 2/1/1\nf 1//1 2//1 4//1\nf 2/1 3/1 4/1\nf -2 -4 -1\nl 1 2\n";
  expect_tetrahedron(parse_polygon_soup(text, ".obj", "t"), "OBJ");
  EXPECT_TRUE(contains(parse_error("v 0 0\nf 1 1 1\n", ".obj"), "vertex 0 (line 1)"));
  EXPECT_TRUE(contains(parse_error("v 0 0 1e999\nf 1 1 1\n", ".obj"), "NaN/Inf or unreadable"));
  EXPECT_TRUE(contains(parse_error("v 0 0 0\n", ".obj"), "holds no faces (1 vertices)"));
}

TEST(Readers, PlyTypesAndLayouts) {
  // Double coordinates and an int16 count / uint32 index list, big-endian, with extra vertex
  // properties before and after x y z.
  std::string ply =
      "ply\r\nformat binary_big_endian 1.0\r\ncomment made by hand\r\nelement vertex 4\r\n"
      "property uchar red\r\nproperty double x\r\nproperty double y\r\nproperty double z\r\n"
      "property float confidence\r\nelement face 4\r\nproperty int16 flags\r\n"
      "property list int16 uint32 vertex_index\r\nend_header\r\n";
  for (const auto& c : kCorners) {
    ply += '\x07';
    for (const double v : c) ply += big_endian(&v, 8);
    const float confidence = 0.5f;
    ply += big_endian(&confidence, 4);
  }
  for (const auto& f : kFaces) {
    const std::int16_t flags = -1, n = 3;
    ply += big_endian(&flags, 2) + big_endian(&n, 2);
    for (const int i : f) {
      const std::uint32_t u = static_cast<std::uint32_t>(i);
      ply += big_endian(&u, 4);
    }
  }
  expect_tetrahedron(parse_polygon_soup(ply, ".ply", "t"), "binary PLY");
  EXPECT_TRUE(contains(parse_error(ply.substr(0, ply.size() - 3), ".ply"),
                       "truncated: the header announces 4 vertices and 4 faces, the file ends "
                       "inside element 'face' 3"));
  std::string no_z = ply;
  no_z.replace(no_z.find("property double z"), 17, "property double w");
  EXPECT_TRUE(contains(parse_error(no_z, ".ply"), "no scalar property 'z'"));
  // The first face's count (big-endian int16 after 4 vertices of 29 bytes and its flags) made
  // 0x7503 = 29955: more indices than the file holds.
  std::string long_list = ply;
  const std::size_t body = long_list.find("end_header\r\n") + 12;
  long_list[body + 4 * 29 + 2] = '\x75';
  EXPECT_TRUE(contains(parse_error(long_list, ".ply"), "announces 29955 entries"))
      << parse_error(long_list, ".ply");
  EXPECT_TRUE(contains(parse_error("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
                                   "property list float int i\nend_header\n",
                                   ".ply"),
                       "not a property of a known type"));
}

TEST(Readers, StlWeldsCornersAndNamesBrokenFacets) {
  std::string ascii = "solid tet\n";
  for (const auto& f : kFaces) {
    ascii += "  facet normal 0 0 0\n    outer loop\n";
    for (const int i : f)
      ascii += "      vertex " + std::to_string(kCorners[i][0]) + " " +
               std::to_string(kCorners[i][1]) + " " + std::to_string(kCorners[i][2]) + "\n";
    ascii += "    endloop\n  endfacet\n";
  }
  ascii += "endsolid tet\n";
  const PolygonSoup soup = parse_polygon_soup(ascii, ".stl", "t");
  EXPECT_EQ(soup.points.size(), 4u);  // 12 corners welded by position
  expect_tetrahedron(soup, "ASCII STL");
  // Upper-case keywords, as some exporters write, read the same.
  std::string upper = ascii;
  for (char& c : upper) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  expect_tetrahedron(parse_polygon_soup(upper, ".stl", "t"), "upper-case STL");
  EXPECT_TRUE(contains(parse_error(ascii.substr(0, ascii.size() / 2), ".stl"), "truncated"));
  EXPECT_TRUE(
      contains(parse_error(ascii.substr(0, ascii.rfind("endsolid")), ".stl"), "before 'endsolid'"));
  std::string two = ascii;
  two.erase(two.find("      vertex 0"),
            two.find('\n', two.find("      vertex 0")) + 1 - two.find("      vertex 0"));
  EXPECT_TRUE(contains(parse_error(two, ".stl"), "facet 0 has 2 vertices, a facet needs 3"));
  std::string word = ascii;
  word.replace(word.find("outer loop"), 10, "outer lop");
  EXPECT_TRUE(contains(parse_error(word, ".stl"), "'outer' without 'loop' (line 3)"));
  EXPECT_TRUE(contains(parse_error("xyz", ".stl"), "3 bytes, less than the 84-byte header"));
}

TEST(Readers, EveryFuzzFindingIsBadInputOrASurface) {
  // Each file under tests/fuzz/regressions/<surface format>/ once crashed, hung or exhausted memory
  // in a reader; now each must give a surface or an InputError (a hang meets ctest's timeout).
  const std::filesystem::path root = VDB_SHELL_FUZZ_REGRESSIONS;
  ASSERT_TRUE(std::filesystem::is_directory(root)) << root;
  std::size_t files = 0;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(root)) {
    const std::string ext = "." + entry.path().parent_path().filename().string();
    if (!entry.is_regular_file() || ext == ".vdb") continue;  // .vdb: tests/vdb_ops
    std::ifstream in(entry.path(), std::ios::binary);
    std::stringstream bytes;
    bytes << in.rdbuf();
    try {
      make_surface(parse_polygon_soup(bytes.str(), ext, entry.path().string()), "t");
    } catch (const InputError&) {
    }
    ++files;
  }
  EXPECT_GT(files, 0u);
}

}  // namespace
}  // namespace vdb_shell
