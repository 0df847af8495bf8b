// pictures.h — the HTML report's pictures of a shell (core/render/raster.h draws them): the
// shell cut away in front of a plane, a surface coloured per corner, the traces in an x-ray view.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "core/base/surface_mesh.h"
#include "core/base/tet_mesh.h"
#include "core/render/raster.h"
#include "core/trace/trace.h"

namespace vdb_shell {

inline constexpr Rgb kBackground{255, 255, 255};
inline constexpr Rgb kOuterColour{150, 178, 214};  ///< the input surface
inline constexpr Rgb kInnerColour{226, 150, 84};   ///< the inner surface
/// Trace colours by StopReason (critical, merge, flux, cap).
inline constexpr std::array<Rgb, 4> kStopColour = {Rgb{31, 119, 180}, Rgb{255, 127, 14},
                                                   Rgb{44, 160, 44}, Rgb{214, 39, 40}};

/// What a cut-away needs of the shell's topology, computed once: per tet face (4 t + k, the face
/// opposite corner k) the tet on its other side or -1, and for the faces with none whether the
/// face is one of the surface's triangles (the outer side) or not (the inner side).
struct ShellFaces {
  std::vector<std::int64_t> neighbour;
  std::vector<std::uint8_t> outer;
};
/// \pre the surface's points are the shell's first points (ShellResult::mesh).
ShellFaces shell_faces(const TetMesh& mesh, const SurfaceMesh& surface);

/// The shell seen through `camera` with every tet whose centroid is on the positive side of the
/// plane (point `at`, normal `cut`) removed: the input surface and the inner surface in their
/// colours, the faces the cut exposes coloured by their tet's quality (ColourMap::quality()),
/// with the tet edges drawn where they are large enough to see.
Image render_cut_away(const TetMesh& mesh, const ShellFaces& faces, const Camera& camera,
                      const Vec3d& at, const Vec3d& cut, int supersample);

/// `surface` seen through `camera`, shaded, corner k of triangle t coloured corner_colour[3t+k].
Image render_surface(const SurfaceMesh& surface, const std::vector<Rgb>& corner_colour,
                     const Camera& camera, int supersample);

/// Which traces render_traces() draws: every trace_stride()-th of `traces`, at most `max_traces`.
inline std::size_t trace_stride(std::size_t traces, std::size_t max_traces) {
  return max_traces > 0 && traces > max_traces ? (traces + max_traces - 1) / max_traces : 1;
}

/// The traces of at most `max_traces` surface vertices (every trace_stride()-th) as polylines
/// coloured by stop reason (kStopColour) over a faded picture of the surface, from the surface
/// vertex to the end.
Image render_traces(const SurfaceMesh& surface, const TraceResult& traces, const Camera& camera,
                    std::size_t max_traces, int supersample);

}  // namespace vdb_shell
