// --optimize (core/validity/optimize.h) end to end: the optimised shell is valid by the
// independent checks, keeps its prisms (recut ones still meeting face to face), the thickness
// limits and its coverage, never lowers the smallest quality or dihedral angle, raises the 5th
// percentile, and is the same for any thread count.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "assets/shapes.h"
#include "tests/test_support.h"
#include "vdb_shell/vdb_shell.h"

namespace vdb_shell {
namespace {

/// Volume-length ratio and smallest dihedral angle of every tet, computed here.
struct Measures {
  std::vector<double> quality, dihedral;
};
Measures measures(const TetMesh& m) {
  Measures out;
  for (const Tet& t : m.tets) {
    const Vec3d p[4] = {m.points[t[0]], m.points[t[1]], m.points[t[2]], m.points[t[3]]};
    out.quality.push_back(test::independent_quality(m, t));
    double smallest = 180;
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j) {  // the edge (i, j) between the faces without k and l
        int k = 0;
        while (k == i || k == j) ++k;
        int l = k + 1;
        while (l == i || l == j) ++l;
        const Vec3d e = normalized(p[j] - p[i]);
        Vec3d a = p[k] - p[i], b = p[l] - p[i];
        a -= e * dot(a, e);
        b -= e * dot(b, e);
        smallest =
            std::min(smallest, std::acos(std::clamp(dot(normalized(a), normalized(b)), -1.0, 1.0)) *
                                   180 / kPi);
      }
    out.dihedral.push_back(smallest);
  }
  return out;
}

/// How many tet faces (vertex triples) occur once, and whether none occurs more than twice.
std::pair<std::size_t, bool> unshared_faces(const TetMesh& m) {
  std::map<std::array<std::uint32_t, 3>, int> count;
  for (const Tet& t : m.tets)
    for (int skip = 0; skip < 4; ++skip) {
      std::array<std::uint32_t, 3> f;
      for (int k = 0, j = 0; k < 4; ++k)
        if (k != skip) f[j++] = t[k];
      std::sort(f.begin(), f.end());
      ++count[f];
    }
  std::size_t once = 0;
  bool at_most_twice = true;
  for (const auto& [face, c] : count) once += c == 1, at_most_twice = at_most_twice && c <= 2;
  return {once, at_most_twice};
}

double at_rank(std::vector<double> v, double fraction) {
  std::sort(v.begin(), v.end());
  return v[std::size_t(fraction * v.size())];
}

ShellResult shell(const SurfaceMesh& surface, bool optimize, int threads = 0,
                  double max_thickness = 0) {
  ShellOptions o;
  o.fields.resolution = 64;
  o.optimize.enabled = optimize;
  o.threads = threads;
  o.thickness.max_thickness = max_thickness;
  return build_shell(surface, o);
}

TEST(Optimize, ValidThickAndNeverWorseAtItsWorst) {
  int recut = 0;  // shapes with some prism cut otherwise
  for (const char* name : {"star", "horn", "propeller", "torus"}) {
    const SurfaceMesh surface = make_shape(name);
    const ShellResult plain = shell(surface, false), opt = shell(surface, true);
    ASSERT_EQ(test::independent_shell_problems(opt.surface, opt.mesh, 2 * opt.validity.sectors), "")
        << name;
    // The same prisms, some cut otherwise: as many tets of each triangle, on its prism's
    // corners, meeting face to face (an unshared face more would be a quad cut two ways).
    ASSERT_EQ(opt.mesh.source_triangle, plain.mesh.source_triangle) << name;
    std::map<std::uint32_t, std::set<std::uint32_t>> corners;  // per triangle: its prism's
    for (std::size_t t = 0; t < plain.mesh.tets.size(); ++t)
      corners[plain.mesh.source_triangle[t]].insert(plain.mesh.tets[t].begin(),
                                                    plain.mesh.tets[t].end());
    for (std::size_t t = 0; t < opt.mesh.tets.size(); ++t)
      for (const std::uint32_t v : opt.mesh.tets[t])
        ASSERT_TRUE(corners[opt.mesh.source_triangle[t]].count(v)) << name << " tet " << t;
    recut += opt.mesh.tets != plain.mesh.tets;
    EXPECT_EQ(unshared_faces(opt.mesh), unshared_faces(plain.mesh)) << name;
    EXPECT_TRUE(unshared_faces(opt.mesh).second) << name;
    for (std::size_t v = 0; v < surface.points.size(); ++v)
      ASSERT_EQ(opt.mesh.points[v], plain.mesh.points[v]) << name;
    const Measures before = measures(plain.mesh), after = measures(opt.mesh);
    const auto smallest = [](const std::vector<double>& v) {
      return *std::min_element(v.begin(), v.end());
    };
    EXPECT_GE(smallest(after.quality), smallest(before.quality) * (1 - 1e-9)) << name;
    EXPECT_GE(smallest(after.dihedral), smallest(before.dihedral) * (1 - 1e-9)) << name;
    EXPECT_GT(at_rank(after.quality, 0.05), at_rank(before.quality, 0.05)) << name;
    EXPECT_GT(opt.optimize.report.moved_vertices, 0u) << name;
    EXPECT_GT(test::independent_coverage(opt.surface, opt.mesh),
              test::independent_coverage(plain.surface, plain.mesh) - 0.02)
        << name;
    // The inner surface shows the moved points (inner_surface's points are shell points).
    std::vector<Vec3d> points(opt.mesh.points.begin(), opt.mesh.points.end());
    const auto less = [](const Vec3d& a, const Vec3d& b) {
      return a.x != b.x ? a.x < b.x : a.y != b.y ? a.y < b.y : a.z < b.z;
    };
    std::sort(points.begin(), points.end(), less);
    for (const Vec3d& p : opt.inner_surface.points)
      ASSERT_TRUE(std::binary_search(points.begin(), points.end(), p, less)) << name;
  }
  EXPECT_GT(recut, 0);
}

TEST(Optimize, KeepsTheThicknessLimitAndIsDeterministic) {
  const SurfaceMesh surface = make_shape("star");
  const double limit = 0.06;
  const ShellResult one = shell(surface, true, 1, limit), two = shell(surface, true, 2, limit);
  ASSERT_GT(one.optimize.report.moved_vertices, 0u);
  EXPECT_EQ(one.mesh.points, two.mesh.points);
  EXPECT_EQ(one.mesh.tets, two.mesh.tets);
  // Every surface vertex is within the limit of its inner vertex: inner_surface triangle t is
  // surface triangle t reversed.
  const int corner[3] = {0, 2, 1};
  for (std::size_t t = 0; t < one.surface.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      const Vec3d& s = one.surface.points[one.surface.triangles[t][k]];
      const Vec3d& in = one.inner_surface.points[one.inner_surface.triangles[t][corner[k]]];
      ASSERT_LE(distance(s, in), limit * (1 + 1e-12)) << t;
    }
}

TEST(Optimize, OnByDefaultAndReported) {
  EXPECT_TRUE(ShellOptions().optimize.enabled);
  const ShellResult r = shell(make_shape("horn"), true), off = shell(make_shape("horn"), false);
  const std::string report = report_json(r);
  EXPECT_NE(report.find("\"optimize\": {\n    \"enabled\": true"), std::string::npos) << report;
  EXPECT_NE(report_json(off).find("\"optimize\": {\n    \"enabled\": false"), std::string::npos);
  EXPECT_GT(r.quality.p5_quality, r.optimize.p5_quality_before);
  EXPECT_EQ(r.optimize.p5_quality_before, off.quality.p5_quality);
}

}  // namespace
}  // namespace vdb_shell
