// vec3.h — the small double-precision 3-vector used throughout core/.
//
// Plain value type with the arithmetic the pipeline needs; no dependency on OpenVDB
// so that core/ headers stay light. All coordinates are in the input's (world) units.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>

namespace vdb_shell {

inline constexpr double kPi = 3.14159265358979323846;

struct Vec3d {
  double x = 0.0, y = 0.0, z = 0.0;

  constexpr Vec3d() = default;
  constexpr Vec3d(double x_, double y_, double z_) : x(x_), y(y_), z(z_) {}

  constexpr double operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
  double& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }

  constexpr Vec3d operator+(const Vec3d& o) const { return {x + o.x, y + o.y, z + o.z}; }
  constexpr Vec3d operator-(const Vec3d& o) const { return {x - o.x, y - o.y, z - o.z}; }
  constexpr Vec3d operator-() const { return {-x, -y, -z}; }
  constexpr Vec3d operator*(double s) const { return {x * s, y * s, z * s}; }
  constexpr Vec3d operator/(double s) const { return {x / s, y / s, z / s}; }
  Vec3d& operator+=(const Vec3d& o) {
    x += o.x;
    y += o.y;
    z += o.z;
    return *this;
  }
  Vec3d& operator-=(const Vec3d& o) {
    x -= o.x;
    y -= o.y;
    z -= o.z;
    return *this;
  }
  Vec3d& operator*=(double s) {
    x *= s;
    y *= s;
    z *= s;
    return *this;
  }
  constexpr bool operator==(const Vec3d& o) const { return x == o.x && y == o.y && z == o.z; }
  constexpr bool operator!=(const Vec3d& o) const { return !(*this == o); }
};

constexpr Vec3d operator*(double s, const Vec3d& v) { return v * s; }
constexpr double dot(const Vec3d& a, const Vec3d& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
constexpr Vec3d cross(const Vec3d& a, const Vec3d& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
constexpr double norm2(const Vec3d& v) { return dot(v, v); }
inline double norm(const Vec3d& v) { return std::sqrt(norm2(v)); }
inline double distance(const Vec3d& a, const Vec3d& b) { return norm(a - b); }
inline Vec3d normalized(const Vec3d& v) {
  const double n = norm(v);
  return n > 0.0 ? v / n : Vec3d{};
}
inline bool is_finite(const Vec3d& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}
/// std::fmin() and std::fmax() (a NaN argument loses to a number), inline: the library calls
/// cost more than the comparison in the boxes of every tet.
inline double min_number(double a, double b) { return std::isnan(a) || b < a ? b : a; }
inline double max_number(double a, double b) { return std::isnan(a) || b > a ? b : a; }
inline Vec3d min_of(const Vec3d& a, const Vec3d& b) {
  return {min_number(a.x, b.x), min_number(a.y, b.y), min_number(a.z, b.z)};
}
inline Vec3d max_of(const Vec3d& a, const Vec3d& b) {
  return {max_number(a.x, b.x), max_number(a.y, b.y), max_number(a.z, b.z)};
}

/// Signed volume of tet (a, b, c, d): positive when d lies on the side of triangle (a, b, c)
/// that its normal (b-a) x (c-a) points away from, i.e. (a,b,c) seen counter-clockwise from
/// outside the tet — the orientation VTK, Gmsh and TetGen call positive.
inline double tet_volume(const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& d) {
  return dot(cross(b - a, c - a), d - a) / 6.0;
}

/// Axis-aligned box; empty when lo > hi.
struct BBox {
  Vec3d lo{INFINITY, INFINITY, INFINITY};
  Vec3d hi{-INFINITY, -INFINITY, -INFINITY};
  void expand(const Vec3d& p) {
    lo = min_of(lo, p);
    hi = max_of(hi, p);
  }
  bool empty() const { return lo.x > hi.x || lo.y > hi.y || lo.z > hi.z; }
  Vec3d extent() const { return empty() ? Vec3d{} : hi - lo; }
  double diagonal() const { return norm(extent()); }
  double max_side() const {
    const Vec3d e = extent();
    return max_number(e.x, max_number(e.y, e.z));
  }
};

}  // namespace vdb_shell
