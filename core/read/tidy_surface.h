// tidy_surface.h — a contoured surface (volumeToMesh's polygons: the --repair surface) without
// its specks and slivers.
//
// Contouring puts a vertex in every voxel the surface crosses. Where the surface passes near a
// grid point, the vertices of the voxels around it crowd onto it and the polygons between them
// are needles, with edges of a thousandth of a voxel; where a grid point lies just inside, alone,
// the contour around it is a speck, a part of a dozen faces smaller than a voxel. A shell keeps
// every surface triangle as the outer face of its prism, so such triangles have flat tets
// whatever the trace does (12-322 tets of no volume on repaired meshes with holes or noise at
// 128^3). tidy_contoured_surface() drops the parts that enclose less than a bound, triangulates
// the polygons (each quad along the diagonal that gives the better pair) and collapses the edges
// shorter than a bound into their midpoints, shortest first. A collapse keeps the surface a
// closed, oriented 2-manifold (the link condition) and is refused when it would turn a face
// that stays by more than 30 degrees or leave it below a quality of 0.1 and below half its own
// (faces whose edges are all short are collapsed in turn and may change freely); it moves two
// points by half the edge at most. It can still make faces cross where two sheets of the surface
// are closer than the edge: callers check (the repair freezes the points there and tidies again).
//
// Deterministic (serial, in a fixed order). Internal to the library (not installed).
#pragma once

#include <cstddef>
#include <vector>

#include "core/read/polygon_soup.h"

namespace vdb_shell {

/// What tidy_contoured_surface() removes.
struct TidyOptions {
  double min_edge = 0.0;         ///< world units: shorter edges are collapsed
  double min_part_volume = 0.0;  ///< world units cubed: parts enclosing less are dropped
  /// One entry per point of the soup, or empty: the edges of a point p with frozen[p] != 0 are
  /// not collapsed.
  std::vector<char> frozen;
};

/// What tidy_contoured_surface() did.
struct TidyCounts {
  std::size_t dropped_parts = 0;  ///< connected parts enclosing less than min_part_volume
  std::size_t collapsed = 0;      ///< short edges collapsed (each removes two triangles)
};

/// The triangles of `soup` (a closed, oriented 2-manifold of triangles and quads, indices valid)
/// without its specks (connected parts enclosing less than options.min_part_volume, either way
/// round: a contour around one grid point) and with its edges shorter than options.min_edge
/// collapsed where that is sound (see above); the points no triangle uses any more are dropped.
/// `counts` (when not null) receives what was done.
PolygonSoup tidy_contoured_surface(const PolygonSoup& soup, const TidyOptions& options,
                                   TidyCounts* counts = nullptr);

/// Area-length quality of a triangle: 4 sqrt(3) area / (sum of its squared edges), 1 for an
/// equilateral triangle, 0 for one of no area.
double triangle_quality(const Vec3d& a, const Vec3d& b, const Vec3d& c);

}  // namespace vdb_shell
