// closest_triangle.h — squared distances from voxel centres to triangles in index space, in
// float: the inner loop of the interior fill (wavefront.cpp) and its refinement (refine.cpp).
// Internal to vdb_ops/fields/.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "vdb_ops/fields/fields_internal.h"

namespace vdb_shell {
namespace fields_detail {

/// A triangle in index space, float, prepared for point_triangle_distance2f.
struct TriangleF {
  float a[3], ab[3], ac[3];
  /// Face region test: the barycentric coordinates (v, w) of p's projection are (bv . ap,
  /// bw . ap); the distance there is |n . ap| (n: unit normal). NaN for degenerate triangles
  /// (every comparison false: the face test fails, and no normal "faces away").
  float bv[3], bw[3], n[3];
  /// Heights of b, c and a over the opposite edges (ac, ab, bc): a point whose barycentric
  /// coordinate of b is bv < 0 lies at least -bv * height[0] from the triangle within its plane.
  float height[3];
};

inline float dot3(const float* u, const float* v) {
  return u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
}

inline std::vector<TriangleF> float_triangles(const IndexMesh& m) {
  std::vector<TriangleF> out(m.triangles.size());
  for (std::size_t i = 0; i < out.size(); ++i) {
    const openvdb::Vec3s& a = m.points[m.triangles[i][0]];
    const openvdb::Vec3s& b = m.points[m.triangles[i][1]];
    const openvdb::Vec3s& c = m.points[m.triangles[i][2]];
    TriangleF& t = out[i];
    for (int k = 0; k < 3; ++k) {
      t.a[k] = a[k];
      t.ab[k] = b[k] - a[k];
      t.ac[k] = c[k] - a[k];
    }
    const float d00 = dot3(t.ab, t.ab), d01 = dot3(t.ab, t.ac), d11 = dot3(t.ac, t.ac);
    const float inv = 1.0f / (d00 * d11 - d01 * d01);
    const float cr[3] = {t.ab[1] * t.ac[2] - t.ab[2] * t.ac[1],
                         t.ab[2] * t.ac[0] - t.ab[0] * t.ac[2],
                         t.ab[0] * t.ac[1] - t.ab[1] * t.ac[0]};
    const float len = std::sqrt(dot3(cr, cr));
    for (int k = 0; k < 3; ++k) {
      t.bv[k] = (d11 * t.ab[k] - d01 * t.ac[k]) * inv;
      t.bw[k] = (d00 * t.ac[k] - d01 * t.ab[k]) * inv;
      t.n[k] = cr[k] / len;
    }
    const float bc[3] = {t.ac[0] - t.ab[0], t.ac[1] - t.ab[1], t.ac[2] - t.ab[2]};
    t.height[0] = len / std::sqrt(d11);
    t.height[1] = len / std::sqrt(d00);
    t.height[2] = len / std::sqrt(dot3(bc, bc));
  }
  return out;
}

/// Squared distance from p to a triangle, float (Ericson 5.1.5, as point_triangle_distance2).
inline float point_triangle_distance2f(const float (&p)[3], const TriangleF& t) {
  const float ap[3] = {p[0] - t.a[0], p[1] - t.a[1], p[2] - t.a[2]};
  // Most points project into the triangle: the plane's distance, without Ericson's regions.
  const float bv = dot3(t.bv, ap), bw = dot3(t.bw, ap);
  if (bv >= 0.0f && bw >= 0.0f && bv + bw <= 1.0f) {
    const float d = dot3(t.n, ap);
    return d * d;
  }
  const float d1 = dot3(t.ab, ap), d2 = dot3(t.ac, ap);
  if (d1 <= 0.0f && d2 <= 0.0f) return dot3(ap, ap);
  const float bp[3] = {ap[0] - t.ab[0], ap[1] - t.ab[1], ap[2] - t.ab[2]};
  const float d3 = dot3(t.ab, bp), d4 = dot3(t.ac, bp);
  if (d3 >= 0.0f && d4 <= d3) return dot3(bp, bp);
  const float vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0f && d1 >= 0.0f && d3 <= 0.0f) {
    const float v = d1 / (d1 - d3);
    const float q[3] = {ap[0] - t.ab[0] * v, ap[1] - t.ab[1] * v, ap[2] - t.ab[2] * v};
    return dot3(q, q);
  }
  const float cp[3] = {ap[0] - t.ac[0], ap[1] - t.ac[1], ap[2] - t.ac[2]};
  const float d5 = dot3(t.ab, cp), d6 = dot3(t.ac, cp);
  if (d6 >= 0.0f && d5 <= d6) return dot3(cp, cp);
  const float vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0f && d2 >= 0.0f && d6 <= 0.0f) {
    const float w = d2 / (d2 - d6);
    const float q[3] = {ap[0] - t.ac[0] * w, ap[1] - t.ac[1] * w, ap[2] - t.ac[2] * w};
    return dot3(q, q);
  }
  const float va = d3 * d6 - d5 * d4;
  if (va <= 0.0f && (d4 - d3) >= 0.0f && (d5 - d6) >= 0.0f) {
    const float w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    const float bc[3] = {t.ac[0] - t.ab[0], t.ac[1] - t.ab[1], t.ac[2] - t.ab[2]};
    const float q[3] = {bp[0] - bc[0] * w, bp[1] - bc[1] * w, bp[2] - bc[2] * w};
    return dot3(q, q);
  }
  const float denom = 1.0f / (va + vb + vc);
  const float v = vb * denom, w = vc * denom;
  const float q[3] = {ap[0] - t.ab[0] * v - t.ac[0] * w, ap[1] - t.ab[1] * v - t.ac[1] * w,
                      ap[2] - t.ab[2] * v - t.ac[2] * w};
  return dot3(q, q);
}

/// Squared distance from p to the nearest of a triangle's three edges, float: what
/// point_triangle_distance2f() measures for a triangle that is a segment or a point in float
/// (two corners within rounding of each other), where its formulas divide zero by zero.
inline float edges_distance2f(const float (&p)[3], const TriangleF& t) {
  const float ap[3] = {p[0] - t.a[0], p[1] - t.a[1], p[2] - t.a[2]};
  const float bc[3] = {t.ac[0] - t.ab[0], t.ac[1] - t.ab[1], t.ac[2] - t.ab[2]};
  const float bp[3] = {ap[0] - t.ab[0], ap[1] - t.ab[1], ap[2] - t.ab[2]};
  const auto segment = [](const float* from, const float* along) {  // from: p - start
    const float l2 = dot3(along, along);
    const float s = l2 > 0.0f ? std::min(1.0f, std::max(0.0f, dot3(from, along) / l2)) : 0.0f;
    const float q[3] = {from[0] - along[0] * s, from[1] - along[1] * s, from[2] - along[2] * s};
    return dot3(q, q);
  };
  return std::min({segment(ap, t.ab), segment(ap, t.ac), segment(bp, bc)});
}

/// Lowers (best, best_id) to the closest of the triangles cand[0, nc) to p (squared distance,
/// ties to the smaller index), exactly as measuring each with point_triangle_distance2f() would,
/// but cheaper: the triangles p projects into are measured first (their distance is the
/// plane's), and the others only where a lower bound of their distance (to the plane, and within
/// it to the triangle's nearest edge line) does not already exceed the best by more than
/// rounding. About half of the wavefront's measurements project outside the triangle, and the
/// bound rules out many of those.
inline void lower_to_closest(const float (&p)[3], const std::int32_t* cand, int nc,
                             const std::vector<TriangleF>& tris, float& best,
                             std::int32_t& best_id) {
  float bound[124];  // up to the 5^3 neighbourhood's triangles (refinement)
  int later[124];
  int n_later = 0;
  for (int q = 0; q < nc; ++q) {
    const TriangleF& t = tris[std::size_t(cand[q])];
    const float ap[3] = {p[0] - t.a[0], p[1] - t.a[1], p[2] - t.a[2]};
    const float bv = dot3(t.bv, ap), bw = dot3(t.bw, ap);
    const float d = dot3(t.n, ap);
    if (bv >= 0.0f && bw >= 0.0f && bv + bw <= 1.0f) {
      const float d2 = d * d;
      if (d2 < best || (d2 == best && cand[q] < best_id)) {
        best = d2;
        best_id = cand[q];
      }
    } else {
      const float m =
          std::max(std::max(-bv * t.height[0], -bw * t.height[1]), (bv + bw - 1.0f) * t.height[2]);
      bound[n_later] = d * d + m * m;
      later[n_later++] = q;
    }
  }
  for (int r = 0; r < n_later; ++r) {
    // Rounding of either value stays far below this margin (relative 1e-5, absolute 1e-3
    // voxels^2); NaN bounds (degenerate triangles) fail the test and are measured.
    if (bound[r] > best * 1.00001f + 1e-3f) continue;
    const std::int32_t id = cand[later[r]];
    float d2 = point_triangle_distance2f(p, tris[std::size_t(id)]);
    if (d2 != d2) d2 = edges_distance2f(p, tris[std::size_t(id)]);  // NaN: degenerate in float
    if (d2 < best || (d2 == best && id < best_id)) {
      best = d2;
      best_id = id;
    }
  }
}
/// Where the closest triangles of neighbouring voxels face directions this far apart (cosine of
/// the angle between their normals), the voxel lies on or next to the medial surface of a
/// rounded part (the centre of a sphere, the axis of a cylinder): closest-triangle cells there
/// are thinner than a voxel and its neighbours may not know its closest triangle.
inline constexpr float kMedialNormalCos = -0.25f;

}  // namespace fields_detail
}  // namespace vdb_shell
