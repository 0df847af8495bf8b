// sectors_test.cpp — core/inner/sectors.h: the most inward direction against sampled
// directions and a closed form, and the flap shape's folded vertex split into sectors whose
// directions point inward for their faces.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <map>
#include <random>
#include <vector>

#include "assets/shapes.h"
#include "core/base/vec3.h"
#include "core/inner/inner.h"
#include "core/inner/sectors.h"
#include "core/trace/trace.h"

namespace vdb_shell {
namespace {

Vec3d random_unit(std::mt19937& rng) {
  std::normal_distribution<double> g;
  return normalized(Vec3d{g(rng), g(rng), g(rng)});
}

/// The best inward margin over `samples` random directions (an independent lower bound of the
/// true maximum, close to it for many samples).
double sampled_best_margin(const std::vector<Vec3d>& normals, int samples, std::mt19937& rng) {
  double best = -2;
  for (int s = 0; s < samples; ++s) {
    const Vec3d d = random_unit(rng);
    double m = 2;
    for (const Vec3d& n : normals) m = std::min(m, -dot(n, d));
    best = std::max(best, m);
  }
  return best;
}

TEST(Sectors, MostInwardDirectionBeatsEverySampledDirection) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 40; ++trial) {
    // Normals within a cone of half-angle 30-85 degrees around a random axis: some fit in a
    // hemisphere with room, some barely, some not at all.
    const Vec3d axis = random_unit(rng);
    const double spread = 0.5 + 1.0 * (trial % 10) / 9.0;
    std::vector<Vec3d> normals;
    for (int k = 0; k < 3 + trial % 7; ++k)
      normals.push_back(normalized(axis + random_unit(rng) * spread));
    const Vec3d d = most_inward_direction(normals);
    const double sampled = sampled_best_margin(normals, 20000, rng);
    if (norm2(d) == 0) {
      EXPECT_LE(sampled, 1e-9) << trial;  // no direction with a positive margin exists
      continue;
    }
    EXPECT_NEAR(norm(d), 1.0, 1e-12);
    EXPECT_GE(inward_margin(normals, d), sampled - 1e-9) << trial;
  }
}

TEST(Sectors, MostInwardDirectionOfAKnifeEdgeIsItsBisector) {
  // The faces of a wedge of interior angle theta: the best margin is sin(theta / 2), found
  // exactly however thin the wedge.
  for (const double degrees : {90.0, 10.0, 1.0, 0.1}) {
    const double theta = degrees * kPi / 180;
    const std::vector<Vec3d> normals = {{0, 0, 1}, {0, std::sin(theta), -std::cos(theta)}};
    const Vec3d d = most_inward_direction(normals);
    EXPECT_NEAR(inward_margin(normals, d), std::sin(theta / 2), 1e-12) << degrees;
  }
  // Opposite normals: no inward direction.
  EXPECT_EQ(norm2(most_inward_direction({{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}})), 0.0);
}

TEST(Sectors, TheFlapsFoldedVertexIsSplitIntoInwardSectors) {
  const SurfaceMesh mesh = make_shape("flap", 2);
  const SectorSplit split = split_folded_vertices(mesh);
  std::uint32_t centre = UINT32_MAX;
  for (std::uint32_t v = 0; v < mesh.points.size(); ++v)
    if (mesh.points[v] == Vec3d(0, 0, 0.5)) centre = v;
  ASSERT_NE(centre, UINT32_MAX);
  // The centre's incident face normals fit in no hemisphere (sampled independently).
  std::vector<Vec3d> fan_normals;
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f)
    for (const std::uint32_t c : mesh.triangles[f])
      if (c == centre) fan_normals.push_back(normalized(face_normal_area(mesh, f)));
  std::mt19937 rng(3);
  EXPECT_LT(sampled_best_margin(fan_normals, 50000, rng), 0.0);
  ASSERT_EQ(split.folded, std::vector<std::uint32_t>{centre});
  EXPECT_TRUE(split.unsplit.empty());
  ASSERT_GE(split.sectors, 2u);

  // The split surface: the same triangles once each copy is mapped back, copies where their
  // vertex is, and every face of the centre's fan in exactly one sector.
  ASSERT_EQ(split.surface.triangles.size(), mesh.triangles.size());
  ASSERT_EQ(split.surface.points.size(), mesh.points.size() + split.sectors - 1);
  std::map<std::uint32_t, std::vector<std::uint32_t>> sector_faces;  // copy -> its faces
  for (std::uint32_t f = 0; f < mesh.triangles.size(); ++f)
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t c = split.surface.triangles[f][k];
      EXPECT_EQ(split.vertex[c], mesh.triangles[f][k]) << f;
      EXPECT_EQ(split.surface.points[c], mesh.points[split.vertex[c]]);
      if (split.vertex[c] == centre) sector_faces[c].push_back(f);
    }
  EXPECT_EQ(sector_faces.size(), split.sectors);
  std::size_t faces = 0;
  for (const auto& [copy, list] : sector_faces) {
    faces += list.size();
    // Each sector's direction points inward for each of its faces, with the sector margin.
    const Vec3d d = split.direction[copy];
    EXPECT_NEAR(norm(d), 1.0, 1e-12);
    for (const std::uint32_t f : list)
      EXPECT_GE(-dot(normalized(face_normal_area(mesh, f)), d), kSectorMargin) << f;
  }
  EXPECT_EQ(faces, fan_normals.size());
  EXPECT_EQ(split.boundaries.size(), split.sectors);
}

TEST(Sectors, ACopyHasItsVertexsEdgeFactorLimit) {
  // Straight traces, far longer than the limits: every sector of the flap's centre is limited
  // to K times the centre's mean incident edge over its whole fan, not over its sector's.
  const SurfaceMesh mesh = make_shape("flap", 2);
  const SectorSplit split = split_folded_vertices(mesh);
  ASSERT_FALSE(split.empty());
  TraceResult traces;
  traces.offsets.push_back(0);
  for (const Vec3d& p : split.surface.points) {
    traces.samples.insert(traces.samples.end(), {p, p - Vec3d{0, 0, 10}});
    traces.arc_length.insert(traces.arc_length.end(), {0.0, 10.0});
    traces.end.push_back(1);
    traces.offsets.push_back(static_cast<std::uint32_t>(traces.samples.size()));
  }
  ThicknessOptions options;
  options.edge_factor = 0.5;
  const std::uint32_t centre = split.folded.front();
  double sum = 0;
  int count = 0;
  for (const Triangle& t : mesh.triangles)
    for (int k = 0; k < 3; ++k)
      if (t[k] == centre) {
        sum += distance(mesh.points[centre], mesh.points[t[(k + 1) % 3]]) +
               distance(mesh.points[centre], mesh.points[t[(k + 2) % 3]]);
        count += 2;
      }
  const InnerVertices joined = place_inner_vertices(split.surface, traces, options, split.vertex);
  const InnerVertices alone = place_inner_vertices(split.surface, traces, options);
  bool sector_mean_differs = false;
  for (std::uint32_t u = 0; u < split.surface.points.size(); ++u) {
    if (split.vertex[u] != centre) continue;
    EXPECT_NEAR(joined.limit[u], 0.5 * sum / count, 1e-12) << u;
    EXPECT_NEAR(joined.arc[u], 0.5 * sum / count, 1e-12) << u;
    sector_mean_differs = sector_mean_differs || std::abs(alone.limit[u] - joined.limit[u]) > 1e-6;
  }
  EXPECT_TRUE(sector_mean_differs);  // what the test tells apart
}

TEST(Sectors, ASurfaceWithoutFoldsIsNotSplit) {
  for (const char* name : {"box", "sphere", "horn", "pointy"}) {
    const SectorSplit split = split_folded_vertices(make_shape(name, 2));
    EXPECT_TRUE(split.empty()) << name;
    EXPECT_TRUE(split.unsplit.empty()) << name;
  }
}

}  // namespace
}  // namespace vdb_shell
