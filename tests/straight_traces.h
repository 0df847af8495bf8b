// straight_traces.h — how far traces bend where the exact field's paths are straight (the faces
// of a box, the side of a cylinder): shared by trace_vdb_test and vdb_shell_bench_traces.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include "assets/shapes.h"
#include "core/base/surface_mesh.h"
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

/// A shape and the traces of it that are straight in the exact field.
struct StraightCase {
  std::string name;
  SurfaceMesh mesh;
  std::vector<StraightTrace> straight;
};

/// The straight traces of two shapes, each as generated and rotated by 20 degrees about x and 30
/// about z (so that the voxel grid shares none of their symmetries):
///   box (2x2 per face): every vertex lies on an axis of symmetry, so its trace runs straight to
///     the centre (corners and edge midpoints along medial surfaces);
///   cylinder at detail 2 (a 16-sided prism): cap centres run down the axis; side vertices at
///     mid-height lie on a mirror plane through the axis and on z = 0, so they run straight to
///     the axis along the medial surface between two side faces (at 22.5 degrees to the grid).
inline std::vector<StraightCase> straight_trace_cases() {
  std::vector<StraightCase> cases;
  for (const bool rotate : {false, true}) {
    StraightCase box{rotate ? "box, rotated" : "box", make_shape("box", 1), {}};
    for (std::size_t v = 0; v < box.mesh.points.size(); ++v)
      box.straight.push_back({v, normalized(-box.mesh.points[v])});
    cases.push_back(std::move(box));
  }
  for (const bool rotate : {false, true}) {
    StraightCase cylinder{rotate ? "cylinder, rotated" : "cylinder", make_shape("cylinder", 2), {}};
    for (std::size_t v = 0; v < cylinder.mesh.points.size(); ++v) {
      const Vec3d& p = cylinder.mesh.points[v];
      const double rho = std::hypot(p.x, p.y);
      if (rho < 1e-12 && std::fabs(p.z) > 0.5 - 1e-12)
        cylinder.straight.push_back({v, {0, 0, p.z > 0 ? -1.0 : 1.0}});
      else if (std::fabs(p.z) < 1e-12 && std::fabs(rho - 0.5) < 1e-9)
        cylinder.straight.push_back({v, normalized(Vec3d(-p.x, -p.y, 0))});
    }
    cases.push_back(std::move(cylinder));
  }
  for (StraightCase& c : cases) {
    if (c.name.find("rotated") == std::string::npos) continue;
    for (Vec3d& p : c.mesh.points) p = rotated(p, 20.0, 30.0);
    for (StraightTrace& s : c.straight) s.direction = rotated(s.direction, 20.0, 30.0);
  }
  return cases;
}

}  // namespace vdb_shell::test
