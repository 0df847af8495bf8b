// tet_predicates.h — the geometric tests of the shell checks: a tet prepared for separating-axis
// tests, whether two tets overlap, whether a triangle crosses a tet or another triangle.
//
// Every test is a separating-axis test: two convex bodies are apart when their projections on
// some axis overlap by no more than a tolerance. The candidate axes are the face normals of both
// bodies and the cross products of their edges. Bodies that only touch (a shared vertex, edge or
// face, or lying against each other) are therefore apart.
//
// Every test projects differences of the bodies' corners (relative to one corner), not world
// coordinates: far from the origin (coordinates of 1e6 round at 1e-10) the tolerance stays
// meaningful. Lengths are world units. A `tolerance` is a distance in world units; a
// `relative_tolerance` is a multiple of the longest edge involved (dimensionless). Internal to
// core/validity (not installed); the public entry points are tets_overlap() and tet_volume_class()
// (shell_checks.h).
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>

#include "core/base/surface_mesh.h"
#include "core/base/tet_mesh.h"
#include "core/base/vec3.h"

namespace vdb_shell {

/// A tet with what the separating-axis tests need of it.
struct TetGeometry {
  std::array<Vec3d, 4> p;  ///< corners, world units
  std::array<Vec3d, 4> n;  ///< unit normal of the face opposite corner k (0 if degenerate)
  /// Extent of the tet along n[k] relative to p[0] (of the points p[j] - p[0]), world units:
  /// the tests project differences of nearby points, never world coordinates, which far from
  /// the origin round at more than the tolerance.
  std::array<double, 4> lo{};
  std::array<double, 4> hi{};
  double max_edge = 0.0;  ///< longest edge, world units
  BBox box;               ///< bounding box, world units
};

/// The four corners of tet `t` of `mesh`. \pre its indices are in range.
inline std::array<Vec3d, 4> tet_corners(const TetMesh& mesh, std::size_t t) {
  const Tet& v = mesh.tets[t];
  return {mesh.points[v[0]], mesh.points[v[1]], mesh.points[v[2]], mesh.points[v[3]]};
}

/// The three corners of triangle `f` of `surface`.
inline std::array<Vec3d, 3> triangle_corners(const SurfaceMesh& surface, std::size_t f) {
  const Triangle& tri = surface.triangles[f];
  return {surface.points[tri[0]], surface.points[tri[1]], surface.points[tri[2]]};
}

/// Length of the longest of the six edges of tet `p` (world units).
double longest_edge(const std::array<Vec3d, 4>& p);

/// The tet with corners `p` (world units), prepared for the tests below.
TetGeometry tet_geometry(const std::array<Vec3d, 4>& p);

/// Whether the closed boxes `a` and `b` share a point.
inline bool boxes_overlap(const BBox& a, const BBox& b) {
  return a.lo.x <= b.hi.x && b.lo.x <= a.hi.x && a.lo.y <= b.hi.y && b.lo.y <= a.hi.y &&
         a.lo.z <= b.hi.z && b.lo.z <= a.hi.z;
}

/// Whether the interiors of tets `a` and `b` intersect: no axis (4 + 4 face normals, 36 edge
/// cross products) sees their projections overlap by at most `tolerance` (world units).
bool geometries_overlap(const TetGeometry& a, const TetGeometry& b, double tolerance);

/// Whether tets `a` and `b` overlap: their boxes meet and geometries_overlap() holds with a
/// tolerance of `relative_tolerance` times the longest edge of the two (dimensionless).
inline bool tets_intersect(const TetGeometry& a, const TetGeometry& b, double relative_tolerance) {
  if (!boxes_overlap(a.box, b.box)) return false;
  return geometries_overlap(a, b, relative_tolerance * std::max(a.max_edge, b.max_edge));
}

/// Whether triangles `a` and `b` (corners, world units) cross: no axis (both normals, the 9 cross
/// products of their edges, each normal crossed with the other's edges for coplanar pairs) sees
/// their projections overlap by at most `tolerance` (world units).
bool triangles_cross(const std::array<Vec3d, 3>& a, const std::array<Vec3d, 3>& b,
                     double tolerance);

/// Whether triangle `t` (corners, world units) crosses the interior of tet `g`: no axis (the
/// triangle's normal, the tet's face normals, the 18 cross products of their edges) sees their
/// projections overlap by at most `tolerance` (world units).
bool triangle_crosses_tet(const std::array<Vec3d, 3>& t, const TetGeometry& g, double tolerance);

/// Whether triangle `f` of `surface` crosses the interior of tet `g`: their boxes meet and
/// triangle_crosses_tet() holds with a tolerance of `relative_tolerance` times the tet's longest
/// edge (dimensionless).
inline bool surface_triangle_crosses(const SurfaceMesh& surface, std::size_t f,
                                     const TetGeometry& g, double relative_tolerance) {
  const std::array<Vec3d, 3> t = triangle_corners(surface, f);
  BBox box;
  for (const Vec3d& p : t) box.expand(p);
  return boxes_overlap(box, g.box) && triangle_crosses_tet(t, g, relative_tolerance * g.max_edge);
}

}  // namespace vdb_shell
