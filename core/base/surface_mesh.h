// surface_mesh.h — the triangle surface every stage reads.
//
// Conventions: coordinates in the input's units and frame; triangles are counter-clockwise
// seen from outside (normals point outward) once the mesh has passed validation; vertex
// indices are 0-based.
#pragma once

#include <array>
#include <cstdint>
#include <utility>
#include <vector>

#include "core/base/vec3.h"

namespace vdb_shell {

using Triangle = std::array<std::uint32_t, 3>;

/// An indexed triangle mesh. After load_surface(): closed, 2-manifold, outward oriented.
struct SurfaceMesh {
  std::vector<Vec3d> points;        ///< vertex positions, world units
  std::vector<Triangle> triangles;  ///< vertex indices, CCW seen from outside

  std::size_t num_vertices() const { return points.size(); }
  std::size_t num_faces() const { return triangles.size(); }
};

/// Geometry helpers on a SurfaceMesh.
BBox bounding_box(const SurfaceMesh& mesh);
/// Area-weighted normal (b-a)x(c-a) of triangle f; its length is twice the area.
Vec3d face_normal_area(const SurfaceMesh& mesh, std::size_t f);
/// Signed enclosed volume (divergence theorem); positive for outward-oriented closed meshes.
double signed_volume(const SurfaceMesh& mesh);
/// The undirected edges (smaller index first), each once, sorted.
std::vector<std::pair<std::uint32_t, std::uint32_t>> unique_edges(const SurfaceMesh& mesh);
/// Mean length of the mesh's edges (each undirected edge counted once).
double mean_edge_length(const SurfaceMesh& mesh);

/// The power of two k for which 2^k times the largest coordinate magnitude of `points` lies in
/// [1, 2); 0 when there is none but 0. Scale-free computations run on points scaled by it (exact
/// both ways) so that squared lengths, areas and volumes neither overflow nor underflow,
/// whatever the input's unit.
int unit_scale_exponent(const std::vector<Vec3d>& points);
/// Multiplies `points` by 2^k, coordinate by coordinate (std::ldexp: exact unless it leaves the
/// range of normal doubles).
void scale_by_power_of_two(std::vector<Vec3d>& points, int k);

}  // namespace vdb_shell
