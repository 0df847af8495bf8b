// geometry.h — distances and solid angles of triangles, for the checks (core/validity), the
// sectors of folded vertices (core/inner) and the
// fields' refinement (vdb_ops/fields).
#pragma once

#include <algorithm>
#include <cmath>

#include "core/base/vec3.h"

namespace vdb_shell {

/// Squared distance from p to triangle (a, b, c), world units squared (Ericson, Real-Time
/// Collision Detection 5.1.5). A degenerate triangle gives the nearest corner's.
inline double point_triangle_distance2(const Vec3d& p, const Vec3d& a, const Vec3d& b,
                                       const Vec3d& c) {
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

/// Solid angle of triangle (a, b, c) seen from p, signed: positive when (a, b, c) is
/// counter-clockwise seen from p (Van Oosterom and Strackee 1983). Over a closed outward surface
/// the sum is 4 pi at inside points, 0 outside.
inline double solid_angle(const Vec3d& p, const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  const Vec3d x = a - p, y = b - p, z = c - p;
  const double lx = norm(x), ly = norm(y), lz = norm(z);
  const double num = dot(x, cross(y, z));
  const double den = lx * ly * lz + dot(x, y) * lz + dot(y, z) * lx + dot(z, x) * ly;
  return 2.0 * std::atan2(num, den);
}

}  // namespace vdb_shell
