// flap.cpp — the "flap" test shape; see flap.h.
#include "assets/flap.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "assets/shapes.h"
#include "core/base/errors.h"

namespace vdb_shell {

SurfaceMesh make_flap(int detail) {
  constexpr double kDome = 0.3;  // top height lost per squared distance from the axis
  constexpr double kFin = 0.1;   // a flap's depth below its neighbour per distance from the edge
  SurfaceMesh mesh = make_shape("box", detail);
  std::uint32_t v = UINT32_MAX;
  for (std::uint32_t i = 0; i < mesh.points.size(); ++i) {
    Vec3d& p = mesh.points[i];
    // Heights above the bottom scaled down away from the axis: the rows keep their order.
    p.z = -0.5 + (p.z + 0.5) * (1 - kDome * (p.x * p.x + p.y * p.y));
    if (p.x == 0 && p.y == 0 && p.z == 0.5) v = i;
  }
  if (v == UINT32_MAX) throw InternalError("make_flap: the box has no top centre vertex");
  // Two faces of v's fan half a turn apart, each (v, B, Q) with the face (v, A, B) before it.
  const auto at = [&](std::uint32_t f, std::uint32_t x) {  // face f rotated to start at x
    const Triangle& t = mesh.triangles[f];
    const int k = t[0] == x ? 0 : t[1] == x ? 1 : 2;
    return Triangle{t[k], t[(k + 1) % 3], t[(k + 2) % 3]};
  };
  const auto has = [&](std::uint32_t f, std::uint32_t x) {
    return std::count(mesh.triangles[f].begin(), mesh.triangles[f].end(), x) > 0;
  };
  std::vector<std::uint32_t> fan;
  for (std::uint32_t f = 0; f < mesh.triangles.size() && fan.empty(); ++f)
    if (has(f, v)) fan.push_back(f);
  for (;;) {  // the next face starts where the last one ends
    std::uint32_t next = 0;
    while (!(has(next, v) && at(next, v)[1] == at(fan.back(), v)[2])) ++next;
    if (next == fan.front()) break;
    fan.push_back(next);
  }
  for (const std::size_t k : {std::size_t{0}, fan.size() / 2}) {
    const std::uint32_t vbq = fan[k], vab = fan[(k + fan.size() - 1) % fan.size()];
    const std::uint32_t a = at(vab, v)[1], b = at(vbq, v)[1], q = at(vbq, v)[2];
    const Vec3d pv = mesh.points[v], pa = mesh.points[a], pb = mesh.points[b];
    // P: halfway between the midpoint of (v, B) and the centroid of (v, A, B), then below that
    // triangle's plane by kFin of its distance from the edge.
    const Vec3d mid = (pv + pb) * 0.5, centroid = (pv + pa + pb) / 3.0;
    const Vec3d inside = mid + (centroid - mid) * 0.5;
    const Vec3d normal = normalized(cross(pa - pv, pb - pv));
    const Vec3d edge = normalized(pb - pv);
    const Vec3d off = inside - pv;
    const double from_edge = norm(off - edge * dot(off, edge));
    const auto p = static_cast<std::uint32_t>(mesh.points.size());
    mesh.points.push_back(inside - normal * (kFin * from_edge));
    mesh.triangles[vbq] = {v, b, p};
    mesh.triangles.push_back({b, q, p});
    mesh.triangles.push_back({q, v, p});
  }
  return mesh;
}

}  // namespace vdb_shell
