#include "core/render/sections.h"

#include <gtest/gtest.h>

#include <cmath>
#include <regex>
#include <string>
#include <vector>

#include "assets/shapes.h"
#include "core/base/tet_faces.h"
#include "core/render/raster.h"

namespace vdb_shell {
namespace {

/// The unit cube [0, 1]^3 as six tets around its diagonal (0 -> 7, vertex x + 2y + 4z) and its
/// boundary as the surface: the tets fill exactly what the surface encloses.
struct Cube {
  SurfaceMesh surface;
  TetMesh mesh;
};
Cube kuhn_cube() {
  Cube c;
  for (int v = 0; v < 8; ++v)
    c.mesh.points.push_back({double(v & 1), double(v >> 1 & 1), double(v >> 2)});
  const int axes[6][3] = {{1, 2, 4}, {1, 4, 2}, {2, 1, 4}, {2, 4, 1}, {4, 1, 2}, {4, 2, 1}};
  for (const auto& a : axes) {
    Tet t = {0, std::uint32_t(a[0]), std::uint32_t(a[0] + a[1]), 7};
    if (tet_volume(c.mesh.points[t[0]], c.mesh.points[t[1]], c.mesh.points[t[2]],
                   c.mesh.points[t[3]]) < 0)
      std::swap(t[2], t[3]);
    c.mesh.tets.push_back(t);
    c.mesh.quality.push_back(0.93);
  }
  const FaceRecords faces = sorted_tet_faces(c.mesh);
  for (std::size_t i = 0; i < faces.size(); ++i) {
    const bool alone = (i == 0 || !faces[i].same_key(faces[i - 1])) &&
                       (i + 1 == faces.size() || !faces[i].same_key(faces[i + 1]));
    if (!alone) continue;
    const int* f = kTetOutwardFace[faces[i].face];
    const Tet& t = c.mesh.tets[faces[i].tet];
    c.surface.triangles.push_back({t[f[0]], t[f[1]], t[f[2]]});
  }
  c.surface.points = c.mesh.points;
  return c;
}

/// The polygons of the `d` attributes of the <path>s whose fill is `fill`, in SVG units.
std::vector<std::vector<std::pair<double, double>>> polygons(const std::string& svg,
                                                             const std::string& fill) {
  std::vector<std::vector<std::pair<double, double>>> out;
  const std::regex path("<path fill=\"" + fill + "\"[^>]* d=\"([^\"]*)\"");
  const std::regex point("([ML])([-0-9.]+) ([-0-9.]+)");
  for (auto p = std::sregex_iterator(svg.begin(), svg.end(), path); p != std::sregex_iterator();
       ++p) {
    const std::string d = (*p)[1].str();
    for (auto q = std::sregex_iterator(d.begin(), d.end(), point); q != std::sregex_iterator();
         ++q) {
      if ((*q)[1] == "M") out.emplace_back();
      out.back().push_back({std::stod((*q)[2]), std::stod((*q)[3])});
    }
  }
  return out;
}

double area(const std::vector<std::pair<double, double>>& poly) {
  double a = 0;
  for (std::size_t i = 0; i < poly.size(); ++i) {
    const auto& p = poly[i];
    const auto& q = poly[(i + 1) % poly.size()];
    a += p.first * q.second - q.first * p.second;
  }
  return std::fabs(0.5 * a);
}

TEST(Sections, TetsCutByThePlaneFillTheOutlineOfACube) {
  const Cube cube = kuhn_cube();
  const BBox box = bounding_box(cube.surface);
  for (int axis = 0; axis < 3; ++axis) {
    const std::string svg = section_svg(cube.surface, cube.mesh, axis, 0.37, box, 412, 300);
    // The frame is the unit square fitted into 412 x 300 with 6 units of margin: 288 per unit.
    EXPECT_NE(svg.find("width=\"300\" height=\"300\""), std::string::npos) << svg.substr(0, 120);
    const auto outline = polygons(svg, kUncoveredColour);
    ASSERT_EQ(outline.size(), 1u) << axis;
    EXPECT_NEAR(area(outline[0]), 288.0 * 288.0, 60.0) << axis;
    const auto tets = polygons(svg, hex(ColourMap::quality()(0.925)));  // class of Q = 0.93
    EXPECT_EQ(tets.size(), 6u) << axis;  // every tet spans z = 0.37 (each joins 0 and 7)
    double sum = 0;
    for (const auto& t : tets) sum += area(t);
    EXPECT_NEAR(sum, 288.0 * 288.0, 150.0) << axis;
  }
  // A plane through a face of the cube (vertices on it count as above): nothing cut.
  const std::string at_face = section_svg(cube.surface, cube.mesh, 2, 0.0, box, 300, 300);
  EXPECT_TRUE(polygons(at_face, kUncoveredColour).empty());
  EXPECT_TRUE(polygons(at_face, hex(ColourMap::quality()(0.925))).empty());
}

TEST(Sections, ATorusCutAcrossItsRingHasTwoLoops) {
  const SurfaceMesh torus = make_shape("torus", 2);  // radii 0.35 and 0.15, around z
  const BBox box = bounding_box(torus);
  const std::string svg = section_svg(torus, TetMesh{}, 0, 0.0, box, 500, 500);
  const auto loops = polygons(svg, kUncoveredColour);
  ASSERT_EQ(loops.size(), 2u);
  const double scale = (500 - 12) / box.extent().y;
  for (const auto& loop : loops)
    EXPECT_NEAR(area(loop) / (scale * scale), kPi * 0.15 * 0.15, 0.03 * kPi * 0.15 * 0.15);
  // Cut along the ring (z = 0): an annulus, two nested loops (even-odd fill leaves the hole).
  const auto annulus =
      polygons(section_svg(torus, TetMesh{}, 2, 0.0, box, 500, 500), kUncoveredColour);
  EXPECT_EQ(annulus.size(), 2u);
}

}  // namespace
}  // namespace vdb_shell
