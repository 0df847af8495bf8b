// load_surface.h — turning a file's polygons into a closed, 2-manifold, outward triangle surface.
//
// Every rule of a closed 2-manifold surface is checked and reported by name with its first
// offending elements (indices, 0-based, and positions): NaN/Inf coordinates, out-of-range indices,
// polygons with fewer than three corners, degenerate (zero-area) and duplicate faces (the same
// corners, or corners at the same positions: parts touching face to face), boundary edges,
// non-manifold edges and vertices, inconsistent orientation, and (on a surface that passes all of
// those) faces that cross each other. Several components are allowed. A surface that breaks a
// rule only because vertices are written twice at one position (seams) is taken with those
// welded, and a notice says so. Faces pointing into the solid (by the even-odd rule: a component
// nested in an odd number of others bounds a cavity) are flipped, all of them or component by
// component, and a notice says so. Vertices no face uses are dropped with a notice. The geometric
// rules (areas, crossings, orientation) are judged on the points scaled by a power of two to unit
// magnitude, exactly, so the verdicts do not depend on the input's unit; messages name the
// input's points.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "core/base/surface_mesh.h"
#include "core/read/polygon_soup.h"
#include "core/read/zero_area.h"

namespace vdb_shell {

struct ValidationOptions {
  /// How many offending elements each problem lists in the message.
  std::size_t max_listed = 3;
  /// Faces whose area is at most this fraction of the squared bounding-box diagonal count as
  /// degenerate (zero-area).
  double degenerate_area_fraction = 1e-14;
  /// Faces with an edge no longer than this fraction of the bounding-box diagonal are refused:
  /// readers that weld positions within it (the independent checker does, at 1e-9) join the
  /// edge's ends and see the face collapse. 0: no limit.
  double short_edge_fraction = 1e-9;
  /// Vertices of open edges closer than this fraction of the bounding-box diagonal to another
  /// are welded when that closes the surface (cracks between patches written a rounding apart).
  double open_seam_fraction = 1e-7;
  /// Loops of open edges along one line, their vertices within this fraction of the
  /// bounding-box diagonal of it, are closed by slivers when that makes a valid surface (cracks
  /// where one side has vertices on an edge of the other: T-junctions).
  double t_junction_fraction = 1e-6;
  /// A surface that crosses itself, or has zero-area faces that cannot be flipped away alone, is
  /// shelled with the slivers where it crosses itself flipped too (core/read/zero_area.h,
  /// SliverFlips): faces whose corner facing the longest edge lies within this fraction of the
  /// bounding-box diagonal of it.
  double sliver_fraction = 1e-4;
};

/// Facts about a valid surface (what `vdb_shell INPUT` prints).
struct SurfaceStats {
  std::size_t vertices = 0;
  std::size_t faces = 0;
  std::size_t edges = 0;
  std::size_t components = 0;
  int genus = 0;                ///< sum over components of (2 - V + E - F) / 2
  BBox bbox;                    ///< world units
  double mean_edge_length = 0;  ///< world units
  double enclosed_volume = 0;   ///< world units cubed, positive once oriented outward
};

/// A validated surface and what was done to it on the way.
struct LoadedSurface {
  SurfaceMesh mesh;
  SurfaceStats stats;
  std::string source;                     ///< the name messages use (make_surface()'s source)
  std::size_t polygons_read = 0;          ///< faces in the file before triangulation
  std::size_t triangulated_polygons = 0;  ///< polygons with more than three corners
  std::size_t dropped_unused_vertices = 0;
  /// Vertices at exactly the position of an earlier one, welded to it: seams written twice
  /// (make_surface() welds them only when that makes a valid surface of an invalid one).
  std::size_t seam_vertices = 0;
  /// Vertices of open edges within ValidationOptions::open_seam_fraction of another, welded to it
  /// (make_surface() welds them only when that makes a valid surface of one with open edges).
  std::size_t crack_vertices = 0;
  /// Slivers added to close loops of open edges along a line (T-junctions), after the input's
  /// faces (make_surface() adds them only when that makes a valid surface).
  std::size_t crack_faces = 0;
  /// Faces repeating an earlier one corner for corner in the same direction (written twice),
  /// dropped (make_surface() drops them only when that makes a valid surface).
  std::size_t repeated_faces = 0;
  /// Faces turned to run against their neighbours along every shared edge, as a consistently
  /// oriented surface's do (make_surface() turns them only when that, after any welding, makes a
  /// valid surface of an invalid one; which way the whole faces is decided after).
  std::size_t reoriented_faces = 0;
  /// Vertices where parts of the surface meet only at that point, split into one vertex per fan
  /// of faces, the copies after all other vertices (make_surface() splits them only when that,
  /// after any welding, makes a valid surface of an invalid one).
  std::size_t pinched_vertices = 0;
  /// Edges where parts of the surface touch (more than two faces on the edge, alternating in
  /// direction around it, as unions of solids meeting along an edge leave), split with their
  /// vertices into one edge per pair of faces enclosing solid between them (their vertices are
  /// not counted in `pinched_vertices`; split only when that makes a valid surface of an invalid
  /// one).
  std::size_t touching_edges = 0;
  /// Zero-area faces (three corners on one line), flipped away for the shell and kept on its
  /// boundary by flat tets (core/read/zero_area.h; make_surface() flips them only when that
  /// makes a valid surface of one whose only fault they are).
  ZeroAreaFlips zero_area;
  bool flipped = false;  ///< true when the input was oriented inward
  /// Components flipped alone (some of several faced into the solid; `flipped` when all did).
  std::size_t flipped_components = 0;
  std::vector<std::string> notices;  ///< one sentence each, for the CLI to print
};

/// One broken rule: a short name ("boundary edges") and its first offending elements.
struct SurfaceProblem {
  std::string rule;
  std::size_t count = 0;
  bool at_least = false;  ///< counting stopped at `count` (crossings: see find_surface_problems())
  std::string first;      ///< e.g. "edge (3, 7) at (0, 0, 1)-(1, 0, 1)"
  std::string remedy;
};

/// Lists every broken rule of `soup` (empty when it is a valid closed 2-manifold surface).
std::vector<SurfaceProblem> find_surface_problems(const PolygonSoup& soup,
                                                  const ValidationOptions& options = {});

/// Validates `soup` and returns it as an outward triangle surface.
/// \param source  name used in messages (usually the file path)
/// \throw InputError naming `source`, every broken rule and its first offending elements.
LoadedSurface make_surface(const PolygonSoup& soup, const std::string& source,
                           const ValidationOptions& options = {});

/// read_polygon_soup() followed by make_surface().
LoadedSurface load_surface(const std::string& path, const ValidationOptions& options = {});

/// The triangles of `mesh` as a soup's polygons (to validate or load a surface built in code).
PolygonSoup polygon_soup_of(const SurfaceMesh& mesh);

/// Counts, genus, bounds and volume of a triangle surface (closed meshes give exact genus).
SurfaceStats surface_stats(const SurfaceMesh& mesh);

}  // namespace vdb_shell
