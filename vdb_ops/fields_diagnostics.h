// fields_diagnostics.h — builds of the fields' parts for tests and benchmarks only: the seed band
// two ways (compare_seed_band()) and OpenVDB's plain narrow band, the benchmarks' floor. Not part
// of the installed API.
#pragma once

#include <cstddef>

#include "core/base/surface_mesh.h"
#include "vdb_ops/fields.h"

namespace vdb_shell {

/// The kExactInterior seed band built twice at plan_fields()'s voxel size: as build_fields()
/// builds it (its own voxelization where that applies, then meshToVolume's remaining steps) and
/// by OpenVDB's meshToVolume alone, with the voxels that differ.
struct SeedBandComparison {
  bool voxelized_here = false;          ///< false: the mesh went to meshToVolume both times
                                        ///< (fewer than 1000 triangles, or a huge triangle)
  std::size_t flood_filled = 0;         ///< triangles voxelized by a flood fill (thin, or tall
                                        ///< boxes) instead of bit rows
  std::size_t band_voxels = 0;          ///< active voxels of the band
  std::size_t differing_voxels = 0;     ///< distance, triangle or active state differ, plus one
                                        ///< per tree whose tiles differ (0 expected)
  double seconds = 0.0;                 ///< build_fields()'s band
  double seconds_mesh_to_volume = 0.0;  ///< meshToVolume's
};

/// For tests and benchmarks: see SeedBandComparison.
SeedBandComparison compare_seed_band(const SurfaceMesh& mesh, const FieldOptions& options);

/// Benchmark floor: OpenVDB's plain narrow-band meshToLevelSet (half-width 3 voxels) of `mesh`
/// at the voxel size plan_fields() derives. Returns its time (seconds_sdf, seconds_total), active
/// voxel count and memory; no fields are kept.
FieldStats build_narrow_band_reference(const SurfaceMesh& mesh, const FieldOptions& options);

}  // namespace vdb_shell
