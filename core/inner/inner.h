// inner.h — from traces to the inner vertices of the shell: thickness limits and welding
// (the paper's Fig. 12 and its post-processing).
//
// Each surface vertex v gets the point of its own trace at arc length
//     min(end arc, max_thickness, edge_factor * mean length of v's incident edges)
// (the limits that are set), interpolated between samples — thickness is measured along the
// trace. Trace ends (not points a limit placed mid-trace: welding could carry them past the
// limit) that meet are then welded: in vertex order, each point joins the first
// earlier representative within the weld tolerance whose position is within the point's own
// limit (straight-line distance from its surface vertex: the thickness the shell shows), or
// becomes a representative itself (no chains: a welded group never spans more than the
// tolerance from its representative). The representative keeps its own position, so every
// inner vertex lies on a trace.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/trace/trace.h"

namespace vdb_shell {

/// The inner side of the shell: where every surface vertex ended its inward trace.
struct ShellInput {
  /// Inner vertex positions, world units. Several surface vertices may share one (welded).
  std::vector<Vec3d> inner_points;
  /// Per surface vertex v: index into inner_points of v's inner vertex, or kOnSurface. Size
  /// num_vertices().
  std::vector<std::uint32_t> inner_id;
  /// Faces whose three corners are kOnSurface, each with one extra inner point below it: the
  /// face's prism is the single tet from the face to that point (ascending faces).
  std::vector<std::uint32_t> cap_faces;
  std::vector<Vec3d> cap_points;  ///< one per cap face, after inner_points in the tet mesh
  /// Empty, or per surface vertex its place in the order the prisms' global-index rule follows
  /// instead of the vertex order (a permutation; assemble.h): the validity search places a
  /// vertex that follows an edge's end right after it, so that the sliver prisms between them
  /// cut their two nearly coincident side quads alike, and orders a cap's base ends so that
  /// their side quad is cut the way it bends towards the cap (docs/validity.md, step 6).
  std::vector<std::uint32_t> split_order;
};

/// inner_id of a vertex that is its own inner vertex: the shell has zero thickness there and its
/// prisms become pyramids (two tets) or, with two such corners, one tet. A face with three such
/// corners has no prism, unless it is a cap face (ShellInput::cap_faces).
constexpr std::uint32_t kOnSurface = 0xFFFFFFFFu;

struct ThicknessOptions {
  double max_thickness = 0.0;    ///< world units, along the trace; 0: no global limit
  double edge_factor = 0.0;      ///< K (paper Fig. 12): limit K * mean incident edge length;
                                 ///< 0: no local limit
  double weld_tolerance = -1.0;  ///< world units; negative: half the point size; 0: no welding
};

struct InnerVertices {
  ShellInput input;         ///< inner points and the inner vertex of each surface vertex
  std::vector<double> arc;  ///< per surface vertex: arc length at its inner point
  /// Per surface vertex: the largest distance its inner vertex may have from it (the thickness
  /// limits; infinity: none). Every inner point placed here, welded or not, is within it.
  std::vector<double> limit;
  /// Per surface vertex (or empty): what its inner direction must satisfy beyond pointing
  /// inward for its faces, as normals n with -n.d > 0 (SectorSplit::constraints).
  std::vector<std::vector<Vec3d>> constraints;
  std::size_t limited = 0;  ///< vertices whose thickness a limit shortened
  std::size_t welded = 0;   ///< surface vertices sharing another's inner vertex
};

/// Peak bytes per surface vertex of place_inner_vertices(): its limit, arc, end point, weld
/// flags and ids, its inner point and the weld index's cells. Measured: 62-147 bytes per vertex
/// (fandisk, fertility, spot, knight, torus, box, bowl, propeller, flap; fewer where many trace
/// ends weld together).
inline constexpr std::size_t kInnerBytesPerVertex = 224;

/// Estimated peak bytes of place_inner_vertices() on `mesh` (kInnerBytesPerVertex per point).
inline std::size_t estimate_inner_bytes(const SurfaceMesh& mesh) {
  return mesh.points.size() * kInnerBytesPerVertex;
}

/// \param vertex  empty, or per point of `mesh` the vertex it is (a split surface's copies,
///                SectorSplit::vertex): the edge-factor limit of a copy is its vertex's, over
///                the whole fan.
/// \throw InputError for negative or non-finite limits.
InnerVertices place_inner_vertices(const SurfaceMesh& mesh, const TraceResult& traces,
                                   const ThicknessOptions& options,
                                   const std::vector<std::uint32_t>& vertex = {});

/// Point of trace v at arc length `s` (clamped to the trace), interpolated linearly.
Vec3d point_at_arc(const TraceResult& traces, std::size_t v, double s);

}  // namespace vdb_shell
