// straight_traces.h — how far traces bend where the exact field's paths are straight (the faces
// of a box, the side of a cylinder): shared by trace_vdb_test and vdb_shell_bench_traces.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

#include "core/base/vec3.h"
#include "core/trace/trace.h"

namespace vdb_shell::test {

/// A trace that is a straight segment in the exact field: vertex v, along `direction` (unit).
struct StraightTrace {
  std::size_t vertex;
  Vec3d direction;
};

/// Largest distance (voxels) of any sample, up to the end, from the straight line of each trace.
inline double largest_deviation(const TraceResult& r, const std::vector<StraightTrace>& straight,
                                double voxel) {
  double worst = 0;
  for (const StraightTrace& s : straight) {
    const Vec3d& p = r.sample(s.vertex, 0);
    for (std::size_t i = 1; i <= r.end[s.vertex]; ++i) {
      const Vec3d d = r.sample(s.vertex, i) - p;
      worst = std::max(worst, norm(d - dot(d, s.direction) * s.direction) / voxel);
    }
  }
  return worst;
}

/// Rotation by `deg_z` degrees about z after `deg_x` degrees about x.
inline Vec3d rotated(const Vec3d& p, double deg_x, double deg_z) {
  const double ax = deg_x * kPi / 180.0, az = deg_z * kPi / 180.0;
  const Vec3d q(p.x, std::cos(ax) * p.y - std::sin(ax) * p.z,
                std::sin(ax) * p.y + std::cos(ax) * p.z);
  return {std::cos(az) * q.x - std::sin(az) * q.y, std::sin(az) * q.x + std::cos(az) * q.y, q.z};
}

}  // namespace vdb_shell::test
