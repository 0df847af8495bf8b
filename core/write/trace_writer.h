// trace_writer.h — the traces as legacy VTK polydata, for inspection in ParaView.
//
// One polyline per surface vertex from its surface point to its end sample; point data
// `arc_length` (world units); cell data `stop_reason` (0 critical, 1 merge, 2 flux, 3 cap) and
// `planar` (0/1). Written atomically.
#pragma once

#include <string>

#include "core/trace/trace.h"

namespace vdb_shell {

/// \throw ResourceError when the file cannot be written.
void write_paths_vtk(const std::string& path, const TraceResult& traces);

}  // namespace vdb_shell
