// surface_mesh.cpp — geometry helpers on SurfaceMesh.
#include "core/base/surface_mesh.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace vdb_shell {

BBox bounding_box(const SurfaceMesh& mesh) {
  BBox box;
  for (const Vec3d& p : mesh.points) box.expand(p);
  return box;
}

Vec3d face_normal_area(const SurfaceMesh& mesh, std::size_t f) {
  const Triangle& t = mesh.triangles[f];
  const Vec3d& a = mesh.points[t[0]];
  return cross(mesh.points[t[1]] - a, mesh.points[t[2]] - a);
}

double signed_volume(const SurfaceMesh& mesh) {
  // Sum of tets (origin-shifted to the first vertex for accuracy far from the origin).
  if (mesh.points.empty()) return 0.0;
  const Vec3d o = mesh.points.front();
  double v = 0.0;
  for (const Triangle& t : mesh.triangles)
    v += dot(mesh.points[t[0]] - o, cross(mesh.points[t[1]] - o, mesh.points[t[2]] - o));
  return v / 6.0;
}

std::vector<std::pair<std::uint32_t, std::uint32_t>> unique_edges(const SurfaceMesh& mesh) {
  std::vector<std::pair<std::uint32_t, std::uint32_t>> edges;
  edges.reserve(mesh.triangles.size() * 3);
  for (const Triangle& t : mesh.triangles)
    for (int k = 0; k < 3; ++k)
      edges.emplace_back(std::min(t[k], t[(k + 1) % 3]), std::max(t[k], t[(k + 1) % 3]));
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  return edges;
}

double mean_edge_length(const SurfaceMesh& mesh) {
  const auto edges = unique_edges(mesh);
  if (edges.empty()) return 0.0;
  double sum = 0.0;
  for (const auto& e : edges) sum += distance(mesh.points[e.first], mesh.points[e.second]);
  return sum / static_cast<double>(edges.size());
}

int unit_scale_exponent(const std::vector<Vec3d>& points) {
  double largest = 0.0;
  for (const Vec3d& p : points)
    largest = std::max({largest, std::abs(p.x), std::abs(p.y), std::abs(p.z)});
  return largest > 0.0 && std::isfinite(largest) ? -std::ilogb(largest) : 0;
}

void scale_by_power_of_two(std::vector<Vec3d>& points, int k) {
  for (Vec3d& p : points) p = {std::ldexp(p.x, k), std::ldexp(p.y, k), std::ldexp(p.z, k)};
}

}  // namespace vdb_shell
