// trace_points_grid.h — the traces as an OpenVDB PointDataGrid (the `traces` grid of a --grids
// file; its layout is described in trace_points.h). Includes OpenVDB: for vdb_ops/ only.
#pragma once

#include <openvdb/openvdb.h>

#include "core/trace/trace.h"
#include "vdb_ops/trace_points.h"

namespace vdb_shell {

/// The `traces` PointDataGrid of `traces` with transform `xform` (the `surface` grid's), named
/// kTracePointsGridName, carrying trace_points_metadata() and the trace parameters.
/// \throw InputError if there are more than 2^31 - 1 traces (the int32 `vertex` attribute);
///        InternalError if a stored sample is not finite.
openvdb::GridBase::Ptr make_trace_points_grid(const TraceResult& traces,
                                              const openvdb::math::Transform& xform);

}  // namespace vdb_shell
