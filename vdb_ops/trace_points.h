// trace_points.h — the traces as OpenVDB points: a PointDataGrid named `traces` in the --grids
// file, loadable by Houdini, vdb_print and any OpenVDB points reader.
//
// One point per trace sample from sample 0 (the surface vertex) up to and including the trace's
// end sample (TraceResult::end; samples past it are not stored), with the attributes
//   P            Vec3f, uncompressed (NullCodec): the sample position (world units; stored by
//                OpenVDB as a float offset from its voxel centre, so exact to float rounding of
//                a fraction of a voxel)
//   arc_length   float: length along the trace from the surface vertex, world units (eq. 5)
//   stop_reason  int32, per trace: 0 critical, 1 merge, 2 flux, 3 cap (StopReason)
//   planar       int32, per trace: 1 planar vertex, 0 non-planar (classify_vertices)
//   vertex       int32: index of the surface vertex the trace starts from
//   sample       int32: index of the sample along its trace, 0 = the surface vertex
// The grid's transform is the `surface` grid's (world units = input units). Its metadata
// describes every attribute and code (kTracePointsMetadata) and repeats the trace parameters.
//
// Order: OpenVDB stores points leaf by leaf (the tree's order), within a leaf voxel by voxel,
// and within a voxel in the order of the input array, which is (vertex, sample): the
// tools::PointPartitioner sort is stable. The grid and the file are therefore the same for any
// thread count.
//
// This header includes no OpenVDB header; the grid itself is made by make_trace_points_grid()
// (trace_points_grid.h), which write_grids() uses to write it in the same atomic file as the
// fields.
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "core/base/vec3.h"
#include "core/trace/trace.h"

namespace vdb_shell {

/// Name of the points grid in a --grids file.
inline constexpr const char* kTracePointsGridName = "traces";

/// Grid metadata of the `traces` grid (name -> text): one entry per attribute and its codes.
const std::vector<std::pair<std::string, std::string>>& trace_points_metadata();

/// Points the `traces` grid holds for `traces`: the sum over traces of (end + 1).
std::size_t trace_point_count(const TraceResult& traces);

/// Peak bytes per point of write_grids()'s `traces` grid: the gathered arrays (44 bytes), the
/// point index grid and the partitioner's order, and the grid's own attributes (32 bytes); the
/// fields are shared, not copied.
inline constexpr std::size_t kTracePointBytes = 128;

/// Estimated peak bytes write_grids() allocates for the `traces` grid of `traces`.
inline std::size_t estimate_trace_points_bytes(const TraceResult& traces) {
  return trace_point_count(traces) * kTracePointBytes;
}

/// The `traces` grid of a .vdb file as plain arrays, one entry per point in stored order.
struct TracePoints {
  std::vector<Vec3d> positions;                 ///< world units
  std::vector<float> arc_length;                ///< world units
  std::vector<std::int32_t> stop_reason;        ///< StopReason codes 0..3
  std::vector<std::int32_t> planar;             ///< 1 planar, 0 non-planar
  std::vector<std::int32_t> vertex;             ///< surface vertex index
  std::vector<std::int32_t> sample;             ///< sample index along the trace
  double voxel_size = 0.0;                      ///< world units (x axis of the grid's transform)
  std::vector<std::string> attributes;          ///< attribute names in descriptor order ("P" first)
  std::map<std::string, std::string> metadata;  ///< every grid metadata item, as text
};

/// Reads the points grid `grid_name` of `vdb_path` with the OpenVDB API.
/// \throw InputError naming the file if it is missing or unreadable, has no such grid, the grid
///        is not a PointDataGrid, or an attribute above is missing or of another type.
TracePoints read_trace_points(const std::string& vdb_path,
                              const std::string& grid_name = kTracePointsGridName);

}  // namespace vdb_shell
