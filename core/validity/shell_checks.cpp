// shell_checks.cpp — see shell_checks.h.
//
// Methods:
//   * point in surface: parity of the crossings of an axis-parallel ray, found in a 2D grid of
//     the triangles' projections (one grid per axis). A ray that passes within the tolerance of
//     a triangle edge is ambiguous and the next axis is tried; after three ambiguous axes the
//     generalized winding number over all triangles decides. Points within the tolerance of a
//     triangle (exact point-triangle distance) are on the surface.
//   * tet-tet overlap: a uniform grid (cells about the size of a cube of the mean tet volume) in
//     which every tet enters the cells its face planes do not separate from it; the pairs of
//     tets sharing a cell, with overlapping boxes, go to the separating axis theorem with the
//     4 + 4 face normals and the 36 edge-edge cross products.
//   * boundary faces: the 4T tet faces sorted by their vertex triples.
#include "core/validity/shell_checks.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <memory>
#include <sstream>

#include "core/base/errors.h"
#include "core/base/parallel.h"
#include "core/base/timer.h"

namespace vdb_shell {
namespace {

void list_item(std::vector<std::uint32_t>& list, std::size_t max_listed, std::size_t item) {
  if (list.size() < max_listed) list.push_back(static_cast<std::uint32_t>(item));
}

// ---------------------------------------------------------------------------------------------
// Point in closed surface.

// Squared distance from p to triangle (a, b, c) (Ericson, Real-Time Collision Detection 5.1.5).
double point_triangle_distance2(const Vec3d& p, const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  const Vec3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0.0 && d2 <= 0.0) return norm2(ap);
  const Vec3d bp = p - b;
  const double d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0.0 && d4 <= d3) return norm2(bp);
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return norm2(ap - ab * (d1 / (d1 - d3)));
  const Vec3d cp = p - c;
  const double d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0.0 && d5 <= d6) return norm2(cp);
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return norm2(ap - ac * (d2 / (d2 - d6)));
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0)
    return norm2(bp - (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6))));
  const double denom = va + vb + vc;
  if (!(denom != 0.0)) return std::min({norm2(ap), norm2(bp), norm2(cp)});
  const double v = vb / denom, w = vc / denom;
  return norm2(ap - ab * v - ac * w);
}

// Solid angle of triangle (a, b, c) seen from p, signed (Van Oosterom and Strackee 1983).
double solid_angle(const Vec3d& p, const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  const Vec3d x = a - p, y = b - p, z = c - p;
  const double lx = norm(x), ly = norm(y), lz = norm(z);
  const double num = dot(x, cross(y, z));
  const double den = lx * ly * lz + dot(x, y) * lz + dot(y, z) * lx + dot(z, x) * ly;
  return 2.0 * std::atan2(num, den);
}

enum class RayVerdict { kInside, kOutside, kOnSurface, kAmbiguous };

class InsideTester {
 public:
  InsideTester(const SurfaceMesh& surface, double tolerance)
      : surface_(surface), tolerance_(tolerance) {
    for (int axis = 0; axis < 3; ++axis) build(axis);
  }

  bool outside(const Vec3d& p) const {
    for (int axis = 0; axis < 3; ++axis) {
      switch (cast_ray(axis, p)) {
        case RayVerdict::kInside:
        case RayVerdict::kOnSurface:
          return false;
        case RayVerdict::kOutside:
          return true;
        case RayVerdict::kAmbiguous:
          break;
      }
    }
    double winding = 0.0;
    for (const Triangle& t : surface_.triangles)
      winding += solid_angle(p, surface_.points[t[0]], surface_.points[t[1]],
                             surface_.points[t[2]]);
    return std::abs(winding) < 2.0 * kPi;  // |winding number| < 1/2
  }

 private:
  // Triangles listed per cell of the projection along `axis` onto coordinates (u, v).
  struct ColumnGrid {
    int u = 1, v = 2;
    double lo_u = 0.0, lo_v = 0.0, inv_cell = 1.0;
    long nu = 1, nv = 1;
    std::vector<std::uint32_t> start;  // nu * nv + 1
    std::vector<std::uint32_t> items;
    long cell_u(double x) const {
      return std::clamp(static_cast<long>(std::floor((x - lo_u) * inv_cell)), 0L, nu - 1);
    }
    long cell_v(double x) const {
      return std::clamp(static_cast<long>(std::floor((x - lo_v) * inv_cell)), 0L, nv - 1);
    }
  };

  void build(int axis) {
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
          g.items[fill[static_cast<std::size_t>(iu * g.nv + iv)]++] =
              static_cast<std::uint32_t>(f);
  }

  // Parity of the crossings of the ray from p towards +axis.
  RayVerdict cast_ray(int axis, const Vec3d& p) const {
    const ColumnGrid& g = grids_[axis];
    const double eps = tolerance_;
    const double pu = p[g.u], pv = p[g.v], pz = p[axis];
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
      if (hi[axis] + eps < pz) continue;  // entirely behind the ray's origin
      if (p.x >= lo.x - eps && p.x <= hi.x + eps && p.y >= lo.y - eps && p.y <= hi.y + eps &&
          p.z >= lo.z - eps && p.z <= hi.z + eps &&
          point_triangle_distance2(p, a, b, c) <= eps * eps)
        return RayVerdict::kOnSurface;
      if (ambiguous) continue;  // only an on-surface hit can still decide
      // Signed distances (2D) of the projected point from the projected edges, positive inside.
      const double au = a[g.u], av = a[g.v], bu = b[g.u], bv = b[g.v], cu = c[g.u], cv = c[g.v];
      const double d = (bu - au) * (cv - av) - (bv - av) * (cu - au);
      const double l_bc = std::hypot(cu - bu, cv - bv), l_ca = std::hypot(au - cu, av - cv),
                   l_ab = std::hypot(bu - au, bv - av);
      const double l_max = std::max({l_bc, l_ca, l_ab});
      if (std::abs(d) <= eps * l_max) {
        // Seen edge-on: the ray may graze it.
        if (pu >= lo[g.u] - eps && pu <= hi[g.u] + eps && pv >= lo[g.v] - eps &&
            pv <= hi[g.v] + eps)
          ambiguous = true;
        continue;
      }
      const double s = d > 0.0 ? 1.0 : -1.0;
      const double w0 = (cu - bu) * (pv - bv) - (cv - bv) * (pu - bu);
      const double w1 = (au - cu) * (pv - cv) - (av - cv) * (pu - cu);
      const double w2 = (bu - au) * (pv - av) - (bv - av) * (pu - au);
      const double e0 = s * w0 / l_bc, e1 = s * w1 / l_ca, e2 = s * w2 / l_ab;
      const double e_min = std::min({e0, e1, e2});
      if (e_min < -eps) continue;
      const double z = (w0 * a[axis] + w1 * b[axis] + w2 * c[axis]) / d;
      if (z <= pz) continue;
      if (e_min <= eps) {
        ambiguous = true;
        continue;
      }
      ++crossings;
    }
    if (ambiguous) return RayVerdict::kAmbiguous;
    return crossings % 2 == 1 ? RayVerdict::kInside : RayVerdict::kOutside;
  }

  const SurfaceMesh& surface_;
  double tolerance_;
  ColumnGrid grids_[3];
};

// ---------------------------------------------------------------------------------------------
// Tet-tet overlap.

struct TetGeometry {
  std::array<Vec3d, 4> p;
  std::array<Vec3d, 4> n;      // unit normal of the face opposite corner k (0 if degenerate)
  std::array<double, 4> lo{};  // extent of the tet along n[k]
  std::array<double, 4> hi{};
  double max_edge = 0.0;
  BBox box;
};

TetGeometry tet_geometry(const std::array<Vec3d, 4>& p) {
  TetGeometry g;
  g.p = p;
  for (const Vec3d& x : p) g.box.expand(x);
  for (const auto& e : kTetEdge) g.max_edge = std::max(g.max_edge, distance(p[e[0]], p[e[1]]));
  for (int k = 0; k < 4; ++k) {
    const Vec3d& u = p[(k + 1) % 4];
    const Vec3d m = cross(p[(k + 2) % 4] - u, p[(k + 3) % 4] - u);
    const double len = norm(m);
    g.n[k] = len > 0.0 ? m / len : Vec3d{};
    g.lo[k] = g.hi[k] = dot(g.n[k], u);
    const double opposite = dot(g.n[k], p[k]);
    g.lo[k] = std::min(g.lo[k], opposite);
    g.hi[k] = std::max(g.hi[k], opposite);
  }
  return g;
}

bool separated_on(const Vec3d& axis, double a_lo, double a_hi, const std::array<Vec3d, 4>& q,
                  double tolerance) {
  double b_lo = dot(axis, q[0]), b_hi = b_lo;
  for (int k = 1; k < 4; ++k) {
    const double x = dot(axis, q[k]);
    b_lo = std::min(b_lo, x);
    b_hi = std::max(b_hi, x);
  }
  return b_hi <= a_lo + tolerance || a_hi <= b_lo + tolerance;
}

bool geometries_overlap(const TetGeometry& a, const TetGeometry& b, double tolerance) {
  for (int k = 0; k < 4; ++k)
    if (norm2(a.n[k]) > 0.0 && separated_on(a.n[k], a.lo[k], a.hi[k], b.p, tolerance))
      return false;
  for (int k = 0; k < 4; ++k)
    if (norm2(b.n[k]) > 0.0 && separated_on(b.n[k], b.lo[k], b.hi[k], a.p, tolerance))
      return false;
  for (const auto& ea : kTetEdge) {
    const Vec3d da = a.p[ea[1]] - a.p[ea[0]];
    for (const auto& eb : kTetEdge) {
      const Vec3d db = b.p[eb[1]] - b.p[eb[0]];
      const Vec3d m = cross(da, db);
      const double len2 = norm2(m);
      if (!(len2 > 1e-24 * norm2(da) * norm2(db))) continue;  // (nearly) parallel edges
      const Vec3d axis = m / std::sqrt(len2);
      double a_lo = dot(axis, a.p[0]), a_hi = a_lo;
      for (int k = 1; k < 4; ++k) {
        const double x = dot(axis, a.p[k]);
        a_lo = std::min(a_lo, x);
        a_hi = std::max(a_hi, x);
      }
      if (separated_on(axis, a_lo, a_hi, b.p, tolerance)) return false;
    }
  }
  return true;
}

// Whether triangles a and b cross (separating axes: both normals, the 9 cross products of their
// edges, and each normal crossed with the other's edges for coplanar pairs); projections that
// overlap by no more than `tolerance` only touch.
bool triangles_cross(const std::array<Vec3d, 3>& a, const std::array<Vec3d, 3>& b,
                     double tolerance) {
  auto separated = [&](const Vec3d& axis) {
    const double len2 = norm2(axis);
    if (!(len2 > 0.0)) return false;
    const Vec3d u = axis / std::sqrt(len2);
    double a_lo = dot(u, a[0]), a_hi = a_lo, b_lo = dot(u, b[0]), b_hi = b_lo;
    for (int k = 1; k < 3; ++k) {
      a_lo = std::min(a_lo, dot(u, a[k]));
      a_hi = std::max(a_hi, dot(u, a[k]));
      b_lo = std::min(b_lo, dot(u, b[k]));
      b_hi = std::max(b_hi, dot(u, b[k]));
    }
    return b_hi <= a_lo + tolerance || a_hi <= b_lo + tolerance;
  };
  const Vec3d ea[3] = {a[1] - a[0], a[2] - a[1], a[0] - a[2]};
  const Vec3d eb[3] = {b[1] - b[0], b[2] - b[1], b[0] - b[2]};
  const Vec3d na = cross(ea[0], a[2] - a[0]), nb = cross(eb[0], b[2] - b[0]);
  if (separated(na) || separated(nb)) return false;
  for (const Vec3d& da : ea)
    for (const Vec3d& db : eb)
      if (separated(cross(da, db))) return false;
  for (int k = 0; k < 3; ++k)
    if (separated(cross(na, ea[k])) || separated(cross(nb, eb[k]))) return false;
  return true;
}

// Whether triangle t crosses the interior of tet g (separating axes: the triangle's normal, the
// tet's face normals, the 18 cross products of their edges).
bool triangle_crosses_tet(const std::array<Vec3d, 3>& t, const TetGeometry& g, double tolerance) {
  const auto interval = [](const Vec3d& axis, const Vec3d* p, int count, double& lo,
                           double& hi) {
    lo = hi = dot(axis, p[0]);
    for (int k = 1; k < count; ++k) {
      const double x = dot(axis, p[k]);
      lo = std::min(lo, x);
      hi = std::max(hi, x);
    }
  };
  double a_lo, a_hi, b_lo, b_hi;
  for (int k = 0; k < 4; ++k) {
    if (!(norm2(g.n[k]) > 0.0)) continue;
    interval(g.n[k], t.data(), 3, b_lo, b_hi);
    if (b_hi <= g.lo[k] + tolerance || g.hi[k] <= b_lo + tolerance) return false;
  }
  const Vec3d e[3] = {t[1] - t[0], t[2] - t[1], t[0] - t[2]};
  const Vec3d normal = cross(e[0], t[2] - t[0]);
  if (norm2(normal) > 0.0) {
    const Vec3d axis = normalized(normal);
    const double plane = dot(axis, t[0]);
    interval(axis, g.p.data(), 4, b_lo, b_hi);
    if (b_hi <= plane + tolerance || plane <= b_lo + tolerance) return false;
  }
  for (const Vec3d& da : e) {
    for (const auto& eb : kTetEdge) {
      const Vec3d db = g.p[eb[1]] - g.p[eb[0]];
      const Vec3d m = cross(da, db);
      const double len2 = norm2(m);
      if (!(len2 > 1e-24 * norm2(da) * norm2(db))) continue;
      const Vec3d axis = m / std::sqrt(len2);
      interval(axis, t.data(), 3, a_lo, a_hi);
      interval(axis, g.p.data(), 4, b_lo, b_hi);
      if (b_hi <= a_lo + tolerance || a_hi <= b_lo + tolerance) return false;
    }
  }
  return true;
}

bool boxes_overlap(const BBox& a, const BBox& b) {
  return a.lo.x <= b.hi.x && b.lo.x <= a.hi.x && a.lo.y <= b.hi.y && b.lo.y <= a.hi.y &&
         a.lo.z <= b.hi.z && b.lo.z <= a.hi.z;
}

// Per tet i: the tets j > i that overlap it.
struct OverlapSlot {
  std::vector<std::uint32_t> partners;
  std::uint32_t candidates = 0;
};

// A uniform grid over `box` in which a tet is entered in the cells it may intersect: the cells of
// its bounding box that no face plane of the tet separates from it (conservative). Geometry
// outside `box` is clamped to the border cells, where the plane test may drop it: callers keep
// their tets inside `box` (TetGrid::contains).
class TetGrid {
 public:
  TetGrid(const BBox& box, double cell_size) : box_(box) {
    cell_ = cell_size;
    inv_cell_ = 1.0 / cell_;
    for (int a = 0; a < 3; ++a)
      dims_[a] = std::max(1L, static_cast<long>(std::ceil((box_.hi[a] - box_.lo[a]) * inv_cell_)));
  }

  bool contains(const BBox& b) const {
    return b.lo.x >= box_.lo.x && b.lo.y >= box_.lo.y && b.lo.z >= box_.lo.z &&
           b.hi.x <= box_.hi.x && b.hi.y <= box_.hi.y && b.hi.z <= box_.hi.z;
  }

  // Cells of tet g, written to `out` (when not null) in increasing order; returns how many.
  std::size_t cells_of(const TetGeometry& g, std::uint32_t* out) const {
    return cells_in(g.box, out, [&](const Vec3d& centre, double reach_scale) {
      for (int f = 0; f < 4; ++f) {
        const Vec3d& n = g.n[f];
        const double c = dot(n, centre);
        const double reach = reach_scale * (std::abs(n.x) + std::abs(n.y) + std::abs(n.z));
        if (c - reach > g.hi[f] || c + reach < g.lo[f]) return false;
      }
      return true;
    });
  }

  // Cells that triangle t may intersect, as cells_of().
  std::size_t cells_of_triangle(const std::array<Vec3d, 3>& t, std::uint32_t* out) const {
    BBox box;
    for (const Vec3d& p : t) box.expand(p);
    const Vec3d n = normalized(cross(t[1] - t[0], t[2] - t[0]));
    const double plane = dot(n, t[0]);
    return cells_in(box, out, [&](const Vec3d& centre, double reach_scale) {
      const double reach = reach_scale * (std::abs(n.x) + std::abs(n.y) + std::abs(n.z));
      return std::abs(dot(n, centre) - plane) <= reach;
    });
  }

  std::size_t num_cells() const {
    return static_cast<std::size_t>(dims_[0]) * static_cast<std::size_t>(dims_[1]) *
           static_cast<std::size_t>(dims_[2]);
  }

 private:
  // Cells of `box` (clamped to the grid) for which keep(centre, half side) holds.
  template <class Keep>
  std::size_t cells_in(const BBox& box, std::uint32_t* out, const Keep& keep) const {
    long lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
      lo[a] = cell_of(box.lo[a], a);
      hi[a] = cell_of(box.hi[a], a);
    }
    const double r = 0.5 * cell_;
    std::size_t count = 0;
    for (long i = lo[0]; i <= hi[0]; ++i)
      for (long j = lo[1]; j <= hi[1]; ++j)
        for (long k = lo[2]; k <= hi[2]; ++k) {
          const Vec3d centre = box_.lo + Vec3d{(static_cast<double>(i) + 0.5) * cell_,
                                               (static_cast<double>(j) + 0.5) * cell_,
                                               (static_cast<double>(k) + 0.5) * cell_};
          if (!keep(centre, r)) continue;
          if (out) out[count] = static_cast<std::uint32_t>((i * dims_[1] + j) * dims_[2] + k);
          ++count;
        }
    return count;
  }

  long cell_of(double x, int a) const {
    return std::clamp(static_cast<long>(std::floor((x - box_.lo[a]) * inv_cell_)), 0L,
                      dims_[a] - 1);
  }

  BBox box_;
  double cell_ = 1.0, inv_cell_ = 1.0;
  long dims_[3] = {1, 1, 1};
};

BBox bounding_box_of(const std::vector<TetGeometry>& geo) {
  BBox all;
  for (const TetGeometry& g : geo) {
    all.expand(g.box.lo);
    all.expand(g.box.hi);
  }
  return all;
}

// Cell size: about the edge of a cube of the mean tet volume, so that slivers enter few cells,
// made larger until `all` has at most 32 cells per tet and the tets' boxes span at most 64 cells
// each on average.
double grid_cell_size(const std::vector<TetGeometry>& geo, const BBox& all) {
  const double n = static_cast<double>(geo.size());
  double mean_volume = 0.0, mean_side = 0.0;
  for (const TetGeometry& g : geo) {
    mean_volume += std::abs(tet_volume(g.p[0], g.p[1], g.p[2], g.p[3])) / n;
    const Vec3d e = g.box.extent();
    mean_side += (e.x + e.y + e.z) / (3.0 * n);
  }
  double h = std::max(1.5 * std::cbrt(mean_volume), mean_side / 8.0);
  if (!(h > 0.0)) h = all.max_side() > 0.0 ? all.max_side() : 1.0;
  const Vec3d ext = all.extent();
  for (int round = 0; round < 200; ++round) {
    const double cells = std::ceil(ext.x / h + 1e-9) * std::ceil(ext.y / h + 1e-9) *
                         std::ceil(ext.z / h + 1e-9);
    double spanned = 0.0;
    for (const TetGeometry& g : geo) {
      const Vec3d e = g.box.extent();
      spanned += (std::floor(e.x / h) + 2.0) * (std::floor(e.y / h) + 2.0) *
                 (std::floor(e.z / h) + 2.0);
    }
    if (cells <= 32.0 * n + 64.0 && spanned <= 64.0 * n) break;
    h *= 1.25;
  }
  return h;
}

// Whether tets a and b overlap, with the tolerance of `options` relative to their longest edge.
bool tets_intersect(const TetGeometry& a, const TetGeometry& b, const ShellCheckOptions& options) {
  if (!boxes_overlap(a.box, b.box)) return false;
  return geometries_overlap(a, b, options.overlap_tolerance * std::max(a.max_edge, b.max_edge));
}

// The corners of surface triangle f.
std::array<Vec3d, 3> corners(const SurfaceMesh& surface, std::size_t f) {
  const Triangle& tri = surface.triangles[f];
  return {surface.points[tri[0]], surface.points[tri[1]], surface.points[tri[2]]};
}

// Whether surface triangle f crosses the interior of tet g (touching does not count).
bool surface_triangle_crosses(const SurfaceMesh& surface, std::size_t f, const TetGeometry& g,
                              const ShellCheckOptions& options) {
  const std::array<Vec3d, 3> t = corners(surface, f);
  BBox box;
  for (const Vec3d& p : t) box.expand(p);
  return boxes_overlap(box, g.box) &&
         triangle_crosses_tet(t, g, options.overlap_tolerance * g.max_edge);
}

bool centroid_outside(const InsideTester& inside, const TetGeometry& g) {
  return inside.outside((g.p[0] + g.p[1] + g.p[2] + g.p[3]) * 0.25);
}

// Tet-tet overlaps, and tets reaching outside the surface: crossed by a surface triangle, or
// with their centroid outside.
void check_tet_intersections(const SurfaceMesh& surface, const TetMesh& mesh,
                             const InsideTester& inside, const ShellCheckOptions& options,
                             ShellCheckResult& result) {
  const std::size_t n = mesh.tets.size();
  if (n == 0) return;
  std::vector<TetGeometry> geo(n);
  for_each_chunk(
      n,
      [&](std::size_t begin, std::size_t end) {
        for (std::size_t t = begin; t != end; ++t) {
          const Tet& v = mesh.tets[t];
          geo[t] = tet_geometry(
              {mesh.points[v[0]], mesh.points[v[1]], mesh.points[v[2]], mesh.points[v[3]]});
        }
      },
      1024);

  // Broad phase: tet -> cells, then cell -> tets (tets in increasing order in every cell).
  const BBox grid_box = bounding_box_of(geo);
  const TetGrid grid(grid_box, grid_cell_size(geo, grid_box));
  std::vector<std::uint64_t> tet_start(n + 1, 0);
  for_each_index(n, [&](std::size_t t) { tet_start[t + 1] = grid.cells_of(geo[t], nullptr); });
  for (std::size_t t = 0; t < n; ++t) tet_start[t + 1] += tet_start[t];
  std::vector<std::uint32_t> tet_cells(tet_start[n]);
  for_each_index(n,
                 [&](std::size_t t) { grid.cells_of(geo[t], tet_cells.data() + tet_start[t]); });
  std::vector<std::uint64_t> cell_start(grid.num_cells() + 1, 0);
  for (const std::uint32_t c : tet_cells) ++cell_start[c + 1];
  for (std::size_t c = 0; c < grid.num_cells(); ++c) cell_start[c + 1] += cell_start[c];
  std::vector<std::uint32_t> cell_tets(tet_cells.size());
  {
    std::vector<std::uint64_t> fill(cell_start.begin(), cell_start.end() - 1);
    for (std::size_t t = 0; t < n; ++t)
      for (std::uint64_t k = tet_start[t]; k < tet_start[t + 1]; ++k)
        cell_tets[fill[tet_cells[k]]++] = static_cast<std::uint32_t>(t);
  }

  // Narrow phase: every tet against the later tets sharing one of its cells. Each chunk marks
  // the tets it has met (mark[u] == t + 1) so that a pair sharing several cells is tested once;
  // chunks of at least n / 32 tets keep the cost of the marks linear in n.
  std::vector<OverlapSlot> slots(options.check_overlaps ? n : 0);
  for_each_chunk(
      slots.size(),
      [&](std::size_t begin, std::size_t end) {
        std::vector<std::uint32_t> mark(n, 0);
        for (std::size_t t = begin; t != end; ++t) {
          OverlapSlot& slot = slots[t];
          const auto stamp = static_cast<std::uint32_t>(t + 1);
          for (std::uint64_t k = tet_start[t]; k < tet_start[t + 1]; ++k) {
            const std::uint32_t c = tet_cells[k];
            const std::uint32_t* first = cell_tets.data() + cell_start[c];
            const std::uint32_t* last = cell_tets.data() + cell_start[c + 1];
            for (const std::uint32_t* it = std::upper_bound(first, last, t); it != last; ++it) {
              const std::uint32_t u = *it;
              if (mark[u] == stamp) continue;
              mark[u] = stamp;
              if (!boxes_overlap(geo[t].box, geo[u].box)) continue;
              ++slot.candidates;
              if (tets_intersect(geo[t], geo[u], options)) slot.partners.push_back(u);
            }
          }
          std::sort(slot.partners.begin(), slot.partners.end());
        }
      },
      std::max<std::size_t>(1024, n / 32));
  for (std::size_t t = 0; t < slots.size(); ++t) {
    OverlapSlot& slot = slots[t];
    result.overlap_candidate_pairs += slot.candidates;
    result.overlapping_pairs += slot.partners.size();
    for (const std::uint32_t u : slot.partners)
      if (result.first_overlapping_pairs.size() < options.max_listed)
        result.first_overlapping_pairs.push_back({static_cast<std::uint32_t>(t), u});
  }
  result.overlaps_checked = options.check_overlaps;
  if (!options.check_leaks) return;

  // Leaks: every surface triangle against the tets sharing one of its cells, then the centroids.
  const std::size_t n_faces = surface.triangles.size();
  std::vector<std::vector<std::uint32_t>> crossed(n_faces);
  for_each_chunk(
      n_faces,
      [&](std::size_t begin, std::size_t end) {
        std::vector<std::uint32_t> mark(n, 0);
        std::vector<std::uint32_t> cells;
        for (std::size_t f = begin; f != end; ++f) {
          const std::array<Vec3d, 3> t = corners(surface, f);
          BBox box;
          for (const Vec3d& p : t) box.expand(p);
          if (!boxes_overlap(box, grid_box)) continue;
          cells.resize(grid.cells_of_triangle(t, nullptr));
          grid.cells_of_triangle(t, cells.data());
          const auto stamp = static_cast<std::uint32_t>(f + 1);
          for (const std::uint32_t c : cells) {
            for (std::uint64_t k = cell_start[c]; k < cell_start[c + 1]; ++k) {
              const std::uint32_t u = cell_tets[k];
              if (mark[u] == stamp) continue;
              mark[u] = stamp;
              if (surface_triangle_crosses(surface, f, geo[u], options)) crossed[f].push_back(u);
            }
          }
        }
      },
      std::max<std::size_t>(1024, n_faces / 32));
  std::vector<std::uint8_t> leaking(n, 0);
  for_each_index(n, [&](std::size_t t) { leaking[t] = centroid_outside(inside, geo[t]) ? 1 : 0; });
  for (const std::vector<std::uint32_t>& list : crossed)
    for (const std::uint32_t t : list) leaking[t] = 1;
  for (std::size_t t = 0; t < n; ++t) {
    if (leaking[t]) {
      ++result.leaking_tets;
      list_item(result.first_leaking_tets, options.max_listed, t);
    }
  }
  result.leaks_checked = true;
}

// ---------------------------------------------------------------------------------------------
// Boundary faces.

struct FaceRecord {
  std::array<std::uint32_t, 3> key;  // sorted vertex indices
  std::uint32_t tet;
  std::uint8_t face;  // corner of the tet opposite the face
  bool operator<(const FaceRecord& o) const {  // element by element: no memcmp calls
    if (key[0] != o.key[0]) return key[0] < o.key[0];
    if (key[1] != o.key[1]) return key[1] < o.key[1];
    if (key[2] != o.key[2]) return key[2] < o.key[2];
    return tet != o.tet ? tet < o.tet : face < o.face;
  }
  bool same_key(const FaceRecord& o) const {
    return key[0] == o.key[0] && key[1] == o.key[1] && key[2] == o.key[2];
  }
};

std::array<std::uint32_t, 3> sorted3(std::uint32_t a, std::uint32_t b, std::uint32_t c) {
  std::array<std::uint32_t, 3> k = {a, b, c};
  std::sort(k.begin(), k.end());
  return k;
}

bool same_cycle(const std::array<std::uint32_t, 3>& x, const Triangle& y) {
  for (int r = 0; r < 3; ++r)
    if (x[0] == y[r] && x[1] == y[(r + 1) % 3] && x[2] == y[(r + 2) % 3]) return true;
  return false;
}

void check_faces(const SurfaceMesh& surface, const TetMesh& mesh,
                 const ShellCheckOptions& options, ShellCheckResult& result) {
  // Sorted in two steps: by smallest vertex (counting sort), then within each (small) bucket.
  const std::size_t n_points = mesh.points.size();
  std::vector<std::uint32_t> bucket(n_points + 1, 0);
  for (const Tet& v : mesh.tets)
    for (int k = 0; k < 4; ++k) {
      const int* f = kTetOutwardFace[k];
      ++bucket[std::min({v[f[0]], v[f[1]], v[f[2]]}) + 1];
    }
  for (std::size_t p = 0; p < n_points; ++p) bucket[p + 1] += bucket[p];
  std::vector<FaceRecord> faces(4 * mesh.tets.size());
  {
    std::vector<std::uint32_t> fill(bucket.begin(), bucket.end() - 1);
    for (std::size_t t = 0; t < mesh.tets.size(); ++t) {
      const Tet& v = mesh.tets[t];
      for (int k = 0; k < 4; ++k) {
        const int* f = kTetOutwardFace[k];
        const std::array<std::uint32_t, 3> key = sorted3(v[f[0]], v[f[1]], v[f[2]]);
        faces[fill[key[0]]++] = {key, static_cast<std::uint32_t>(t), static_cast<std::uint8_t>(k)};
      }
    }
  }
  for (std::size_t p = 0; p < n_points; ++p)
    if (bucket[p + 1] - bucket[p] > 1)
      std::sort(faces.begin() + bucket[p], faces.begin() + bucket[p + 1]);
  for (std::size_t i = 0; i < faces.size();) {
    std::size_t j = i + 1;
    while (j < faces.size() && faces[j].same_key(faces[i])) ++j;
    if (j - i > 2) ++result.nonmanifold_faces;
    i = j;
  }

  const std::size_t max_listed = options.max_listed;
  for (std::size_t f = 0; f < surface.triangles.size(); ++f) {
    const Triangle& tri = surface.triangles[f];
    FaceRecord probe{sorted3(tri[0], tri[1], tri[2]), 0, 0};
    const auto lo = std::lower_bound(faces.begin(), faces.end(), probe);
    auto hi = lo;
    while (hi != faces.end() && hi->same_key(probe)) ++hi;
    const std::ptrdiff_t count = hi - lo;
    if (count == 0) {
      ++result.missing_triangles;
      list_item(result.first_missing_triangles, max_listed, f);
    } else if (count > 1) {
      ++result.shared_triangles;
      list_item(result.first_shared_triangles, max_listed, f);
    } else {
      const Tet& v = mesh.tets[lo->tet];
      const int* k = kTetOutwardFace[lo->face];
      if (!same_cycle({v[k[0]], v[k[1]], v[k[2]]}, tri)) {
        ++result.misoriented_triangles;
        list_item(result.first_misoriented_triangles, max_listed, f);
      }
    }
  }
}

std::string format_list(const std::vector<std::uint32_t>& list) {
  std::ostringstream s;
  for (std::size_t i = 0; i < list.size(); ++i) s << (i ? ", " : "") << list[i];
  return s.str();
}

}  // namespace

TetVolume tet_volume_class(const std::array<Vec3d, 4>& p, double zero_volume_tolerance) {
  double l = 0.0;
  for (const auto& e : kTetEdge) l = std::max(l, distance(p[e[0]], p[e[1]]));
  const double vol = tet_volume(p[0], p[1], p[2], p[3]);
  if (std::abs(vol) <= zero_volume_tolerance * l * l * l) return TetVolume::kZero;
  return vol < 0.0 ? TetVolume::kInverted : TetVolume::kPositive;
}

std::vector<std::array<std::uint32_t, 2>> surface_self_intersections(const SurfaceMesh& surface,
                                                                      std::size_t max_listed) {
  std::vector<std::array<std::uint32_t, 2>> out;
  const std::size_t n = surface.triangles.size();
  if (n == 0) return out;
  const BBox box = bounding_box(surface);
  double mean_edge = 0;
  for (std::size_t f = 0; f < n; ++f) {
    const std::array<Vec3d, 3> t = corners(surface, f);
    mean_edge += (distance(t[0], t[1]) + distance(t[1], t[2]) + distance(t[2], t[0])) / (3.0 * n);
  }
  double h = std::max(mean_edge, 1e-12 * box.diagonal());
  while (std::ceil(box.extent().x / h + 1) * std::ceil(box.extent().y / h + 1) *
             std::ceil(box.extent().z / h + 1) > 8.0 * static_cast<double>(n) + 64.0)
    h *= 1.25;
  BBox grid_box = box;
  grid_box.expand(box.lo - Vec3d{h, h, h});
  grid_box.expand(box.hi + Vec3d{h, h, h});
  const TetGrid grid(grid_box, h);
  std::vector<std::vector<std::uint32_t>> cell_faces(grid.num_cells());
  std::vector<std::vector<std::uint32_t>> face_cells(n);
  for (std::size_t f = 0; f < n; ++f) {
    const std::array<Vec3d, 3> t = corners(surface, f);
    face_cells[f].resize(grid.cells_of_triangle(t, nullptr));
    grid.cells_of_triangle(t, face_cells[f].data());
    for (const std::uint32_t c : face_cells[f])
      cell_faces[c].push_back(static_cast<std::uint32_t>(f));
  }
  const double tolerance = ShellCheckOptions{}.overlap_tolerance;  // relative, as for tets
  std::vector<std::uint32_t> mark(n, UINT32_MAX);
  for (std::uint32_t f = 0; f < n && out.size() < max_listed; ++f) {
    const std::array<Vec3d, 3> a = corners(surface, f);
    const Triangle& ta = surface.triangles[f];
    for (const std::uint32_t c : face_cells[f])
      for (const std::uint32_t g : cell_faces[c]) {
        if (g <= f || mark[g] == f) continue;
        mark[g] = f;
        const Triangle& tb = surface.triangles[g];
        int shared = 0;
        for (const std::uint32_t u : ta)
          shared += (u == tb[0]) + (u == tb[1]) + (u == tb[2]);
        if (shared >= 2) continue;  // neighbours across an edge only touch (2-manifold)
        const std::array<Vec3d, 3> b = corners(surface, g);
        const double tol = tolerance * std::max({distance(a[0], a[1]), distance(a[1], a[2]),
                                            distance(a[2], a[0]), distance(b[0], b[1]),
                                            distance(b[1], b[2]), distance(b[2], b[0])});
        if (triangles_cross(a, b, tol) && out.size() < max_listed) out.push_back({f, g});
      }
  }
  return out;
}

bool tets_overlap(const std::array<Vec3d, 4>& a, const std::array<Vec3d, 4>& b,
                  const ShellCheckOptions& options) {
  return tets_intersect(tet_geometry(a), tet_geometry(b), options);
}

namespace {

// Inverted and zero-volume tets into `result`.
void count_volumes(const TetMesh& mesh, const ShellCheckOptions& options,
                   ShellCheckResult& result) {
  const std::size_t max_listed = options.max_listed;
  std::vector<TetVolume> sign(mesh.tets.size(), TetVolume::kPositive);
  for_each_chunk(
      mesh.tets.size(),
      [&](std::size_t begin, std::size_t end) {
        for (std::size_t t = begin; t != end; ++t) {
          const Tet& v = mesh.tets[t];
          sign[t] = tet_volume_class(
              {mesh.points[v[0]], mesh.points[v[1]], mesh.points[v[2]], mesh.points[v[3]]},
              options.zero_volume_tolerance);
        }
      },
      4096);
  for (std::size_t t = 0; t < sign.size(); ++t) {
    if (sign[t] == TetVolume::kInverted) {
      ++result.inverted_tets;
      list_item(result.first_inverted_tets, max_listed, t);
    } else if (sign[t] == TetVolume::kZero) {
      ++result.zero_volume_tets;
      list_item(result.first_zero_volume_tets, max_listed, t);
    }
  }
}

// The checks every call makes in full: mesh sanity (throws), T <= 3F, volumes, surface points
// kept, and (with `faces`) boundary faces. Returns the indices of the inner points.
std::vector<std::uint32_t> check_basics(const SurfaceMesh& surface, const TetMesh& mesh,
                                        const ShellCheckOptions& options,
                                        ShellCheckResult& result, bool faces = true) {
  const std::size_t n_points = mesh.points.size();
  for (std::size_t t = 0; t < mesh.tets.size(); ++t)
    for (const std::uint32_t v : mesh.tets[t])
      if (v >= n_points)
        throw InputError("check_shell: tet " + std::to_string(t) + " refers to point " +
                         std::to_string(v) + ", but the tet mesh has " +
                         std::to_string(n_points) + " points");
  for (std::size_t v = 0; v < n_points; ++v)
    if (!is_finite(mesh.points[v]))
      throw InputError("check_shell: point " + std::to_string(v) +
                       " of the tet mesh has a NaN or infinite coordinate");
  if (!mesh.inner.empty() && mesh.inner.size() != n_points)
    throw InputError("check_shell: " + std::to_string(mesh.inner.size()) + " inner flags for " +
                     std::to_string(n_points) + " points; give one per point or none");

  result.tets = mesh.tets.size();
  result.faces = surface.triangles.size();
  result.too_many_tets = result.tets > 3 * result.faces;
  const std::size_t max_listed = options.max_listed;

  count_volumes(mesh, options, result);

  // Surface points kept.
  const std::size_t n_surface = surface.points.size();
  for (std::size_t v = 0; v < n_surface; ++v) {
    if (v >= n_points || mesh.points[v] != surface.points[v]) {
      ++result.moved_surface_points;
      list_item(result.first_moved_surface_points, max_listed, v);
    }
  }

  if (faces) check_faces(surface, mesh, options, result);

  std::vector<std::uint32_t> inner_points;
  for (std::size_t v = 0; v < n_points; ++v)
    if (mesh.inner.empty() ? v >= n_surface : mesh.inner[v] != 0)
      inner_points.push_back(static_cast<std::uint32_t>(v));
  result.checked_inner_vertices = inner_points.size();
  return inner_points;
}

void record_outside_points(const std::vector<std::uint32_t>& inner_points,
                           const std::vector<std::uint8_t>& outside,
                           const ShellCheckOptions& options, ShellCheckResult& result) {
  for (std::size_t i = 0; i < inner_points.size(); ++i) {
    if (outside[i]) {
      ++result.outside_inner_vertices;
      list_item(result.first_outside_vertices, options.max_listed, inner_points[i]);
    }
  }
}

double on_surface_distance(const SurfaceMesh& surface, const ShellCheckOptions& options) {
  return options.on_surface_tolerance * bounding_box(surface).diagonal();
}

}  // namespace

bool ShellCheckResult::valid() const {
  return inverted_tets == 0 && zero_volume_tets == 0 && outside_inner_vertices == 0 &&
         moved_surface_points == 0 && missing_triangles == 0 && shared_triangles == 0 &&
         misoriented_triangles == 0 && nonmanifold_faces == 0 && overlapping_pairs == 0 &&
         leaking_tets == 0 && !too_many_tets;
}

ShellCheckResult check_volumes(const TetMesh& mesh, const ShellCheckOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  ShellCheckResult result;
  result.tets = mesh.tets.size();
  count_volumes(mesh, options, result);
  result.seconds = seconds_since(start);
  return result;
}

ShellCheckResult check_shell(const SurfaceMesh& surface, const TetMesh& mesh,
                             const ShellCheckOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  ShellCheckResult result;
  const std::vector<std::uint32_t> inner_points = check_basics(surface, mesh, options, result);

  // Inner points inside.
  const InsideTester tester(surface, on_surface_distance(surface, options));
  std::vector<std::uint8_t> outside(inner_points.size(), 0);
  for_each_index(inner_points.size(), [&](std::size_t i) {
    outside[i] = tester.outside(mesh.points[inner_points[i]]) ? 1 : 0;
  });
  record_outside_points(inner_points, outside, options, result);

  if (options.check_overlaps || options.check_leaks) {
    const auto intersection_start = std::chrono::steady_clock::now();
    check_tet_intersections(surface, mesh, tester, options, result);
    result.intersection_seconds = seconds_since(intersection_start);
  }
  result.seconds = seconds_since(start);
  return result;
}

// ---------------------------------------------------------------------------------------------
// ShellChecker: the same checks, repeated on shells that change a few prisms at a time.
//
// A uniform grid over the surface's box (grown to hold the first shell) is built once, with
// the surface triangles entered once and the tets of every prism entered under the key
// 3 * prism + k and moved when their prism moves. A call tests the "dirty" prisms — changed
// since the previous call, or offending in it — against everything, and trusts every other
// pair: both of its tets are where they were when the pair was last tested, and it passed.

struct ShellChecker::Impl {
  Impl(const SurfaceMesh& s, const ShellCheckOptions& o)
      : surface(s), options(o), tester(s, on_surface_distance(s, o)) {}

  struct Prism {
    int count = 0;
    std::array<TetGeometry, 3> geo;
    std::array<std::vector<std::uint32_t>, 3> cells;  // empty and stray: outside the grid
    std::array<bool, 3> stray{};
  };

  const SurfaceMesh& surface;
  ShellCheckOptions options;
  InsideTester tester;
  std::unique_ptr<TetGrid> grid;
  std::vector<std::uint32_t> triangle_start, triangle_items;  // surface triangles per cell
  std::vector<std::vector<std::uint32_t>> cell_keys;           // tet keys per cell
  std::vector<std::uint32_t> stray_keys;                       // tets outside the grid's box
  std::vector<Prism> prisms;
  std::vector<BBox> key_box;           // per tet key: its box (compact, for the broad phase)
  std::vector<std::uint8_t> offended;  // per prism, in the previous call
  std::map<std::array<double, 3>, bool> outside_cache;
  // Boundary faces depend on the tets' vertex indices only: the last result and its tets.
  std::vector<Tet> faces_tets;
  ShellCheckResult faces_result;

  void build_grid(const std::vector<TetGeometry>& geo) {
    BBox box = bounding_box(surface);
    const BBox tets = bounding_box_of(geo);
    box.expand(tets.lo);
    box.expand(tets.hi);
    const double margin = 0.05 * box.diagonal();
    box.expand(box.lo - Vec3d{margin, margin, margin});
    box.expand(box.hi + Vec3d{margin, margin, margin});
    grid = std::make_unique<TetGrid>(box, grid_cell_size(geo, box));
    cell_keys.assign(grid->num_cells(), {});
    const std::size_t n_faces = surface.triangles.size();
    std::vector<std::vector<std::uint32_t>> cells(n_faces);
    for_each_index(n_faces, [&](std::size_t f) {
      const std::array<Vec3d, 3> t = corners(surface, f);
      cells[f].resize(grid->cells_of_triangle(t, nullptr));
      grid->cells_of_triangle(t, cells[f].data());
    });
    triangle_start.assign(grid->num_cells() + 1, 0);
    for (const auto& list : cells)
      for (const std::uint32_t c : list) ++triangle_start[c + 1];
    for (std::size_t c = 0; c < grid->num_cells(); ++c) triangle_start[c + 1] += triangle_start[c];
    triangle_items.resize(triangle_start.back());
    std::vector<std::uint32_t> fill(triangle_start.begin(), triangle_start.end() - 1);
    for (std::size_t f = 0; f < n_faces; ++f)
      for (const std::uint32_t c : cells[f])
        triangle_items[fill[c]++] = static_cast<std::uint32_t>(f);
  }

  void remove(std::uint32_t key) {
    Prism& p = prisms[key / 3];
    const int k = static_cast<int>(key % 3);
    if (p.stray[k]) {
      stray_keys.erase(std::find(stray_keys.begin(), stray_keys.end(), key));
      p.stray[k] = false;
    }
    for (const std::uint32_t c : p.cells[k]) {
      std::vector<std::uint32_t>& list = cell_keys[c];
      list.erase(std::lower_bound(list.begin(), list.end(), key));
    }
    p.cells[k].clear();
  }

  void insert(std::uint32_t key) {
    Prism& p = prisms[key / 3];
    const int k = static_cast<int>(key % 3);
    if (p.stray[k]) {
      stray_keys.push_back(key);
    } else {
      for (const std::uint32_t c : p.cells[k]) {  // the lists stay sorted
        std::vector<std::uint32_t>& list = cell_keys[c];
        list.insert(std::lower_bound(list.begin(), list.end(), key), key);
      }
    }
  }

  // Calls visit(other) once for every tet key that may touch tet `key` (the stray tets
  // included), using `mark` (one entry per key, never equal to stamp before) to skip repeats;
  // with `only_greater`, the cells' keys below `key` are skipped.
  template <class Visit>
  void for_each_candidate(std::uint32_t key, bool only_greater, std::vector<std::uint32_t>& mark,
                          std::uint32_t stamp, const Visit& visit) const {
    const Prism& p = prisms[key / 3];
    const int k = static_cast<int>(key % 3);
    auto once = [&](std::uint32_t other) {
      if (mark[other] == stamp) return;
      mark[other] = stamp;
      visit(other);
    };
    if (p.stray[k]) {
      for (std::uint32_t f = 0; f < prisms.size(); ++f)
        for (int j = 0; j < prisms[f].count; ++j) once(3 * f + static_cast<std::uint32_t>(j));
      return;
    }
    for (const std::uint32_t c : p.cells[k]) {
      const std::vector<std::uint32_t>& list = cell_keys[c];
      for (auto it = only_greater ? std::upper_bound(list.begin(), list.end(), key) : list.begin();
           it != list.end(); ++it)
        once(*it);
    }
    for (const std::uint32_t other : stray_keys) once(other);
  }

  // Calls visit(f) once for every surface triangle f that may cross tet `key`, as above.
  template <class Visit>
  void for_each_triangle(std::uint32_t key, std::vector<std::uint32_t>& mark, std::uint32_t stamp,
                         const Visit& visit) const {
    const Prism& p = prisms[key / 3];
    const int k = static_cast<int>(key % 3);
    if (p.stray[k]) {
      for (std::uint32_t f = 0; f < surface.triangles.size(); ++f) visit(f);
      return;
    }
    for (const std::uint32_t c : p.cells[k])
      for (std::uint32_t i = triangle_start[c]; i < triangle_start[c + 1]; ++i) {
        const std::uint32_t f = triangle_items[i];
        if (mark[f] == stamp) continue;
        mark[f] = stamp;
        visit(f);
      }
  }
};

ShellChecker::ShellChecker(const SurfaceMesh& surface, const ShellCheckOptions& options)
    : impl_(std::make_unique<Impl>(surface, options)) {}

ShellChecker::~ShellChecker() = default;

ShellCheckResult ShellChecker::check(const TetMesh& mesh) {
  Impl& m = *impl_;
  const ShellCheckOptions& options = m.options;
  const auto start = std::chrono::steady_clock::now();
  ShellCheckResult result;
  const std::vector<std::uint32_t> inner_points =
      check_basics(m.surface, mesh, options, result, /*faces=*/false);
  if (mesh.tets != m.faces_tets) {
    m.faces_result = ShellCheckResult{};
    check_faces(m.surface, mesh, options, m.faces_result);
    m.faces_tets = mesh.tets;
  }
  const ShellCheckResult& f = m.faces_result;
  result.missing_triangles = f.missing_triangles;
  result.first_missing_triangles = f.first_missing_triangles;
  result.shared_triangles = f.shared_triangles;
  result.first_shared_triangles = f.first_shared_triangles;
  result.misoriented_triangles = f.misoriented_triangles;
  result.first_misoriented_triangles = f.first_misoriented_triangles;
  result.nonmanifold_faces = f.nonmanifold_faces;

  // Inner points inside, each position tested once over all calls.
  {
    std::vector<std::uint8_t> outside(inner_points.size(), 0);
    std::vector<std::size_t> unknown;
    for (std::size_t i = 0; i < inner_points.size(); ++i) {
      const Vec3d& p = mesh.points[inner_points[i]];
      const auto it = m.outside_cache.find({p.x, p.y, p.z});
      if (it == m.outside_cache.end())
        unknown.push_back(i);
      else
        outside[i] = it->second ? 1 : 0;
    }
    for_each_index(unknown.size(), [&](std::size_t j) {
      outside[unknown[j]] = m.tester.outside(mesh.points[inner_points[unknown[j]]]) ? 1 : 0;
    });
    for (const std::size_t i : unknown) {
      const Vec3d& p = mesh.points[inner_points[i]];
      m.outside_cache.emplace(std::array<double, 3>{p.x, p.y, p.z}, outside[i] != 0);
    }
    record_outside_points(inner_points, outside, options, result);
  }
  if (!options.check_overlaps && !options.check_leaks) {
    result.seconds = seconds_since(start);
    return result;
  }
  const auto intersection_start = std::chrono::steady_clock::now();

  // Prisms: tets grouped by source triangle, at most 3 each.
  const std::size_t n_faces = m.surface.triangles.size();
  const std::size_t n = mesh.tets.size();
  if (mesh.source_triangle.size() != n)
    throw InputError("ShellChecker: the tet mesh has no source triangle per tet; pass an "
                     "assemble_shell() result");
  std::vector<std::uint32_t> first(n_faces + 1, 0);
  for (std::size_t t = 0; t < n; ++t) {
    const std::uint32_t f = mesh.source_triangle[t];
    if (f >= n_faces || (t > 0 && f < mesh.source_triangle[t - 1]))
      throw InputError("ShellChecker: tet " + std::to_string(t) + " has source triangle " +
                       std::to_string(f) + " out of order or range; pass an assemble_shell() "
                       "result");
    ++first[f + 1];
  }
  for (std::size_t f = 0; f < n_faces; ++f) {
    if (first[f + 1] > 3)
      throw InputError("ShellChecker: triangle " + std::to_string(f) +
                       " has more than 3 tets; pass an assemble_shell() result");
    first[f + 1] += first[f];
  }

  // Which prisms moved: their tets' corners, compared with the stored ones.
  const bool initial = m.prisms.empty();
  if (initial) {
    m.prisms.resize(n_faces);
    m.key_box.resize(3 * n_faces);
    m.offended.assign(n_faces, 0);
  }
  auto corners = [&](std::uint32_t t) {
    const Tet& v = mesh.tets[t];
    return std::array<Vec3d, 4>{mesh.points[v[0]], mesh.points[v[1]], mesh.points[v[2]],
                                mesh.points[v[3]]};
  };
  std::vector<std::uint8_t> changed(n_faces, 0);
  for_each_index(n_faces, [&](std::size_t f) {
    const Impl::Prism& old = m.prisms[f];
    bool same = !initial && old.count == static_cast<int>(first[f + 1] - first[f]);
    for (std::uint32_t t = first[f]; same && t < first[f + 1]; ++t)
      same = corners(t) == old.geo[t - first[f]].p;
    changed[f] = same ? 0 : 1;
  });
  std::vector<std::uint32_t> moved, dirty;
  for (std::uint32_t f = 0; f < n_faces; ++f) {
    if (changed[f]) moved.push_back(f);
    if (changed[f] || m.offended[f]) dirty.push_back(f);
  }
  // The moved prisms' new tets (geometry and cells) in parallel, then the grid's lists in order.
  std::vector<Impl::Prism> fresh(moved.size());
  for_each_index(moved.size(), [&](std::size_t i) {
    const std::uint32_t f = moved[i];
    Impl::Prism& p = fresh[i];
    p.count = static_cast<int>(first[f + 1] - first[f]);
    for (std::uint32_t t = first[f]; t < first[f + 1]; ++t)
      p.geo[t - first[f]] = tet_geometry(corners(t));
  });
  if (initial) {
    std::vector<TetGeometry> all;
    all.reserve(n);
    for (const Impl::Prism& p : fresh)
      for (int k = 0; k < p.count; ++k) all.push_back(p.geo[static_cast<std::size_t>(k)]);
    m.build_grid(all);
  }
  for_each_index(moved.size(), [&](std::size_t i) {
    Impl::Prism& p = fresh[i];
    for (int k = 0; k < p.count; ++k) {
      const auto kk = static_cast<std::size_t>(k);
      p.stray[kk] = !m.grid->contains(p.geo[kk].box);
      if (p.stray[kk]) continue;
      p.cells[kk].resize(m.grid->cells_of(p.geo[kk], nullptr));
      m.grid->cells_of(p.geo[kk], p.cells[kk].data());
    }
  });
  for (std::size_t i = 0; i < moved.size(); ++i) {
    const std::uint32_t f = moved[i];
    for (int k = 0; k < m.prisms[f].count; ++k) m.remove(3 * f + static_cast<std::uint32_t>(k));
    m.prisms[f] = std::move(fresh[i]);
    for (int k = 0; k < m.prisms[f].count; ++k)
      m.key_box[3 * f + static_cast<std::uint32_t>(k)] = m.prisms[f].geo[static_cast<std::size_t>(k)].box;
    for (int k = 0; k < m.prisms[f].count; ++k) m.insert(3 * f + static_cast<std::uint32_t>(k));
  }

  // Every tet of a dirty prism against its candidates; a pair of two dirty tets once, from the
  // smaller key. Results per dirty prism, in tet order.
  struct Found {
    std::vector<std::array<std::uint32_t, 2>> pairs;
    std::vector<std::uint32_t> leaking;
    std::size_t candidates = 0;
  };
  std::vector<std::uint8_t> is_dirty(n_faces, 0);
  for (const std::uint32_t f : dirty) is_dirty[f] = 1;
  std::vector<Found> found(dirty.size());
  const bool all_dirty = dirty.size() == n_faces;  // every pair from its smaller key
  for_each_chunk(
      dirty.size(),
      [&](std::size_t begin, std::size_t end) {
        std::vector<std::uint32_t> tet_mark(3 * n_faces, 0), triangle_mark(n_faces, 0);
        for (std::size_t i = begin; i != end; ++i) {
          const std::uint32_t f = dirty[i];
          const Impl::Prism& p = m.prisms[f];
          Found& out = found[i];
          for (int k = 0; k < p.count; ++k) {
            const std::uint32_t key = 3 * f + static_cast<std::uint32_t>(k);
            const TetGeometry& a = p.geo[static_cast<std::size_t>(k)];
            const std::uint32_t ta = first[f] + static_cast<std::uint32_t>(k);
            if (options.check_overlaps) {
              m.for_each_candidate(key, all_dirty, tet_mark, key + 1, [&](std::uint32_t other) {
                const std::uint32_t g = other / 3;
                if (other == key || (is_dirty[g] && other < key)) return;
                if (!boxes_overlap(a.box, m.key_box[other])) return;
                const TetGeometry& b = m.prisms[g].geo[other % 3];
                ++out.candidates;
                if (!tets_intersect(a, b, options)) return;
                const std::uint32_t tb = first[g] + other % 3;
                out.pairs.push_back({std::min(ta, tb), std::max(ta, tb)});
              });
            }
            if (options.check_leaks) {
              bool leak = centroid_outside(m.tester, a);
              if (!leak)
                m.for_each_triangle(key, triangle_mark, key + 1, [&](std::uint32_t t) {
                  if (!leak && surface_triangle_crosses(m.surface, t, a, options)) leak = true;
                });
              if (leak) out.leaking.push_back(ta);
            }
          }
        }
      },
      std::max<std::size_t>(16, dirty.size() / 32));

  std::vector<std::array<std::uint32_t, 2>> pairs;
  std::vector<std::uint32_t> leaking;
  for (const Found& f : found) {
    result.overlap_candidate_pairs += f.candidates;
    pairs.insert(pairs.end(), f.pairs.begin(), f.pairs.end());
    leaking.insert(leaking.end(), f.leaking.begin(), f.leaking.end());
  }
  std::sort(pairs.begin(), pairs.end());
  result.overlaps_checked = options.check_overlaps;
  result.overlapping_pairs = pairs.size();
  for (const auto& pair : pairs)
    if (result.first_overlapping_pairs.size() < options.max_listed)
      result.first_overlapping_pairs.push_back(pair);
  result.leaks_checked = options.check_leaks;
  result.leaking_tets = leaking.size();  // in increasing order already: dirty is sorted
  for (const std::uint32_t t : leaking) list_item(result.first_leaking_tets, options.max_listed, t);

  // Prisms offending now are tested again next time, whether they move or not.
  std::fill(m.offended.begin(), m.offended.end(), 0);
  auto offend = [&](std::uint32_t t) { m.offended[mesh.source_triangle[t]] = 1; };
  for (const auto& pair : pairs) {
    offend(pair[0]);
    offend(pair[1]);
  }
  for (const std::uint32_t t : leaking) offend(t);
  result.intersection_seconds = seconds_since(intersection_start);
  result.seconds = seconds_since(start);
  return result;
}

std::string describe_problems(const ShellCheckResult& r) {
  std::ostringstream s;
  const auto line = [&](std::size_t count, const char* what,
                        const std::vector<std::uint32_t>& first) {
    if (count == 0) return;
    s << count << ' ' << what;
    if (!first.empty()) s << " (first: " << format_list(first) << ')';
    s << '\n';
  };
  line(r.inverted_tets, "inverted tets", r.first_inverted_tets);
  line(r.zero_volume_tets, "zero-volume tets", r.first_zero_volume_tets);
  line(r.outside_inner_vertices, "inner vertices outside the surface", r.first_outside_vertices);
  line(r.moved_surface_points, "surface points moved", r.first_moved_surface_points);
  line(r.missing_triangles, "input triangles not a face of any tet", r.first_missing_triangles);
  line(r.shared_triangles, "input triangles shared by several tets", r.first_shared_triangles);
  line(r.misoriented_triangles, "input triangles on a tet turned the wrong way",
       r.first_misoriented_triangles);
  line(r.nonmanifold_faces, "faces shared by three or more tets", {});
  if (r.overlapping_pairs > 0) {
    s << r.overlapping_pairs << " overlapping tet pairs (first:";
    for (std::size_t i = 0; i < r.first_overlapping_pairs.size(); ++i)
      s << (i ? ", " : " ") << '(' << r.first_overlapping_pairs[i][0] << ", "
        << r.first_overlapping_pairs[i][1] << ')';
    s << ")\n";
  }
  line(r.leaking_tets, "tets reaching outside the surface", r.first_leaking_tets);
  if (r.too_many_tets) s << r.tets << " tets for " << r.faces << " triangles: more than 3 per\n";
  return s.str();
}

bool point_outside_surface(const SurfaceMesh& surface, const Vec3d& p, double tolerance) {
  return InsideTester(surface, tolerance).outside(p);
}

bool tets_overlap(const std::array<Vec3d, 4>& a, const std::array<Vec3d, 4>& b,
                  double tolerance) {
  return geometries_overlap(tet_geometry(a), tet_geometry(b), tolerance);
}

}  // namespace vdb_shell
