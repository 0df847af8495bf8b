// --optimize (core/validity/optimize.h) end to end: the optimised shell is valid by the
// independent checks, keeps the thickness limits and its coverage, never lowers the smallest
// quality or dihedral angle, raises the 5th percentile, and is the same for any thread count.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
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
  for (const char* name : {"star", "horn", "propeller", "torus"}) {
    const SurfaceMesh surface = make_shape(name);
    const ShellResult plain = shell(surface, false), opt = shell(surface, true);
    ASSERT_EQ(test::independent_shell_problems(opt.surface, opt.mesh, 2 * opt.validity.sectors), "")
        << name;
    EXPECT_EQ(opt.mesh.tets, plain.mesh.tets) << name;  // the same tets, moved corners only
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
}

TEST(Optimize, KeepsTheThicknessLimitAndIsDeterministic) {
  const SurfaceMesh surface = make_shape("star");
  const double limit = 0.06;
  const ShellResult one = shell(surface, true, 1, limit), two = shell(surface, true, 2, limit);
  ASSERT_GT(one.optimize.report.moved_vertices, 0u);
  EXPECT_EQ(one.mesh.points, two.mesh.points);
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

TEST(Optimize, OffByDefaultAndReported) {
  EXPECT_FALSE(ShellOptions().optimize.enabled);
  const ShellResult r = shell(make_shape("horn"), true);
  const std::string report = report_json(r);
  EXPECT_NE(report.find("\"optimize\": {\n    \"enabled\": true"), std::string::npos) << report;
  EXPECT_GT(r.quality.p5_quality, r.optimize.p5_quality_before);
}

}  // namespace
}  // namespace vdb_shell
