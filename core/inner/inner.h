// inner.h — from traces to the inner vertices of the shell: thickness limits and welding
// (DESIGN steps 5-6, the paper's Fig. 12 and its post-processing).
//
// Each surface vertex v gets the point of its own trace at arc length
//     min(end arc, max_thickness, edge_factor * mean length of v's incident edges)
// (the limits that are set), interpolated between samples — thickness is measured along the
// trace. Trace ends (not points a limit placed mid-trace: welding could carry them past the
// limit) that meet are then welded: in vertex order, each point joins the first
// earlier representative within the weld tolerance, or becomes a representative itself (no
// chains: a welded group never spans more than the tolerance from its representative). The
// representative keeps its own position, so every inner vertex lies on a trace.
#pragma once

#include <cstddef>
#include <vector>

#include "core/assemble/assemble.h"
#include "core/trace/trace.h"

namespace vdb_shell {

struct ThicknessOptions {
  double max_thickness = 0.0;   ///< world units, along the trace; 0: no global limit
  double edge_factor = 0.0;     ///< K (paper Fig. 12): limit K * mean incident edge length;
                                ///< 0: no local limit
  double weld_tolerance = -1.0; ///< world units; negative: half the point size; 0: no welding
};

struct InnerVertices {
  ShellInput input;                 ///< inner points and the inner vertex of each surface vertex
  std::vector<double> arc;          ///< per surface vertex: arc length at its inner point
  std::size_t limited = 0;          ///< vertices whose thickness a limit shortened
  std::size_t welded = 0;           ///< surface vertices sharing another's inner vertex
};

/// \throw InputError for negative or non-finite limits.
InnerVertices place_inner_vertices(const SurfaceMesh& mesh, const TraceResult& traces,
                                   const ThicknessOptions& options);

/// Point of trace v at arc length `s` (clamped to the trace), interpolated linearly.
Vec3d point_at_arc(const TraceResult& traces, std::size_t v, double s);

}  // namespace vdb_shell
