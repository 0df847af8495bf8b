// test_support_test.cpp — the suite's own checks of a shell (tests/test_support.h): each problem
// independent_shell_problems() names is caught on a shell broken that one way, a valid shell
// passes, independent_coverage() has its analytic value, and read_tetgen_shell() reads back what
// write_tet_mesh() wrote. The other tests rely on these checks being able to fail.
#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <utility>

#include "assets/shapes.h"
#include "core/assemble/assemble.h"
#include "core/base/surface_mesh.h"
#include "core/base/tet_mesh.h"
#include "core/write/shell_writers.h"
#include "tests/test_support.h"

namespace vdb_shell {
namespace {

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

/// The shell between `s` (centred on the origin) and its copy scaled by `factor`.
TetMesh scaled_shell(const SurfaceMesh& s, double factor) {
  ShellInput in;
  for (std::size_t v = 0; v < s.points.size(); ++v) {
    in.inner_points.push_back(s.points[v] * factor);
    in.inner_id.push_back(static_cast<std::uint32_t>(v));
  }
  return assemble_shell(s, in).mesh;
}

/// One tet per face of `s`, all to the origin.
TetMesh centre_shell(const SurfaceMesh& s) {
  ShellInput in;
  in.inner_points = {Vec3d{0, 0, 0}};
  in.inner_id.assign(s.points.size(), 0);
  return assemble_shell(s, in).mesh;
}

TEST(TestSupport, ValidShellsPass) {
  const SurfaceMesh box = make_shape("box", 1), sphere = make_shape("sphere", 1);
  EXPECT_EQ(test::independent_shell_problems(box, scaled_shell(box, 0.5)), "");
  EXPECT_EQ(test::independent_shell_problems(box, centre_shell(box)), "");
  EXPECT_EQ(test::independent_shell_problems(sphere, scaled_shell(sphere, 0.7)), "");
}

TEST(TestSupport, EachProblemIsCaught) {
  const SurfaceMesh box = make_shape("box", 1);
  {
    TetMesh m = scaled_shell(box, 0.5);
    m.points[3].x += 1e-3;
    EXPECT_TRUE(contains(test::independent_shell_problems(box, m), "surface point 3 moved"));
  }
  {
    TetMesh m = centre_shell(box);
    while (m.tets.size() <= 3 * box.triangles.size()) m.tets.push_back(m.tets[0]);
    EXPECT_TRUE(contains(test::independent_shell_problems(box, m), "T > 3F"));
  }
  {
    TetMesh m = scaled_shell(box, 0.5);
    std::swap(m.tets[4][0], m.tets[4][1]);
    EXPECT_TRUE(contains(test::independent_shell_problems(box, m), "tet 4 has signed volume"));
  }
  {
    // A surface triangle without its tet.
    TetMesh m = centre_shell(box);
    m.tets.erase(m.tets.begin() + 2);
    EXPECT_TRUE(contains(test::independent_shell_problems(box, m), "not the outward face"));
  }
  {
    // A second tet on the inner side of a surface triangle, apex halfway to the centre.
    TetMesh m = centre_shell(box);
    const Triangle& f = box.triangles[m.source_triangle[0]];
    const Vec3d mid = (m.points[f[0]] + m.points[f[1]] + m.points[f[2]]) / 3.0;
    m.points.push_back(mid * 0.5);
    Tet extra = {f[0], f[1], f[2], static_cast<std::uint32_t>(m.points.size() - 1)};
    if (tet_volume(m.points[f[0]], m.points[f[1]], m.points[f[2]], m.points.back()) < 0)
      std::swap(extra[0], extra[1]);
    m.tets.push_back(extra);
    const std::string p = test::independent_shell_problems(box, m);
    EXPECT_TRUE(contains(p, "on the same side")) << p;
  }
  {
    // A small tet inside another, sharing none of its faces: only the overlap test sees it.
    TetMesh m = centre_shell(box);
    const Tet t = m.tets[0];
    Vec3d c;
    for (std::uint32_t i : t) c += m.points[i] * 0.25;
    const auto base = static_cast<std::uint32_t>(m.points.size());
    for (std::uint32_t i : t) m.points.push_back(c + (m.points[i] - c) * 0.1);
    m.tets.push_back({base, base + 1, base + 2, base + 3});
    const std::string p = test::independent_shell_problems(box, m);
    EXPECT_TRUE(contains(p, "tets 0 and 48 overlap")) << p;
  }
  {
    // A point beyond the surface points outside the surface.
    TetMesh m = centre_shell(box);
    m.points.push_back({2, 0, 0});
    EXPECT_TRUE(contains(test::independent_shell_problems(box, m), "lies outside the surface"));
  }
}

TEST(TestSupport, CoverageOfAHalvedCube) {
  // Cube [-0.5, 0.5]^3, inner cube half as large: 1 - 1/8.
  const SurfaceMesh box = make_shape("box", 2);
  EXPECT_NEAR(test::independent_coverage(box, scaled_shell(box, 0.5)), 0.875, 1e-12);
  EXPECT_NEAR(test::independent_coverage(box, centre_shell(box)), 1.0, 1e-12);
  EXPECT_EQ(test::independent_coverage(SurfaceMesh{}, TetMesh{}), 0.0);
}

TEST(TestSupport, TetGenShellReadsBack) {
  const SurfaceMesh sphere = make_shape("sphere", 1);
  const TetMesh m = scaled_shell(sphere, 0.6);
  test::TempDir dir;
  write_tet_mesh(dir.file("s.ele"), m, TetFormat::TetGen);
  const TetMesh back = test::read_tetgen_shell(dir.file("s.ele"));
  EXPECT_EQ(back.points, m.points);
  EXPECT_EQ(back.tets, m.tets);
  EXPECT_THROW(test::read_tetgen_shell(dir.file("missing.ele")), std::runtime_error);
}

}  // namespace
}  // namespace vdb_shell
