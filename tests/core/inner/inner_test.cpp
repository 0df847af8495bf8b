// inner_test.cpp — place_inner_vertices() (core/inner/inner.h): welding joins each trace end to
// the smallest earlier representative within half the point size, checked against brute force.
#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <set>
#include <vector>

#include "core/base/surface_mesh.h"
#include "core/inner/inner.h"
#include "core/trace/trace.h"

namespace vdb_shell {
namespace {

TEST(Inner, WeldingJoinsTheSmallestEarlierRepresentativeWithinTolerance) {
  // Straight two-sample traces ending at random points, in a crowd (most ends within the
  // tolerance of many others) and spread out; the result must be the greedy rule, brute force.
  std::mt19937 rng(7);
  for (const double spread : {0.3, 3.0}) {
    const std::uint32_t n = 600;
    std::uniform_real_distribution<double> u(-spread, spread);
    SurfaceMesh mesh;
    TraceResult traces;
    traces.parameters.point_size = 1.0;
    traces.offsets.push_back(0);
    for (std::uint32_t v = 0; v < n; ++v) {
      const Vec3d start{10.0 + v, 0, 0}, end{u(rng), u(rng), u(rng)};
      mesh.points.push_back(start);
      traces.samples.insert(traces.samples.end(), {start, end});
      traces.arc_length.insert(traces.arc_length.end(), {0.0, distance(start, end)});
      traces.end.push_back(1);
      traces.offsets.push_back(static_cast<std::uint32_t>(traces.samples.size()));
    }
    const InnerVertices inner = place_inner_vertices(mesh, traces, ThicknessOptions{});
    const double tol = 0.5;  // half the point size
    std::vector<std::uint32_t> rep(n);
    std::size_t welded = 0;
    for (std::uint32_t v = 0; v < n; ++v) {
      rep[v] = v;
      for (std::uint32_t w = 0; w < v; ++w)
        if (rep[w] == w && distance(traces.end_point(w), traces.end_point(v)) <= tol) {
          rep[v] = w;
          ++welded;
          break;
        }
    }
    EXPECT_EQ(inner.welded, welded) << "spread " << spread;
    if (spread < 1.0) {
      EXPECT_GT(welded, n / 2);
    }
    for (std::uint32_t v = 0; v < n; ++v)
      EXPECT_EQ(inner.input.inner_id[v], inner.input.inner_id[rep[v]]) << v;
    std::set<std::uint32_t> distinct(inner.input.inner_id.begin(), inner.input.inner_id.end());
    EXPECT_EQ(distinct.size(), n - welded);
  }
}

}  // namespace
}  // namespace vdb_shell
