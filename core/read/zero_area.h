// zero_area.h — closed surfaces with zero-area faces (three corners on one line, as CAD exports
// leave where a vertex sits on another face's edge) shelled through a surface without them.
//
// A zero-area face (a, b, m), m on the edge ab, and its neighbour across that edge, (b, a, y),
// cover the same ground as the two faces (m, a, y) and (m, y, b): flipping the edge ab to my
// gives a surface of the same solid without the zero-area face. The shell is built on that
// surface, and the flat tet (a, b, y, m) — four surface points, zero volume — glued on where the
// flip was made gives its outer boundary back the input's faces: its outward faces are (a, b, m)
// and (b, a, y), its other two the flipped faces (m, y, b) and (m, a, y) turned inward, shared
// with the shell's prisms. A face left with zero area by a flip (its neighbour had one too) is
// flipped in turn, its flat tet glued onto the earlier one's; flips onto a face with an area go
// first (a fan of zero-area faces on one line is flipped from the end where it meets one), so
// that no flip makes a face an earlier one removed, which would be a face of three tets.
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "core/base/surface_mesh.h"
#include "core/base/tet_mesh.h"

namespace vdb_shell {

/// The flips of flip_zero_area_faces().
struct ZeroAreaFlips {
  /// The surface's triangles with every zero-area face flipped away (as many as the surface's,
  /// on its points).
  std::vector<Triangle> triangles;
  /// Per triangle of `triangles`: the surface face whose ground it covers.
  std::vector<std::uint32_t> face_of;
  /// The flat tets, one per flip in the order made, each with the index of the zero-area face
  /// it keeps on the boundary (an input face, or, in a fan, the index of one an earlier flip
  /// left with zero area).
  std::vector<Tet> tets;
  std::vector<std::uint32_t> tet_face;

  bool empty() const { return tets.empty(); }
};

/// Flips the edge facing the widest angle of every zero-area face of `mesh` (twice its area at
/// most `min_twice_area`; `mesh` a closed, oriented 2-manifold but for them), see above. Empty
/// (std::nullopt) when a face has a repeated corner, a flip would join two vertices already
/// joined, or faces are left with zero area after 4 flips per zero-area face in all (corners of
/// many faces on one line, flipped round and round).
std::optional<ZeroAreaFlips> flip_zero_area_faces(const SurfaceMesh& mesh, double min_twice_area);

/// The surface `flips` makes of `mesh`: its points, the flipped triangles.
SurfaceMesh flipped_surface(const SurfaceMesh& mesh, const ZeroAreaFlips& flips);

}  // namespace vdb_shell
