// quality_test.cpp — tet_quality(), tet_min_dihedral_deg() and summarize_quality()
// (core/assemble/quality.h) against their analytic values: the regular tet, a flat tet, the
// unit cube's corner tet, the coverage of a cube shell, the histogram and its statistics.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <random>
#include <vector>

#include "assets/shapes.h"
#include "core/assemble/assemble.h"
#include "core/assemble/quality.h"
#include "core/base/vec3.h"

namespace vdb_shell {
namespace {

/// One inner vertex per vertex of a surface centred on the origin: the vertex halved.
ShellInput halved_input(const SurfaceMesh& s) {
  ShellInput in;
  for (std::size_t v = 0; v < s.points.size(); ++v) {
    in.inner_points.push_back(s.points[v] * 0.5);
    in.inner_id.push_back(static_cast<std::uint32_t>(v));
  }
  return in;
}

TEST(Quality, RegularTetIsOne) {
  const Vec3d a{1, 1, 1}, b{1, -1, -1}, c{-1, 1, -1}, d{-1, -1, 1};
  const double sign = tet_volume(a, b, c, d) > 0.0 ? 1.0 : -1.0;
  EXPECT_NEAR(tet_quality(a, b, c, d), sign, 1e-12);
  EXPECT_NEAR(tet_quality(a, b, d, c), -sign, 1e-12);
  const double regular_dihedral_deg = std::acos(1.0 / 3.0) * 180.0 / kPi;
  EXPECT_NEAR(tet_min_dihedral_deg(a, b, c, d), regular_dihedral_deg, 1e-9);
  // Scale and translation do not matter.
  const Vec3d o{10, -3, 7};
  EXPECT_NEAR(tet_quality(o + a * 1e-3, o + b * 1e-3, o + c * 1e-3, o + d * 1e-3), sign, 1e-9);
}

TEST(Quality, FlatTetIsZero) {
  const Vec3d a{0, 0, 0}, b{1, 0, 0}, c{0, 1, 0}, d{1, 1, 0};
  EXPECT_EQ(tet_quality(a, b, c, d), 0.0);
  EXPECT_EQ(tet_min_dihedral_deg(a, b, c, d), 0.0);
  EXPECT_EQ(tet_quality(a, a, a, a), 0.0);
  // The corner tet of the unit cube: V = 1/6, l_rms^2 = (3 + 3 * 2) / 6.
  const double q = tet_quality(a, b, c, Vec3d{0, 0, 1});
  EXPECT_NEAR(q, 6.0 * std::sqrt(2.0) / 6.0 / std::pow(1.5, 1.5), 1e-12);
}

TEST(Quality, CoverageOfScaledCube) {
  // Cube [-0.5, 0.5]^3, inner cube half as large: shell volume 1 - 1/8.
  const SurfaceMesh s = make_shape("box", 2);
  const AssembleResult r = assemble_shell(s, halved_input(s));
  const QualitySummary q = summarize_quality(s, r.mesh);
  EXPECT_EQ(q.tets, r.mesh.tets.size());
  EXPECT_NEAR(q.enclosed_volume, 1.0, 1e-12);
  EXPECT_NEAR(q.shell_volume, 0.875, 1e-12);
  EXPECT_NEAR(q.coverage, 0.875, 1e-12);
  EXPECT_EQ(q.non_positive, 0u);
  ASSERT_EQ(q.histogram.size(), 10u);
  EXPECT_EQ(std::accumulate(q.histogram.begin(), q.histogram.end(), std::size_t{0}), q.tets);
  EXPECT_GT(q.min_quality, 0.0);
  EXPECT_LE(q.min_quality, q.median_quality);
  EXPECT_LE(q.median_quality, 1.0);
  EXPECT_GT(q.mean_quality, 0.0);
  EXPECT_GT(q.min_dihedral_deg, 0.0);
  EXPECT_LT(q.min_dihedral_deg, 70.6);
}

TEST(Quality, HistogramBinsAndStatistics) {
  TetMesh m;
  m.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  m.tets = {{0, 1, 2, 3}, {0, 1, 3, 2}, {0, 1, 2, 3}};
  m.quality = {1.0, -0.5, 0.05};  // used as given
  SurfaceMesh s;
  const QualitySummary q = summarize_quality(s, m);
  EXPECT_EQ(q.non_positive, 1u);
  EXPECT_EQ(q.histogram[9], 1u);
  EXPECT_EQ(q.histogram[0], 1u);
  EXPECT_DOUBLE_EQ(q.min_quality, -0.5);
  EXPECT_DOUBLE_EQ(q.median_quality, 0.05);
  EXPECT_DOUBLE_EQ(q.mean_quality, 0.55 / 3.0);
  EXPECT_NEAR(q.shell_volume, 1.0 / 6.0, 1e-15);
  EXPECT_EQ(q.coverage, 0.0);            // no enclosed volume
  EXPECT_DOUBLE_EQ(q.p5_quality, -0.5);  // rank floor(0.05 * 3) = 0
  // 40 tets of Q 0.01, 0.02, ..., 0.40: the 5th percentile is rank 2, Q 0.03.
  m.tets.assign(40, {0, 1, 2, 3});
  m.quality.clear();
  for (int i = 1; i <= 40; ++i) m.quality.push_back(0.01 * i);
  EXPECT_DOUBLE_EQ(summarize_quality(s, m).p5_quality, 0.03);
}

TEST(Quality, StatisticsAreThoseOfTheSortedQualities) {
  // Shuffled qualities with repeats, odd and even counts (the median of an even count is the mean
  // of the two middle values): against a sorted copy.
  TetMesh m;
  m.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  SurfaceMesh s;
  std::mt19937 random(5);
  for (const std::size_t count : {1, 2, 3, 20, 21, 1000, 1001, 4097}) {
    m.tets.assign(count, {0, 1, 2, 3});
    m.quality.clear();
    std::uniform_int_distribution<int> value(-3, 40);
    for (std::size_t t = 0; t < count; ++t) m.quality.push_back(0.025 * value(random));
    std::vector<double> sorted = m.quality;
    std::sort(sorted.begin(), sorted.end());
    const QualitySummary q = summarize_quality(s, m);
    EXPECT_EQ(q.min_quality, sorted.front()) << count;
    EXPECT_EQ(q.p5_quality, sorted[count / 20]) << count;
    const double median =
        count % 2 == 1 ? sorted[count / 2] : 0.5 * (sorted[count / 2 - 1] + sorted[count / 2]);
    EXPECT_EQ(q.median_quality, median) << count;
  }
}

}  // namespace
}  // namespace vdb_shell
