// assemble.h — building the tet shell from the surface and its traced inner vertices.
//
// Every input triangle (a, b, c) and the inner vertices (a', b', c') of its corners span a
// prism, split into 3 tets without Steiner points by the rule of Dompierre, Labbe, Vallet and
// Camarero, "How to subdivide pyramids, prisms and hexahedra into tetrahedra" (IMR 1999): every
// quad side (a, b, b', a') is cut along the diagonal through its vertex with the smallest global
// index, so the two prisms sharing a quad always cut it the same way and the tet mesh is
// conforming. The smallest index of the whole prism lies on two of its quads, whose diagonals
// both start at it; the three diagonals therefore never form a cycle and a 3-tet split always
// exists (split_prism() below lists the cases). Any order of the vertices serves as well as
// their indices: with ShellInput::split_order, assemble_shell() follows that order instead.
//
// Welding: several surface vertices may share one inner vertex. Tets whose four vertices are
// then no longer distinct are dropped (Dompierre et al.'s post-processing); a prism whose three
// inner vertices are one point keeps exactly one tet, (a, b, c) with the apex. A prism with two
// welded inner corners keeps one or two tets; whether its neighbours across the collapsed side
// still meet it face to face depends on where the welded vertex lies — check_shell() tells.
//
// Orientation: the vertex order of every tet is fixed combinatorially — from its place in the
// prism, never from computed coordinates — such that the tet is positive (tet_volume > 0,
// vec3.h) whenever its prism is not inverted, i.e. (a, b, c) counter-clockwise seen from
// outside and the inner vertices on the inner side. A geometrically inverted prism therefore
// gives negative tets, which check_shell() (shell_checks.h) reports; nothing is flipped.
//
// Units: world units throughout (the input's); thickness is a length in world units.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/base/surface_mesh.h"
#include "core/base/tet_mesh.h"
#include "core/base/vec3.h"
#include "core/inner/inner.h"

namespace vdb_shell {

struct AssembleOptions {
  /// Fill TetMesh::quality with the volume-length ratio of every tet (quality.h).
  bool compute_quality = true;
  /// Layers through the thickness (--layers): every prism becomes `layers` prisms stacked along
  /// its straight side edges (split_layered_prism()), up to 3 * layers tets.
  int layers = 1;
  /// Thickness of each layer over the one outside it (--layer-ratio): geometric growth from the
  /// surface inward, as boundary-layer meshers grade their layers (layer_fractions()).
  double layer_ratio = 1.0;
};

/// Most layers assemble_shell() builds (TetMesh::layer is 8 bits; the pipeline checks --layers).
inline constexpr int kMaxLayers = 64;

/// Where the layer boundaries lie along a side edge from the surface vertex (0) to its inner
/// vertex (1): layers + 1 fractions, 0 and 1 included; each layer is `ratio` times as thick as
/// the one outside it.
std::vector<double> layer_fractions(int layers, double ratio);

/// Index of the first layer point assemble_shell() gives the shell of `surface` and `input`:
/// the points before are the surface, inner and cap points.
inline std::size_t first_layer_point(const SurfaceMesh& surface, const ShellInput& input) {
  return surface.points.size() + input.inner_points.size() + input.cap_points.size();
}

/// The shell and what assembling it did.
struct AssembleResult {
  /// points: the surface points (same indices), then inner_points (surface index count + i),
  /// then cap_points, then (layers > 1) the layer points: for every surface vertex off the
  /// surface, in vertex order, the layers - 1 points between it and its inner vertex, outermost
  /// first; tets: positive when their prism is not inverted; source_triangle, layer and
  /// (optionally) quality per tet; inner (1 for inner and layer points), thickness and
  /// surface_vertex per point.
  TetMesh mesh;
  std::size_t dropped_degenerate_tets = 0;  ///< tets with a repeated vertex, dropped
  std::size_t collapsed_prisms = 0;         ///< prisms whose three inner vertices are one
  std::size_t on_surface_vertices = 0;      ///< surface vertices with inner_id kOnSurface
  std::size_t cap_tets = 0;                 ///< tets of cap faces
  std::size_t welded_inner_vertices = 0;    ///< surface vertices - distinct inner vertices used
  std::size_t unused_inner_points = 0;      ///< inner points no surface vertex refers to
  double seconds = 0.0;                     ///< wall time of assemble_shell()
};

/// The tets of one prism, in the order of the global-index rule.
struct PrismTets {
  std::array<Tet, 3> tets{};  ///< the first `count` entries are used
  int count = 0;              ///< 3, or fewer after dropping tets with a repeated vertex
  int dropped = 0;            ///< 3 - count
};

/// Splits the prism with global vertex indices `ids` = {a, b, c, a', b', c'} into tets.
///
/// (a, b, c) is the outer triangle, counter-clockwise seen from outside; a', b', c' are the
/// inner vertices of a, b, c (on the inner side). Let V1 be the corner with the smallest index
/// (the first such corner when welded corners repeat an index), V2, V3 the other corners of its
/// triangle, V4, V5, V6 the corners joined to V1, V2, V3 by the prism's side edges. The side
/// quads through V1 are cut from V1; the third quad (V2, V3, V6, V5) is cut along V2-V6 when
/// min(V2, V6) < min(V3, V5), giving
///     (V1, V2, V3, V6), (V1, V2, V6, V5), (V1, V5, V6, V4),
/// otherwise along V3-V5, giving
///     (V1, V2, V3, V5), (V1, V5, V3, V6), (V1, V5, V6, V4).
/// V1 ranges over the six corners and the third quad has two cuts: 12 cases. The vertex order
/// of each tet is then that of its positive orientation in the right prism with the given
/// conventions. Tets with a repeated index are dropped.
PrismTets split_prism(const std::array<std::uint32_t, 6>& ids);

/// The cuts of a prism's side quads as a 3-bit mask: quad i has the corners i, i + 1 (mod 3) of
/// the outer triangle and their inner vertices; bit i is set when the quad is cut along
/// (i, (i + 1)'), from its outer corner i, and clear when along (i + 1, i'). The masks 0 and 7
/// cut the three quads in a cycle, which no 3-tet split follows; the other six each have one.
/// Two prisms sharing a quad cut it alike when their bits for it differ (each sees it the other
/// way round).
inline constexpr int kCyclicCuts[2] = {0, 7};

/// The cuts split_prism() makes (the global-index rule). \pre the six ids are distinct.
int prism_cuts(const std::array<std::uint32_t, 6>& ids);

/// Splits the prism `ids` (as split_prism()) into the 3 tets that cut its side quads as `cuts`
/// says; split_prism_cut(ids, prism_cuts(ids)) == split_prism(ids). Optimisation
/// (core/validity/optimize.h) chooses other cuts where they give better tets.
/// \pre the six ids are distinct and cuts is not one of kCyclicCuts.
PrismTets split_prism_cut(const std::array<std::uint32_t, 6>& ids, int cuts);

/// The split keys of a shell of n surface vertices and `layers` layers (assemble_shell(), the
/// validity search, the optimisation): the point of the vertex of order o at layer boundary k,
/// 0 < k < layers, and the inner point of slot `slot` (a surface point's key is its order).
inline std::uint32_t layer_point_key(std::uint32_t n, int layers, std::uint32_t o, int k) {
  return n + static_cast<std::uint32_t>(layers - 1) * o + static_cast<std::uint32_t>(k - 1);
}
inline std::uint32_t inner_point_key(std::uint32_t n, int layers, std::uint32_t slot) {
  return static_cast<std::uint32_t>(layers) * n + slot;
}

/// Splits the prism with corner ids `levels` cut into layers: levels[3 k + i] is corner i of
/// layer boundary k (k = 0: the outer triangle a, b, c; k = layers: a', b', c'; a corner on the
/// surface repeats its id at every level). Layer k + 1 is the prism between boundaries k and
/// k + 1, split by split_prism(): its side quads are cut by the global-index rule too, so
/// neighbouring prisms stay conforming layer by layer. assemble_shell() passes keys that grow
/// with depth (a layer point's above its surface vertex's, an inner point's above every layer
/// point's) and with the vertex order at each boundary: every layer then cuts a side quad
/// from the same vertex, its outer corner to the other's inner one, as a single layer does.
/// Calls emit(tet, layer) for every tet (layer 1 at the outer surface) and returns how many
/// tets were dropped.
template <class Emit>
int split_layered_prism(const std::uint32_t* levels, int layers, const Emit& emit) {
  int dropped = 0;
  for (int k = 0; k < layers; ++k) {
    const std::uint32_t* lo = levels + 3 * k;
    const PrismTets p = split_prism({lo[0], lo[1], lo[2], lo[3], lo[4], lo[5]});
    for (int i = 0; i < p.count; ++i) emit(p.tets[i], k + 1);
    dropped += p.dropped;
  }
  return dropped;
}

/// Builds the tet shell of `surface` with the inner vertices `input`.
/// \pre surface is closed and outward oriented (load_surface()); input.inner_points lie inside.
///      Neither is checked here: check_shell() (shell_checks.h) verifies the result.
/// \throw InputError if input.inner_id does not have one entry per surface vertex, an inner id
///        or a triangle index is out of range, the point count does not fit 32-bit indices, or
///        options.layers is outside [1, kMaxLayers] or options.layer_ratio is not positive.
AssembleResult assemble_shell(const SurfaceMesh& surface, const ShellInput& input,
                              const AssembleOptions& options = {});

}  // namespace vdb_shell
