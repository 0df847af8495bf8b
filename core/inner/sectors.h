// sectors.h — folded surface vertices split into sectors, each with its own inner vertex
// (docs/validity.md, "Folded vertices").
//
// A vertex whose incident face normals fit in no open hemisphere has no direction pointing
// inward for all its faces, and each prism constrains its corners' inner directions against its
// face normal: no single inner vertex works there. Its fan (the incident faces in cyclic order)
// is split into sectors, runs of consecutive faces that do share an inward direction, and every
// sector gets an inner vertex of its own, traced from the vertex along that direction.
//
// Where two sectors meet, along a fan edge e = (v, b) between faces f (sector S) and g (sector T),
// the two prisms' side quads no longer coincide: prism f spans the wedge around e from f to S's
// direction, prism g from T's direction to g. They must not cross, so S's direction is kept on
// f's side of the plane bisecting the interior angle at e and T's on g's side: every sector's
// direction must point inward for its faces and lie on its own side of the bisectors of its two
// boundary edges, and see its faces from v without crossing the fan's other faces. Of the
// splits of the fan into such runs, the one whose faces get the most inward directions wins
// (the sum over faces of their sector's margin, capped at 0.1; then the fewest sectors).
//
// The split is a surface of its own: each extra sector of a vertex v gets a copy of v (same
// position, index n, n + 1, ... in order of v and then of the sector), which the faces of that
// sector use instead of v; the first sector keeps v. The split surface has the same triangles in
// the same order, only slit along the sector boundaries; the shell of the split surface, with the
// copies mapped back to their vertex, is a shell of the input.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "core/base/surface_mesh.h"

namespace vdb_shell {

/// Smallest -n.d over the unit normals `normals` (> 0: d points inward for every one).
double inward_margin(const std::vector<Vec3d>& normals, const Vec3d& d);

/// The unit direction that maximises inward_margin(), or zero when no direction has a positive
/// margin (the normals fit in no open hemisphere).
Vec3d most_inward_direction(const std::vector<Vec3d>& normals);

struct SectorSplit {
  SurfaceMesh surface;  ///< the split surface: the input's points, then one copy per extra sector
  /// Per point of `surface`: the input vertex it is (itself for the input's points).
  std::vector<std::uint32_t> vertex;
  /// Per point of `surface`: the unit direction its sector's trace starts in (zero for vertices
  /// that were not split).
  std::vector<Vec3d> direction;
  /// Per point of `surface`: what its inner direction must satisfy beyond pointing inward for
  /// its faces, as normals n with -n.d > 0 (a sector's two bisector constraints; empty for
  /// vertices that were not split).
  std::vector<std::vector<Vec3d>> constraints;
  std::vector<std::uint32_t> folded;  ///< input vertices split into sectors, ascending
  /// Input vertices whose fan has no split either (kept on the surface, as a last resort).
  std::vector<std::uint32_t> unsplit;
  /// Sector boundary edges: the fan edge (v, b) between faces f and g, as {v, b, f, g} in input
  /// indices, f in the sector before the edge in v's fan order.
  std::vector<std::array<std::uint32_t, 4>> boundaries;
  std::size_t sectors = 0;  ///< sectors over all folded vertices

  bool empty() const { return folded.empty(); }
};

/// A vertex needs an inward direction with at least this margin (the sine of its angle to the
/// nearest face plane: 0.57 degrees); a vertex with less is folded. Below it the thinnest shell
/// is valid only at depths far below the floor (docs/validity.md).
constexpr double kFoldMargin = 0.01;
/// A sector's direction needs this margin (its faces and bisectors; 0.057 degrees): sectors
/// next to knife-sharp folds have less than kFoldMargin to offer, and their first step is
/// straight (retrace_split()), where the thinnest shell is exact rather than first-order.
constexpr double kSectorMargin = 0.001;

/// Finds the folded vertices of a closed, 2-manifold, outward surface and splits their fans.
/// A surface without folded vertices gives an empty split (and `surface` empty).
SectorSplit split_folded_vertices(const SurfaceMesh& mesh);

}  // namespace vdb_shell
