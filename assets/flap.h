// flap.h — the "flap" test shape (shapes.h): a folded vertex, as adaptive meshing and scans
// produce them.
#pragma once

#include "core/base/surface_mesh.h"

namespace vdb_shell {

/// The cube of make_shape("box", detail) with its top domed (heights above the bottom scaled by
/// 1 - 0.3 (x^2 + y^2)) and two thin triangular flaps lifted off it at the top's centre v, half a
/// turn apart: each splits a top triangle (v, B, Q) at a new vertex P and pushes P across the
/// edge (v, B), 0.1 of its distance from that edge below the neighbouring triangle (v, A, B).
/// Each triangle (v, B, P) then faces down: a fin of material 5.7 degrees thick between it and
/// (v, A, B), over a crack that opens towards Q. The fan normals of v fit in no hemisphere.
/// Closed, 2-manifold, outward, free of crossings; 48 N^2 + 4 faces.
SurfaceMesh make_flap(int detail);

}  // namespace vdb_shell
