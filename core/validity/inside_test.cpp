// inside_test.cpp — see inside_test.h; also point_outside_surface() of shell_checks.h.
#include "core/validity/inside_test.h"

#include <algorithm>
#include <cmath>

#include "core/base/geometry.h"
#include "core/base/parallel.h"
#include "core/validity/shell_checks.h"

namespace vdb_shell {
namespace {

// A ray from `p` towards +axis; (u, v) are the two other coordinates; eps in world units.
struct Ray {
  int axis, u, v;
  Vec3d p;
  double eps;
};

enum class RayHit { kMiss, kCross, kGraze };

// How `ray` meets triangle (a, b, c): it crosses the triangle's interior, misses it, or grazes
// it (passes within eps of an edge, which covers meeting it seen edge-on).
RayHit ray_meets(const Ray& ray, const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  const int u = ray.u, v = ray.v;
  const double eps = ray.eps, pu = ray.p[u], pv = ray.p[v];
  // Signed distances (2D) of the projected point from the projected edges, positive inside.
  const double au = a[u], av = a[v], bu = b[u], bv = b[v], cu = c[u], cv = c[v];
  const double d = (bu - au) * (cv - av) - (bv - av) * (cu - au);
  // Lengths by sqrt, not std::hypot (several times slower): the squares overflow only for
  // coordinates over 1e154, where the tets' own squared lengths (tet_geometry()) already would.
  const auto length = [](double x, double y) { return std::sqrt(x * x + y * y); };
  const double l_bc = length(cu - bu, cv - bv), l_ca = length(au - cu, av - cv),
               l_ab = length(bu - au, bv - av);
  const double l_max = std::max({l_bc, l_ca, l_ab});
  if (std::abs(d) <= eps * l_max) {
    // Seen edge-on: the projection is no wider than eps (d / l_max), so the ray meets the
    // triangle only if it passes within eps of a projected edge; it grazes it then.
    const auto to_edge2 = [&](double xu, double xv, double yu, double yv) {
      const double eu = yu - xu, ev = yv - xv, e2 = eu * eu + ev * ev;
      const double t =
          e2 > 0.0 ? std::clamp(((pu - xu) * eu + (pv - xv) * ev) / e2, 0.0, 1.0) : 0.0;
      const double du = pu - xu - t * eu, dv = pv - xv - t * ev;
      return du * du + dv * dv;
    };
    const double near2 =
        std::min({to_edge2(au, av, bu, bv), to_edge2(bu, bv, cu, cv), to_edge2(cu, cv, au, av)});
    return near2 <= eps * eps ? RayHit::kGraze : RayHit::kMiss;
  }
  const double s = d > 0.0 ? 1.0 : -1.0;
  const double w0 = (cu - bu) * (pv - bv) - (cv - bv) * (pu - bu);
  const double w1 = (au - cu) * (pv - cv) - (av - cv) * (pu - cu);
  const double w2 = (bu - au) * (pv - av) - (bv - av) * (pu - au);
  const double e0 = s * w0 / l_bc, e1 = s * w1 / l_ca, e2 = s * w2 / l_ab;
  const double e_min = std::min({e0, e1, e2});
  if (e_min < -eps) return RayHit::kMiss;
  // Where the ray meets the triangle's plane, above a (w0 + w1 + w2 = d): differences only,
  // which stay exact far from the origin.
  const int x = ray.axis;
  const double z = (w1 * (b[x] - a[x]) + w2 * (c[x] - a[x])) / d;
  if (z <= ray.p[x] - a[x]) return RayHit::kMiss;
  return e_min <= eps ? RayHit::kGraze : RayHit::kCross;
}

}  // namespace

long InsideTester::ColumnGrid::cell_u(double x) const {
  return std::clamp(static_cast<long>(std::floor((x - lo_u) * inv_cell)), 0L, nu - 1);
}

long InsideTester::ColumnGrid::cell_v(double x) const {
  return std::clamp(static_cast<long>(std::floor((x - lo_v) * inv_cell)), 0L, nv - 1);
}

InsideTester::InsideTester(const SurfaceMesh& surface, double tolerance)
    : surface_(surface), tolerance_(tolerance) {
  // The three axes' grids are independent: built side by side.
  for_each_chunk(
      3,
      [&](std::size_t begin, std::size_t end) {
        for (std::size_t axis = begin; axis != end; ++axis) build(static_cast<int>(axis));
      },
      1);
}

bool InsideTester::outside(const Vec3d& p) const {
  RayVerdict verdict = cast_rays(p);
  if (verdict == RayVerdict::kAmbiguous) {
    // p is farther than the tolerance from the surface (a ray's column lists every triangle
    // that near, and each was measured), so a point q within p's clearance lies on p's side:
    // the segment pq meets no triangle. Directions away from the axes and their diagonals.
    static constexpr std::array<Vec3d, 3> kAway = {Vec3d{0.5401, 0.7318, 0.4157},
                                                   Vec3d{-0.6923, 0.2549, 0.6751},
                                                   Vec3d{0.3137, -0.8571, 0.4086}};
    const double r = 0.5 * clearance(p);
    for (std::size_t k = 0; k < kAway.size() && verdict == RayVerdict::kAmbiguous; ++k) {
      verdict = cast_rays(p + r / norm(kAway[k]) * kAway[k]);
      if (verdict == RayVerdict::kOnSurface) verdict = RayVerdict::kAmbiguous;  // q, not p
    }
  }
  switch (verdict) {
    case RayVerdict::kInside:
    case RayVerdict::kOnSurface:
      return false;
    case RayVerdict::kOutside:
      return true;
    case RayVerdict::kAmbiguous:
      break;
  }
  double winding = 0.0;
  for (const Triangle& t : surface_.triangles)
    winding += solid_angle(p, surface_.points[t[0]], surface_.points[t[1]], surface_.points[t[2]]);
  // The winding number's parity, as the rays' (it is 0 or 1 on an outward surface; 2 inside
  // two nested components facing the same way, which is outside by parity).
  return std::llround(winding / (4.0 * kPi)) % 2 == 0;
}

void InsideTester::build(int axis) {
  ColumnGrid& g = grids_[axis];
  g.u = (axis + 1) % 3;
  g.v = (axis + 2) % 3;
  const BBox box = bounding_box(surface_);
  const std::size_t n_faces = surface_.triangles.size();
  if (box.empty() || n_faces == 0) {
    g.start.assign(2, 0);
    return;
  }
  const double eps = tolerance_;
  g.lo_u = box.lo[g.u] - eps;
  g.lo_v = box.lo[g.v] - eps;
  const double ext_u = box.hi[g.u] - box.lo[g.u] + 2 * eps;
  const double ext_v = box.hi[g.v] - box.lo[g.v] + 2 * eps;
  // About one triangle per cell, at most 2048 cells a side.
  double cell = std::sqrt(ext_u * ext_v / static_cast<double>(n_faces));
  cell = std::max({cell, ext_u / 2048.0, ext_v / 2048.0});
  if (!(cell > 0.0)) cell = std::max({ext_u, ext_v, 1.0});
  g.inv_cell = 1.0 / cell;
  g.nu = std::clamp(static_cast<long>(std::ceil(ext_u / cell)), 1L, 2048L);
  g.nv = std::clamp(static_cast<long>(std::ceil(ext_v / cell)), 1L, 2048L);

  // Counting sort of the triangles into the cells their projected boxes (grown by eps) cover.
  std::vector<std::array<long, 4>> range(n_faces);  // cell ranges per triangle
  g.start.assign(static_cast<std::size_t>(g.nu * g.nv) + 1, 0);
  for (std::size_t f = 0; f < n_faces; ++f) {
    const Triangle& t = surface_.triangles[f];
    double lu = INFINITY, hu = -INFINITY, lv = INFINITY, hv = -INFINITY;
    for (const std::uint32_t i : t) {
      lu = std::min(lu, surface_.points[i][g.u]);
      hu = std::max(hu, surface_.points[i][g.u]);
      lv = std::min(lv, surface_.points[i][g.v]);
      hv = std::max(hv, surface_.points[i][g.v]);
    }
    range[f] = {g.cell_u(lu - eps), g.cell_u(hu + eps), g.cell_v(lv - eps), g.cell_v(hv + eps)};
    for (long iu = range[f][0]; iu <= range[f][1]; ++iu)
      for (long iv = range[f][2]; iv <= range[f][3]; ++iv)
        ++g.start[static_cast<std::size_t>(iu * g.nv + iv) + 1];
  }
  for (std::size_t c = 1; c < g.start.size(); ++c) g.start[c] += g.start[c - 1];
  g.items.resize(g.start.back());
  std::vector<std::uint32_t> fill(g.start.begin(), g.start.end() - 1);
  for (std::size_t f = 0; f < n_faces; ++f)
    for (long iu = range[f][0]; iu <= range[f][1]; ++iu)
      for (long iv = range[f][2]; iv <= range[f][3]; ++iv)
        g.items[fill[static_cast<std::size_t>(iu * g.nv + iv)]++] = static_cast<std::uint32_t>(f);
}

InsideTester::RayVerdict InsideTester::cast_ray(int axis, const Vec3d& p) const {
  const ColumnGrid& g = grids_[axis];
  const Ray ray{axis, g.u, g.v, p, tolerance_};
  const double eps = tolerance_;
  const double pu = p[g.u], pv = p[g.v];
  if (pu < g.lo_u || pv < g.lo_v || pu > g.lo_u + static_cast<double>(g.nu) / g.inv_cell ||
      pv > g.lo_v + static_cast<double>(g.nv) / g.inv_cell)
    return RayVerdict::kOutside;
  const std::size_t cell = static_cast<std::size_t>(g.cell_u(pu) * g.nv + g.cell_v(pv));
  int crossings = 0;
  bool ambiguous = false;
  for (std::uint32_t k = g.start[cell]; k < g.start[cell + 1]; ++k) {
    const Triangle& t = surface_.triangles[g.items[k]];
    const Vec3d& a = surface_.points[t[0]];
    const Vec3d& b = surface_.points[t[1]];
    const Vec3d& c = surface_.points[t[2]];
    const Vec3d lo = min_of(a, min_of(b, c)), hi = max_of(a, max_of(b, c));
    if (hi[axis] + eps < p[axis]) continue;  // entirely behind the ray's origin
    if (p.x >= lo.x - eps && p.x <= hi.x + eps && p.y >= lo.y - eps && p.y <= hi.y + eps &&
        p.z >= lo.z - eps && p.z <= hi.z + eps && point_triangle_distance2(p, a, b, c) <= eps * eps)
      return RayVerdict::kOnSurface;
    if (ambiguous) continue;  // only an on-surface hit can still decide
    switch (ray_meets(ray, a, b, c)) {
      case RayHit::kCross:
        ++crossings;
        break;
      case RayHit::kGraze:
        ambiguous = true;
        break;
      case RayHit::kMiss:
        break;
    }
  }
  if (ambiguous) return RayVerdict::kAmbiguous;
  return crossings % 2 == 1 ? RayVerdict::kInside : RayVerdict::kOutside;
}

InsideTester::RayVerdict InsideTester::cast_rays(const Vec3d& p) const {
  for (int axis = 0; axis < 3; ++axis)
    if (const RayVerdict verdict = cast_ray(axis, p); verdict != RayVerdict::kAmbiguous)
      return verdict;
  return RayVerdict::kAmbiguous;
}

double InsideTester::clearance(const Vec3d& p) const {
  // A triangle listed in none of the 3 x 3 cells has its projected box (grown by the tolerance)
  // more than a cell's width from p's projection on one coordinate.
  const ColumnGrid& g = grids_[0];
  double r2 = 1.0 / (g.inv_cell * g.inv_cell);
  const long cu = g.cell_u(p[g.u]), cv = g.cell_v(p[g.v]);
  for (long iu = std::max(cu - 1, 0L); iu <= std::min(cu + 1, g.nu - 1); ++iu)
    for (long iv = std::max(cv - 1, 0L); iv <= std::min(cv + 1, g.nv - 1); ++iv) {
      const std::size_t cell = static_cast<std::size_t>(iu * g.nv + iv);
      for (std::uint32_t k = g.start[cell]; k < g.start[cell + 1]; ++k) {
        const Triangle& t = surface_.triangles[g.items[k]];
        r2 = std::min(r2, point_triangle_distance2(p, surface_.points[t[0]], surface_.points[t[1]],
                                                   surface_.points[t[2]]));
      }
    }
  return std::sqrt(r2);
}

bool point_outside_surface(const SurfaceMesh& surface, const Vec3d& p, double tolerance) {
  return InsideTester(surface, tolerance).outside(p);
}

}  // namespace vdb_shell
