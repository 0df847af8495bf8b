// zero_area.h — closed surfaces with zero-area faces (three corners on one line, as CAD exports
// leave where a vertex sits on another face's edge), or slivers folded over their neighbours,
// shelled through a surface without them.
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
// that no flip makes a face an earlier one removed, which would be a face of three tets. Slivers
// folded over their neighbours by rounding (SliverFlips) are flipped the same way; their flat
// tets have the sliver's thickness.
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
  /// How many of the flips were of slivers (SliverFlips) rather than of zero-area faces.
  std::size_t slivers = 0;

  bool empty() const { return tets.empty(); }
};

/// Slivers flipped like zero-area faces: faces with an area whose corner m facing the longest
/// edge ab lies within `max_height` of ab's line (rounding leaves them where a vertex sits on or
/// next to another face's edge, and they can fold over their neighbours: a surface crossing
/// itself), with a corner among `near` (where the surface crosses itself). Only where the flip
/// is sound: m between a and b as seen from the face (b, a, y) across ab, so that the two faces
/// made face as it does, and not above that face's plane, so that the flat tet (a, b, y, m) —
/// the volume between the sliver, its neighbour and the two faces made — is not inverted.
struct SliverFlips {
  double max_height = 0;   ///< 0: zero-area faces only
  std::vector<char> near;  ///< per point of the surface
  double tolerance = 0;    ///< a point this near a plane counts as on it
};

/// Flips the edge facing the widest angle of every zero-area face of `mesh` (twice its area at
/// most `min_twice_area`; `mesh` a closed, oriented 2-manifold but for them), and of every sliver
/// `slivers` admits, see above. Empty (std::nullopt) when a face has a repeated corner, a flip
/// would join two vertices already joined, or faces are left to flip after 4 flips per face in
/// all (corners of many faces on one line, flipped round and round).
std::optional<ZeroAreaFlips> flip_zero_area_faces(const SurfaceMesh& mesh, double min_twice_area,
                                                  const SliverFlips& slivers = {});

/// The surface `flips` makes of `mesh`: its points, the flipped triangles.
SurfaceMesh flipped_surface(const SurfaceMesh& mesh, const ZeroAreaFlips& flips);

}  // namespace vdb_shell
