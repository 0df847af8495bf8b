// repair.h — --repair: a closed, 2-manifold surface rebuilt through a volume from whatever
// polygons a file holds (holes, seams stored twice, non-manifold edges, overlapping parts,
// self-intersections, flipped patches, open sheets).
//
// The input's triangles are voxelized as an unsigned distance (OpenVDB meshToVolume); the voxels
// within `closing` voxels of them are a dilated band that closes every hole and gap narrower than
// about twice that; the outside is what a flood fill from the domain's boundary reaches around
// the band; everything else is the dilated solid (overlapping parts become their union, a closed
// cavity stays a cavity). The solid is eroded back by the same distance (the distance to the
// outside, from a Euclidean distance transform that knows each outside voxel's own distance to
// the band), thin parts the erosion would remove (an open sheet) are kept as slabs about
// `closing` voxels thick, and the distance is meshed with volumeToMesh (at an iso-value just off
// zero, an adaptive mesh mended around its defects; should the mesh still have one, at a nearby
// iso-value, at a lower adaptivity, then all of that after smoothing the distance once), then
// tidied: parts enclosing less than a voxel's volume dropped, edges shorter than a tenth of a
// voxel collapsed (tidy_surface.h), so that no prism stands on a sliver. So the repaired surface
// follows a closed input within about a fifth of a voxel and spans a hole with a smooth cap.
#pragma once

#include <cstddef>
#include <string>

#include "core/read/polygon_soup.h"

namespace vdb_shell {

struct RepairOptions {
  double voxel_size = 0.0;     ///< world units, > 0
  double closing = 2.0;        ///< voxels: holes and gaps up to about twice this across are closed
  double adaptivity = 0.0;     ///< volumeToMesh's, [0, 1]
  double max_memory_gb = 8.0;  ///< the volume's estimate is checked against it
};

/// What a repair did (the report's `repair` section). Distances in input units.
struct RepairReport {
  /// The input was already a closed, 2-manifold surface not crossing itself, and was kept as it
  /// is (load_repaired_surface(): method "kept"; every distance 0): nothing was rebuilt.
  bool kept = false;
  double voxel_size = 0.0;
  double closing = 0.0;          ///< voxels
  std::size_t input_faces = 0;   ///< polygons of the input
  std::size_t faces = 0;         ///< triangles and quads of the repaired surface
  std::size_t holes_closed = 0;  ///< boundary loops of the input
  /// Specks and slivers of the contoured surface tidied away (tidy_surface.h): parts enclosing
  /// less than a voxel's volume dropped, edges shorter than a tenth of a voxel collapsed.
  std::size_t dropped_parts = 0;
  std::size_t collapsed_edges = 0;
  double distance_max = 0.0;  ///< repaired surface -> nearest input triangle
  double distance_mean = 0.0;
  /// Input vertices -> repaired surface, except those swallowed: on the enclosed solid (below)
  /// and inside the repaired surface more than a voxel from it (overlapping parts, closed gaps).
  double input_distance_max = 0.0;
  double input_distance_mean = 0.0;
  /// input_distance_max over the input vertices on the enclosed solid (within 4.5 voxels of a
  /// voxel more than a voxel deep in what the input encloses, before thin parts are added): an
  /// open sheet, kept as a slab with the sheet inside it, does not count.
  double solid_input_distance_max = 0.0;
  std::size_t solid_input_points = 0;  ///< the input vertices counted there
  double seconds = 0.0;
  /// A .vdb input (load_level_set_surface()): the grid meshed (empty for polygons), its class,
  /// the value meshed and whether its solid is where the values exceed it.
  std::string grid;
  std::string grid_class;
  double isovalue = 0.0;
  bool positive_inside = false;
};

/// The repaired surface of `input` (polygons facing outward), `name` naming it in messages.
/// \throw InputError if the input has no usable triangle, the closing swallows the model, or
///        nothing solid is left; ResourceError if the volume exceeds options.max_memory_gb.
PolygonSoup repair_surface(const PolygonSoup& input, const RepairOptions& options,
                           const std::string& name, RepairReport& report);

}  // namespace vdb_shell
