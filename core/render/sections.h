// sections.h — axis-aligned cross-sections of a shell as SVG, for the HTML report: the region
// the surface encloses (the uncovered interior's colour), the shell's tets cut by the plane
// coloured by quality over it, and the surface's outline on top.
#pragma once

#include <string>

#include "core/base/surface_mesh.h"
#include "core/base/tet_mesh.h"
#include "core/base/vec3.h"

namespace vdb_shell {

inline constexpr const char* kUncoveredColour = "#e3e3e3";

/// Picture axes of the section normal to world axis `axis` (0 x, 1 y, 2 z): the world axes
/// drawn to the right and up.
struct SectionAxes {
  int u, v;
};
SectionAxes section_axes(int axis);

/// An inline <svg> element of the section of `surface` and `mesh` by the plane {p[axis] = at},
/// `bounds` (the frame, usually the surface's box) fitted into `width_px` x `height_px` at its
/// proportions (the SVG is as large as the fitted frame). A vertex exactly on the plane counts as
/// above it, so the outline is a set of closed loops on any closed surface. Tets are coloured by
/// ColourMap::quality() in 20 classes of mesh.quality (the whole tet set of one class is one path).
std::string section_svg(const SurfaceMesh& surface, const TetMesh& mesh, int axis, double at,
                        const BBox& bounds, int width_px, int height_px);

}  // namespace vdb_shell
