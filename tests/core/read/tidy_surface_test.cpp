// tidy_surface_test.cpp — core/read/tidy_surface.h on the box with an edge split next to its
// corner (a needle pair), a speck beside it and its faces as quads, checked by the test's own
// edge lengths, point displacements, enclosed volumes and by find_surface_problems().
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "assets/shapes.h"
#include "core/read/load_surface.h"
#include "core/read/tidy_surface.h"

namespace vdb_shell {
namespace {

double shortest_edge(const PolygonSoup& soup) {
  double shortest = INFINITY;
  for (const std::vector<std::int64_t>& f : soup.polygons)
    for (std::size_t k = 0; k < f.size(); ++k)
      shortest = std::min(shortest, distance(soup.points[std::size_t(f[k])],
                                             soup.points[std::size_t(f[(k + 1) % f.size()])]));
  return shortest;
}

double enclosed_volume(const PolygonSoup& soup) {
  double v = 0.0;
  for (const std::vector<std::int64_t>& f : soup.polygons)
    for (std::size_t k = 1; k + 1 < f.size(); ++k)
      v += tet_volume({0, 0, 0}, soup.points[std::size_t(f[0])], soup.points[std::size_t(f[k])],
                      soup.points[std::size_t(f[k + 1])]);
  return v;
}

// The box (detail 2: edges of 0.25) with edge (u, v) of its first face split at a point `gap`
// from u: the two faces on it become four, two of them needles with the edge of length `gap`.
PolygonSoup box_with_needles(double gap, std::int64_t& u) {
  PolygonSoup soup = polygon_soup_of(make_shape("box", 2));
  u = soup.polygons[0][0];
  const std::int64_t v = soup.polygons[0][1];
  const Vec3d at = soup.points[std::size_t(u)] +
                   normalized(soup.points[std::size_t(v)] - soup.points[std::size_t(u)]) * gap;
  const auto m = std::int64_t(soup.points.size());
  soup.points.push_back(at);
  std::vector<std::vector<std::int64_t>> polygons;
  for (const std::vector<std::int64_t>& f : soup.polygons) {
    bool split = false;
    for (int k = 0; k < 3 && !split; ++k) {
      const std::int64_t a = f[k], b = f[(k + 1) % 3], c = f[(k + 2) % 3];
      if ((a == u && b == v) || (a == v && b == u)) {
        polygons.push_back({a, m, c});
        polygons.push_back({m, b, c});
        split = true;
      }
    }
    if (!split) polygons.push_back(f);
  }
  soup.polygons = polygons;
  return soup;
}

TEST(TidySurface, AShortEdgeIsCollapsedIntoItsMiddle) {
  std::int64_t u = 0;
  const PolygonSoup soup = box_with_needles(1e-4, u);
  ASSERT_TRUE(find_surface_problems(soup).empty());
  ASSERT_LT(shortest_edge(soup), 2e-4);
  TidyOptions options;
  options.min_edge = 1e-2;
  TidyCounts counts;
  const PolygonSoup out = tidy_contoured_surface(soup, options, &counts);
  EXPECT_EQ(counts.collapsed, 1u);
  EXPECT_EQ(counts.dropped_parts, 0u);
  EXPECT_TRUE(find_surface_problems(out).empty());
  EXPECT_EQ(out.polygons.size(), soup.polygons.size() - 2);
  EXPECT_EQ(out.points.size(), soup.points.size() - 1);
  EXPECT_GE(shortest_edge(out), 0.2);
  // Every point stays within half the edge of where it was; the volume moves by the corner's
  // shift at most.
  for (const Vec3d& p : out.points) {
    double nearest = INFINITY;
    for (const Vec3d& q : soup.points) nearest = std::min(nearest, distance(p, q));
    EXPECT_LE(nearest, 0.5e-4 + 1e-15);
  }
  EXPECT_NEAR(enclosed_volume(out), enclosed_volume(soup), 1e-4);
}

TEST(TidySurface, FrozenPointsKeepTheirEdges) {
  std::int64_t u = 0;
  const PolygonSoup soup = box_with_needles(1e-4, u);
  TidyOptions options;
  options.min_edge = 1e-2;
  options.frozen.assign(soup.points.size(), 0);
  options.frozen[std::size_t(u)] = 1;
  TidyCounts counts;
  const PolygonSoup out = tidy_contoured_surface(soup, options, &counts);
  EXPECT_EQ(counts.collapsed, 0u);
  EXPECT_EQ(out.polygons.size(), soup.polygons.size());
  EXPECT_LT(shortest_edge(out), 2e-4);
}

TEST(TidySurface, SpecksAreDroppedAndQuadsSplitAlongTheBetterDiagonal) {
  // A unit cube's faces as quads, with the edge (3, 7) pulled in towards the diagonals (0, 2) and
  // (4, 6) along which index order would split the bottom and top quads (every quad still
  // planar), and beside it a speck: an octahedron of radius 1e-3 (volume 1.3e-9).
  PolygonSoup soup;
  soup.points = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                 {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
  soup.polygons = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4},
                   {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}};
  soup.points[3] = {0.45, 0.55, 0};  // bottom and top: (0, 2) and (4, 6) poor diagonals now
  soup.points[7] = {0.45, 0.55, 1};
  const auto o = std::int64_t(soup.points.size());
  const double r = 1e-3;
  for (const Vec3d& d : {Vec3d{r, 0, 0}, Vec3d{-r, 0, 0}, Vec3d{0, r, 0}, Vec3d{0, -r, 0},
                         Vec3d{0, 0, r}, Vec3d{0, 0, -r}})
    soup.points.push_back(Vec3d{2, 0.5, 0.5} + d);
  for (const auto& f : std::vector<std::vector<std::int64_t>>{
           {0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}})
    soup.polygons.push_back({o + f[0], o + f[1], o + f[2]});
  ASSERT_TRUE(find_surface_problems(soup).empty());
  TidyOptions options;
  options.min_part_volume = 1e-6;
  TidyCounts counts;
  const PolygonSoup out = tidy_contoured_surface(soup, options, &counts);
  EXPECT_EQ(counts.dropped_parts, 1u);
  EXPECT_EQ(out.points.size(), 8u);
  EXPECT_EQ(out.polygons.size(), 12u);
  EXPECT_TRUE(find_surface_problems(out).empty());
  EXPECT_NEAR(enclosed_volume(out), enclosed_volume(soup) - 4.0 / 3.0 * r * r * r, 1e-12);
  // The bottom quad's triangles: split along (3, 1), both of fair quality.
  double worst = 1.0;
  for (const std::vector<std::int64_t>& f : out.polygons) {
    const Vec3d a = out.points[std::size_t(f[0])], b = out.points[std::size_t(f[1])],
                c = out.points[std::size_t(f[2])];
    if (a.z == 0 && b.z == 0 && c.z == 0) worst = std::min(worst, triangle_quality(a, b, c));
  }
  EXPECT_GT(worst, 0.4);
}

}  // namespace
}  // namespace vdb_shell
