// inside_test.h — whether points lie outside a closed surface, for many points against one
// index.
//
// Method: the parity of the crossings of an axis-parallel ray, its triangles found in a 2D grid
// of the triangles' projections (one grid per axis). A ray that passes within the tolerance of a
// triangle's edge (a triangle seen edge-on included) is ambiguous and the next axis is tried.
// When all three are (the point lines up with edges on every axis, as inner points do on a mesh
// of axis-aligned faces), the same rays are cast from a few points near it, off those lines, no
// farther than its clearance from the surface: each lies on its side. Only when those are
// ambiguous too does the generalized winding number over all triangles decide, by its parity.
// Points within the tolerance of a triangle (exact point-triangle distance) are on the surface,
// hence not outside. Parity makes the orientation irrelevant: inside two nested components
// facing the same way is outside.
//
// Internal to core/validity (not installed); point_outside_surface() (shell_checks.h) is the
// public one-point call.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "core/base/surface_mesh.h"
#include "core/base/vec3.h"

namespace vdb_shell {

class InsideTester {
 public:
  /// Indexes `surface`, which must be closed (in any orientation: inside is by parity) and
  /// outlive the tester.
  /// \param tolerance  world units: points closer than this to the surface are on it.
  InsideTester(const SurfaceMesh& surface, double tolerance);

  /// Whether `p` (world units) lies outside the surface, farther than the tolerance from it.
  /// Thread-safe.
  bool outside(const Vec3d& p) const;

 private:
  enum class RayVerdict { kInside, kOutside, kOnSurface, kAmbiguous };

  // Triangles listed per cell of the projection along an axis onto coordinates (u, v).
  struct ColumnGrid {
    int u = 1, v = 2;
    double lo_u = 0.0, lo_v = 0.0, inv_cell = 1.0;  // world units, 1 / world units
    long nu = 1, nv = 1;
    std::vector<std::uint32_t> start;  // nu * nv + 1
    std::vector<std::uint32_t> items;
    long cell_u(double x) const;
    long cell_v(double x) const;
  };

  void build(int axis);
  // Parity of the crossings of the ray from p towards +axis.
  RayVerdict cast_ray(int axis, const Vec3d& p) const;
  // The first verdict of the three axes' rays from p that is not ambiguous.
  RayVerdict cast_rays(const Vec3d& p) const;
  // A distance from p within which no triangle lies: the nearest triangle listed in the 3 x 3
  // cells of axis 0's grid around p, else a cell's width (any other triangle is farther).
  double clearance(const Vec3d& p) const;

  const SurfaceMesh& surface_;
  double tolerance_;
  std::array<ColumnGrid, 3> grids_;
};

}  // namespace vdb_shell
