// tet_predicates.cpp — see tet_predicates.h; also tet_volume_class() and tets_overlap() of
// shell_checks.h.
#include "core/validity/tet_predicates.h"

#include <algorithm>
#include <cmath>

#include "core/validity/shell_checks.h"

namespace vdb_shell {
namespace {

// The extent of a set of points along an axis.
struct Interval {
  double lo, hi;
};

template <std::size_t N>
inline Interval project(const Vec3d& axis, const std::array<Vec3d, N>& p) {
  Interval r{dot(axis, p[0]), dot(axis, p[0])};
  for (std::size_t k = 1; k < N; ++k) {
    const double x = dot(axis, p[k]);
    r.lo = std::min(r.lo, x);
    r.hi = std::max(r.hi, x);
  }
  return r;
}

// The points p[k] - origin: exact for points near the origin given (Sterbenz), whatever their
// distance from the world's.
template <std::size_t N>
inline std::array<Vec3d, N> relative_to(const std::array<Vec3d, N>& p, const Vec3d& origin) {
  std::array<Vec3d, N> r;
  for (std::size_t k = 0; k < N; ++k) r[k] = p[k] - origin;
  return r;
}

// Whether two projections overlap by no more than `tolerance`: the axis separates them.
inline bool apart(const Interval& a, const Interval& b, double tolerance) {
  return b.hi <= a.lo + tolerance || a.hi <= b.lo + tolerance;
}

// The unit axis along da x db, or false for (nearly) parallel edges, which give no axis.
inline bool edge_axis(const Vec3d& da, const Vec3d& db, Vec3d& axis) {
  const Vec3d m = cross(da, db);
  const double len2 = norm2(m);
  if (!(len2 > 1e-24 * norm2(da) * norm2(db))) return false;
  axis = m / std::sqrt(len2);
  return true;
}

}  // namespace

double longest_edge(const std::array<Vec3d, 4>& p) {
  double l = 0.0;
  for (const auto& e : kTetEdge) l = std::max(l, distance(p[e[0]], p[e[1]]));
  return l;
}

TetGeometry tet_geometry(const std::array<Vec3d, 4>& p) {
  TetGeometry g;
  g.p = p;
  for (const Vec3d& x : p) g.box.expand(x);
  g.max_edge = longest_edge(p);
  for (int k = 0; k < 4; ++k) {
    const Vec3d& u = p[(k + 1) % 4];
    const Vec3d m = cross(p[(k + 2) % 4] - u, p[(k + 3) % 4] - u);
    const double len = norm(m);
    g.n[k] = len > 0.0 ? m / len : Vec3d{};
    const double base = dot(g.n[k], u - p[0]), opposite = dot(g.n[k], p[k] - p[0]);
    g.lo[k] = std::min(base, opposite);
    g.hi[k] = std::max(base, opposite);
  }
  return g;
}

bool geometries_overlap(const TetGeometry& a, const TetGeometry& b, double tolerance) {
  const std::array<Vec3d, 4> b_from_a = relative_to(b.p, a.p[0]);
  for (int k = 0; k < 4; ++k)
    if (norm2(a.n[k]) > 0.0 && apart({a.lo[k], a.hi[k]}, project(a.n[k], b_from_a), tolerance))
      return false;
  const std::array<Vec3d, 4> a_from_b = relative_to(a.p, b.p[0]);
  for (int k = 0; k < 4; ++k)
    if (norm2(b.n[k]) > 0.0 && apart({b.lo[k], b.hi[k]}, project(b.n[k], a_from_b), tolerance))
      return false;
  const std::array<Vec3d, 4> a_from_a = relative_to(a.p, a.p[0]);
  Vec3d axis;
  for (const auto& ea : kTetEdge) {
    const Vec3d da = a.p[ea[1]] - a.p[ea[0]];
    for (const auto& eb : kTetEdge)
      if (edge_axis(da, b.p[eb[1]] - b.p[eb[0]], axis) &&
          apart(project(axis, a_from_a), project(axis, b_from_a), tolerance))
        return false;
  }
  return true;
}

bool triangles_cross(const std::array<Vec3d, 3>& a_world, const std::array<Vec3d, 3>& b_world,
                     double tolerance) {
  const std::array<Vec3d, 3> a = relative_to(a_world, a_world[0]);
  const std::array<Vec3d, 3> b = relative_to(b_world, a_world[0]);
  const auto separated = [&](const Vec3d& axis) {
    const double len2 = norm2(axis);
    if (!(len2 > 0.0)) return false;
    const Vec3d u = axis / std::sqrt(len2);
    return apart(project(u, a), project(u, b), tolerance);
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

bool triangle_crosses_tet(const std::array<Vec3d, 3>& t_world, const TetGeometry& g,
                          double tolerance) {
  const std::array<Vec3d, 3> t = relative_to(t_world, g.p[0]);
  for (int k = 0; k < 4; ++k)
    if (norm2(g.n[k]) > 0.0 && apart({g.lo[k], g.hi[k]}, project(g.n[k], t), tolerance))
      return false;
  const std::array<Vec3d, 4> p = relative_to(g.p, g.p[0]);
  const Vec3d e[3] = {t[1] - t[0], t[2] - t[1], t[0] - t[2]};
  const Vec3d normal = cross(e[0], t[2] - t[0]);
  if (norm2(normal) > 0.0) {
    const Vec3d axis = normalized(normal);
    const double plane = dot(axis, t[0]);
    if (apart({plane, plane}, project(axis, p), tolerance)) return false;
  }
  Vec3d axis;
  for (const Vec3d& da : e)
    for (const auto& eb : kTetEdge)
      if (edge_axis(da, p[eb[1]] - p[eb[0]], axis) &&
          apart(project(axis, t), project(axis, p), tolerance))
        return false;
  return true;
}

// ---------------------------------------------------------------------------------------------
// The public calls of shell_checks.h.

TetVolume tet_volume_class(const std::array<Vec3d, 4>& p, double zero_volume_tolerance) {
  const double l = longest_edge(p);
  const double vol = tet_volume(p[0], p[1], p[2], p[3]);
  if (std::abs(vol) <= zero_volume_tolerance * l * l * l) return TetVolume::kZero;
  return vol < 0.0 ? TetVolume::kInverted : TetVolume::kPositive;
}

bool tets_overlap(const std::array<Vec3d, 4>& a, const std::array<Vec3d, 4>& b,
                  const ShellCheckOptions& options) {
  return tets_intersect(tet_geometry(a), tet_geometry(b), options.overlap_tolerance);
}

bool tets_overlap(const std::array<Vec3d, 4>& a, const std::array<Vec3d, 4>& b, double tolerance) {
  return geometries_overlap(tet_geometry(a), tet_geometry(b), tolerance);
}

}  // namespace vdb_shell
