// point_index_vdb.h — the merge queries' point index over OpenVDB's tools::PointIndexGrid (the
// paper's spatial hashing; the trace stage's merges, docs/architecture.md).
//
// Implements core's PointIndex (core/trace/point_index.h); no OpenVDB header is included here. The
// points are bucketed into a PointIndexGrid with cubic voxels of edge `radius` (world units);
// find_within_unordered() runs a radial tools::PointIndexIterator search with a slightly larger
// radius and keeps the points with |point - p|^2 <= radius^2, evaluated in double precision in
// world space: after sorting (find_within()), exactly the indices make_hash_point_index()
// returns for the same query.
//
// Space: positions and radii are world coordinates and world units (the input mesh's frame).
// Threads: const queries may run concurrently; each builds its own ValueAccessor and iterator.
// The index keeps its own copy of the points.
#pragma once

#include <memory>
#include <vector>

#include "core/base/vec3.h"
#include "core/trace/point_index.h"

namespace vdb_shell {

/// Builds a PointIndexGrid over `points` (world coordinates).
/// \param radius  the query radius the caller will use, world units: the grid's voxel edge
///                (non-positive or non-finite: 1).
/// \throw InputError if a point is not finite or the points lie too far from the origin for
///        OpenVDB's 32-bit index coordinates at this voxel size.
std::unique_ptr<PointIndex> make_vdb_point_index(const std::vector<Vec3d>& points, double radius);

}  // namespace vdb_shell
