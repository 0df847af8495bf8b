// tet_mesh.h — the tetrahedral shell every writer and check reads.
//
// Conventions: coordinates in world units (the input's); every tet (a, b, c, d) is positively
// oriented: tet_volume(a, b, c, d) > 0, i.e. (a, b, c) counter-clockwise seen from outside the
// tet, the convention of VTK, Gmsh and TetGen alike.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "core/base/vec3.h"

namespace vdb_shell {

using Tet = std::array<std::uint32_t, 4>;

/// Corners of the outward-oriented face opposite corner k of a positive tet (normal by the
/// right-hand rule pointing out of the tet).
inline constexpr int kTetOutwardFace[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
/// The six edges of a tet, as corner pairs.
inline constexpr int kTetEdge[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};

struct TetMesh {
  std::vector<Vec3d> points;  ///< world units
  std::vector<Tet> tets;      ///< positively oriented

  // Optional per-element data (empty, or one entry per tet / per point).
  std::vector<double> quality;                 ///< per tet: volume-length ratio, regular = 1
  std::vector<std::uint32_t> source_triangle;  ///< per tet: index of its input triangle
  /// per tet: its layer through the thickness, 1 at the outer surface to K at the inner one
  /// (--layers K; AssembleOptions::layers)
  std::vector<std::uint8_t> layer;
  std::vector<std::uint8_t> inner;  ///< per point: 1 for traced (inner) vertices
  std::vector<double> thickness;    ///< per point: trace length, world units
  /// per point: the surface vertex it belongs to (itself for surface points; for an inner point
  /// the smallest surface vertex whose inner vertex it is)
  std::vector<std::uint32_t> surface_vertex;
};

}  // namespace vdb_shell
