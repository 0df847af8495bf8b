// shapes.cpp — see shapes.h.
//
// Every shape is assembled from three welded building blocks, each oriented so that the normal
// points out of the solid:
//   * rings: closed loops of vertices, counter-clockwise around an axis (z for the shapes of
//     revolution), all of one shape with the same number of vertices at the same phases;
//   * stitch(a, b): the band of quads between two rings (or a fan to a pole). Its normal is on
//     the right of the direction a -> b when the rings are counter-clockwise, so a profile
//     traversed counter-clockwise in the (r, z) half-plane gives an outward surface;
//   * fan_disk: a fan of triangles (centre, corner k, corner k+1) with each triangle split into
//     n^2 triangles (ring j of the disk has sectors * j vertices): caps and hemispheres with
//     well-shaped triangles and no pole singularity.
// Quads are split along their shorter diagonal (the first one on a tie), so output is
// deterministic and planar quads give no slivers.
#include "assets/shapes.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <map>
#include <sstream>
#include <tuple>

#include "assets/flap.h"
#include "core/base/errors.h"

namespace vdb_shell {
namespace {

using Ring = std::vector<std::uint32_t>;

constexpr std::uint32_t kUnused = 0xffffffffu;

/// Collects welded vertices and outward triangles.
class MeshBuilder {
 public:
  std::uint32_t add(const Vec3d& p) {
    mesh_.points.push_back(p);
    return static_cast<std::uint32_t>(mesh_.points.size() - 1);
  }
  const Vec3d& point(std::uint32_t i) const { return mesh_.points[i]; }

  void triangle(std::uint32_t a, std::uint32_t b, std::uint32_t c) {
    mesh_.triangles.push_back({a, b, c});
  }

  /// Quad a, b, c, d counter-clockwise seen from outside, split along its shorter diagonal.
  void quad(std::uint32_t a, std::uint32_t b, std::uint32_t c, std::uint32_t d) {
    const double ac = norm2(point(c) - point(a));
    const double bd = norm2(point(d) - point(b));
    if (bd < ac * (1.0 - 1e-9)) {
      triangle(a, b, d);
      triangle(b, c, d);
    } else {
      triangle(a, b, c);
      triangle(a, c, d);
    }
  }

  /// The band between rings `a` and `b` (same size, same phase), or the fan between a ring and
  /// a single pole vertex. Outward when the rings are counter-clockwise around the axis and the
  /// outside is on the right of the direction a -> b.
  void stitch(const Ring& a, const Ring& b) {
    if (a.size() == 1) {
      for (std::size_t i = 0; i < b.size(); ++i) triangle(a[0], b[(i + 1) % b.size()], b[i]);
      return;
    }
    if (b.size() == 1) {
      for (std::size_t i = 0; i < a.size(); ++i) triangle(a[i], a[(i + 1) % a.size()], b[0]);
      return;
    }
    const std::size_t s = a.size();
    for (std::size_t i = 0; i < s; ++i) {
      const std::size_t k = (i + 1) % s;
      quad(a[i], a[k], b[k], b[i]);
    }
  }

  /// A ring of `count` vertices, vertex m at position(m).
  Ring ring(int count, const std::function<Vec3d(int)>& position) {
    Ring r(static_cast<std::size_t>(count));
    for (int m = 0; m < count; ++m) r[static_cast<std::size_t>(m)] = add(position(m));
    return r;
  }

  /// The mesh, without the vertices no triangle uses (e.g. inside a blade's root patch); the
  /// others keep their order.
  SurfaceMesh take() {
    std::vector<std::uint32_t> remap(mesh_.points.size(), kUnused);
    for (const Triangle& t : mesh_.triangles) {
      for (std::uint32_t v : t) remap[v] = 0;
    }
    std::uint32_t next = 0;
    for (std::size_t v = 0; v < remap.size(); ++v) {
      if (remap[v] == kUnused) continue;
      mesh_.points[next] = mesh_.points[v];
      remap[v] = next++;
    }
    mesh_.points.resize(next);
    for (Triangle& t : mesh_.triangles) {
      for (std::uint32_t& v : t) v = remap[v];
    }
    return std::move(mesh_);
  }

 private:
  SurfaceMesh mesh_;
};

/// Position of vertex i (0 <= i < j) of sector `sector` on ring j (1 <= j <= n) of a fan disk.
using DiskPosition = std::function<Vec3d(int j, int sector, int i)>;

/// A fan of `sectors` triangles around `centre`, each split into n^2 triangles; ring j (j >= 1)
/// has sectors * j vertices, vertex sector * j + i at position(j, sector, i). Ring n is `outer`
/// (given, shared with the rest of the shape; sectors * n vertices). Unflipped, the triangles
/// are oriented like (centre, corner k, corner k + 1), i.e. counter-clockwise around the axis
/// the sectors turn around; `flip` reverses them.
void fan_disk(MeshBuilder& mb, int sectors, int n, std::uint32_t centre, const Ring& outer,
              const DiskPosition& position, bool flip) {
  std::vector<Ring> rings(static_cast<std::size_t>(n + 1));
  rings[0] = {centre};
  for (int j = 1; j < n; ++j) {
    rings[static_cast<std::size_t>(j)] =
        mb.ring(sectors * j, [&](int m) { return position(j, m / j, m % j); });
  }
  rings[static_cast<std::size_t>(n)] = outer;
  auto id = [&](int j, int sector, int i) -> std::uint32_t {
    if (j == 0) return centre;
    const Ring& r = rings[static_cast<std::size_t>(j)];
    return r[static_cast<std::size_t>((sector * j + i) % (sectors * j))];
  };
  auto emit = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c) {
    if (flip) {
      mb.triangle(a, c, b);
    } else {
      mb.triangle(a, b, c);
    }
  };
  for (int sector = 0; sector < sectors; ++sector) {
    for (int j = 1; j <= n; ++j) {
      for (int i = 0; i < j; ++i) {
        emit(id(j - 1, sector, i), id(j, sector, i), id(j, sector, i + 1));
      }
      for (int i = 0; i + 1 < j; ++i) {
        emit(id(j - 1, sector, i), id(j, sector, i + 1), id(j - 1, sector, i + 1));
      }
    }
  }
}

/// A ring of `count` vertices counter-clockwise around +z: radius r, height z, vertex m at the
/// angle 2 pi m / count.
Ring ring_z(MeshBuilder& mb, int count, double r, double z) {
  return mb.ring(count, [&](int m) {
    const double phi = 2.0 * kPi * m / count;
    return Vec3d{r * std::cos(phi), r * std::sin(phi), z};
  });
}

/// Flat polar disk of radius `radius` at height z (fan_disk with rings at radius R j / n).
void polar_cap(MeshBuilder& mb, int sectors, int n, double radius, double z, const Ring& outer,
               bool facing_down) {
  const std::uint32_t centre = mb.add({0.0, 0.0, z});
  fan_disk(
      mb, sectors, n, centre, outer,
      [&](int j, int sector, int i) {
        const double r = radius * j / n;
        const double phi = 2.0 * kPi * (sector * j + i) / (sectors * j);
        return Vec3d{r * std::cos(phi), r * std::sin(phi), z};
      },
      facing_down);
}

/// A point of the (r, z) half-plane.
struct ProfilePoint {
  double r = 0.0;
  double z = 0.0;
};

/// Appends the points of segment a -> b split into `segments` pieces, without b.
void append_segment(std::vector<ProfilePoint>& out, ProfilePoint a, ProfilePoint b, int segments) {
  for (int k = 0; k < segments; ++k) {
    const double t = static_cast<double>(k) / segments;
    out.push_back({a.r + t * (b.r - a.r), a.z + t * (b.z - a.z)});
  }
}

/// Surface of revolution of a closed profile (counter-clockwise in the (r, z) half-plane, away
/// from the axis) with `segments` vertices per ring: a genus-1 solid.
void revolve_closed(MeshBuilder& mb, const std::vector<ProfilePoint>& profile, int segments) {
  std::vector<Ring> rings;
  rings.reserve(profile.size());
  for (const ProfilePoint& p : profile) rings.push_back(ring_z(mb, segments, p.r, p.z));
  for (std::size_t k = 0; k < rings.size(); ++k) {
    mb.stitch(rings[k], rings[(k + 1) % rings.size()]);
  }
}

// ---- the shapes ------------------------------------------------------------------------------

SurfaceMesh make_box(int detail) {
  const int n = 2 * detail;
  MeshBuilder mb;
  std::map<std::tuple<int, int, int>, std::uint32_t> lattice;
  auto vertex = [&](int ix, int iy, int iz) {
    const auto key = std::make_tuple(ix, iy, iz);
    const auto found = lattice.find(key);
    if (found != lattice.end()) return found->second;
    const std::uint32_t v =
        mb.add({-0.5 + static_cast<double>(ix) / n, -0.5 + static_cast<double>(iy) / n,
                -0.5 + static_cast<double>(iz) / n});
    lattice.emplace(key, v);
    return v;
  };
  // Per side: the constant axis and its value, then the axes u and v with u x v = outward.
  struct Side {
    int axis, value, u, v;
  };
  const Side sides[6] = {{0, n, 1, 2}, {0, 0, 2, 1}, {1, n, 2, 0},
                         {1, 0, 0, 2}, {2, n, 0, 1}, {2, 0, 1, 0}};
  for (const Side& side : sides) {
    auto at = [&](int a, int b) {
      int c[3];
      c[side.axis] = side.value;
      c[side.u] = a;
      c[side.v] = b;
      return vertex(c[0], c[1], c[2]);
    };
    for (int a = 0; a < n; ++a) {
      for (int b = 0; b < n; ++b) mb.quad(at(a, b), at(a + 1, b), at(a + 1, b + 1), at(a, b + 1));
    }
  }
  return mb.take();
}

SurfaceMesh make_cylinder(int detail) {
  constexpr double kRadius = 0.5;
  const int segments = 8 * detail, rows = 2 * detail;
  MeshBuilder mb;
  std::vector<Ring> rings;
  for (int k = 0; k <= rows; ++k) {
    rings.push_back(ring_z(mb, segments, kRadius, -0.5 + static_cast<double>(k) / rows));
  }
  for (int k = 0; k < rows; ++k) mb.stitch(rings[k], rings[k + 1]);
  polar_cap(mb, 8, detail, kRadius, -0.5, rings.front(), true);
  polar_cap(mb, 8, detail, kRadius, 0.5, rings.back(), false);
  return mb.take();
}

SurfaceMesh make_sphere(int detail) {
  constexpr double kRadius = 0.5;
  const int slices = 20 * detail, stacks = 20 * detail;
  MeshBuilder mb;
  Ring previous = {mb.add({0.0, 0.0, -kRadius})};
  for (int k = 1; k < stacks; ++k) {
    const double theta = kPi * k / stacks;
    Ring ring = ring_z(mb, slices, kRadius * std::sin(theta), -kRadius * std::cos(theta));
    mb.stitch(previous, ring);
    previous = std::move(ring);
  }
  mb.stitch(previous, {mb.add({0.0, 0.0, kRadius})});
  return mb.take();
}

SurfaceMesh make_tube(int detail) {
  constexpr double kInner = 0.3, kOuter = 0.5, kHalfHeight = 0.5;
  std::vector<ProfilePoint> profile;
  append_segment(profile, {kInner, -kHalfHeight}, {kOuter, -kHalfHeight}, 2 * detail);
  append_segment(profile, {kOuter, -kHalfHeight}, {kOuter, kHalfHeight}, 6 * detail);
  append_segment(profile, {kOuter, kHalfHeight}, {kInner, kHalfHeight}, 2 * detail);
  append_segment(profile, {kInner, kHalfHeight}, {kInner, -kHalfHeight}, 6 * detail);
  MeshBuilder mb;
  revolve_closed(mb, profile, 16 * detail);
  return mb.take();
}

SurfaceMesh make_torus(int detail) {
  constexpr double kMajor = 0.35, kMinor = 0.15;
  const int around = 12 * detail;
  std::vector<ProfilePoint> profile;
  for (int k = 0; k < around; ++k) {
    const double psi = 2.0 * kPi * k / around;
    profile.push_back({kMajor + kMinor * std::cos(psi), kMinor * std::sin(psi)});
  }
  MeshBuilder mb;
  revolve_closed(mb, profile, 24 * detail);
  return mb.take();
}

SurfaceMesh make_bowl(int detail) {
  constexpr double kOuter = 0.5, kWall = 0.03, kRim = 0.25;  // rim height; sphere centre there
  constexpr int kSectors = 5;
  const int n = 16 * detail, segments = kSectors * n, rim_rows = detail;
  MeshBuilder mb;
  // Rim: flat annulus at z = kRim from the outer to the inner radius (outward normal +z).
  std::vector<Ring> rim;
  for (int q = 0; q <= rim_rows; ++q) {
    rim.push_back(ring_z(mb, segments, kOuter - kWall * q / rim_rows, kRim));
  }
  for (int q = 0; q < rim_rows; ++q) mb.stitch(rim[q], rim[q + 1]);
  // Hemispheres below the rim: polar angle theta = (pi / 2) j / n from the bottom pole.
  auto hemisphere = [&](double radius, const Ring& outer, bool flip) {
    const std::uint32_t pole = mb.add({0.0, 0.0, kRim - radius});
    fan_disk(
        mb, kSectors, n, pole, outer,
        [&](int j, int sector, int i) {
          const double theta = 0.5 * kPi * j / n;
          const double phi = 2.0 * kPi * (sector * j + i) / (kSectors * j);
          return Vec3d{radius * std::sin(theta) * std::cos(phi),
                       radius * std::sin(theta) * std::sin(phi), kRim - radius * std::cos(theta)};
        },
        flip);
  };
  hemisphere(kOuter, rim.front(), true);  // outside of the bowl: normals away from the centre
  hemisphere(kOuter - kWall, rim.back(), false);  // inside: normals towards the centre
  return mb.take();
}

SurfaceMesh make_funnel(int detail) {
  constexpr double kWall = 0.03;
  const ProfilePoint mid[3] = {{0.1, -0.5}, {0.1, -0.15}, {0.485, 0.5}};
  const int rows[2] = {3 * detail, 6 * detail};  // neck, cone
  // Mid-surface samples and their offset directions (right-hand normals of the upward profile,
  // mitred at the kink so that the wall keeps its thickness).
  std::vector<ProfilePoint> centre;
  std::vector<ProfilePoint> offset;
  ProfilePoint normals[2];
  for (int s = 0; s < 2; ++s) {
    const double dr = mid[s + 1].r - mid[s].r, dz = mid[s + 1].z - mid[s].z;
    const double len = std::hypot(dr, dz);
    normals[s] = {dz / len, -dr / len};
  }
  const double half = 0.5 * kWall;
  for (int s = 0; s < 2; ++s) {
    for (int k = 0; k < rows[s]; ++k) {
      const double t = static_cast<double>(k) / rows[s];
      centre.push_back(
          {mid[s].r + t * (mid[s + 1].r - mid[s].r), mid[s].z + t * (mid[s + 1].z - mid[s].z)});
      ProfilePoint nrm = normals[s];
      if (s == 1 && k == 0) {  // the kink: mitre
        const double mr = normals[0].r + normals[1].r, mz = normals[0].z + normals[1].z;
        const double ml = std::hypot(mr, mz);
        const double scale = 1.0 / ((mr / ml) * normals[0].r + (mz / ml) * normals[0].z);
        nrm = {mr / ml * scale, mz / ml * scale};
      }
      offset.push_back({half * nrm.r, half * nrm.z});
    }
  }
  centre.push_back(mid[2]);
  offset.push_back({half * normals[1].r, half * normals[1].z});
  const std::size_t last = centre.size() - 1;
  auto outer = [&](std::size_t k) {
    return ProfilePoint{centre[k].r + offset[k].r, centre[k].z + offset[k].z};
  };
  auto inner = [&](std::size_t k) {
    return ProfilePoint{centre[k].r - offset[k].r, centre[k].z - offset[k].z};
  };
  // Counter-clockwise around the wall's cross-section: bottom rim (inner to outer), up the
  // outside, top rim (outer to inner), down the inside.
  std::vector<ProfilePoint> profile;
  append_segment(profile, inner(0), outer(0), detail);
  for (std::size_t k = 0; k < last; ++k) profile.push_back(outer(k));
  append_segment(profile, outer(last), inner(last), detail);
  for (std::size_t k = last; k > 0; --k) profile.push_back(inner(k));
  MeshBuilder mb;
  revolve_closed(mb, profile, 32 * detail);
  return mb.take();
}

SurfaceMesh make_star(int detail) {
  constexpr double kOuter = 0.5, kHalfHeight = 0.15;
  constexpr int kCorners = 10;
  // Inner radius of the regular star polygon {5/2}: R cos(72 deg) / cos(36 deg).
  const double inner = kOuter * std::cos(0.4 * kPi) / std::cos(0.2 * kPi);
  Vec3d corners[kCorners];
  for (int k = 0; k < kCorners; ++k) {
    const double angle = 0.5 * kPi + k * kPi / 5.0;
    const double r = k % 2 == 0 ? kOuter : inner;
    corners[k] = {r * std::cos(angle), r * std::sin(angle), 0.0};
  }
  const int n = 4 * detail, rows = 3 * detail;
  auto boundary = [&](int sector, double t, double z) {
    const Vec3d a = corners[sector % kCorners], b = corners[(sector + 1) % kCorners];
    const Vec3d p = a + t * (b - a);
    return Vec3d{p.x, p.y, z};
  };
  MeshBuilder mb;
  std::vector<Ring> rings;
  for (int l = 0; l <= rows; ++l) {
    const double z = -kHalfHeight + 2.0 * kHalfHeight * l / rows;
    rings.push_back(
        mb.ring(kCorners * n, [&](int m) { return boundary(m / n, double(m % n) / n, z); }));
  }
  for (int l = 0; l < rows; ++l) mb.stitch(rings[l], rings[l + 1]);
  auto cap = [&](double z, const Ring& outer, bool facing_down) {
    const std::uint32_t centre = mb.add({0.0, 0.0, z});
    fan_disk(
        mb, kCorners, n, centre, outer,
        [&](int j, int sector, int i) {
          const Vec3d a = corners[sector], b = corners[(sector + 1) % kCorners];
          const Vec3d p = (double(j) / n) * a + (double(i) / n) * (b - a);
          return Vec3d{p.x, p.y, z};
        },
        facing_down);
  };
  cap(-kHalfHeight, rings.front(), true);
  cap(kHalfHeight, rings.back(), false);
  return mb.take();
}

/// Translates the bounding-box centre to the origin and scales the longest side to 1.
void normalize_to_unit_cube(SurfaceMesh& mesh) {
  const BBox box = bounding_box(mesh);
  const Vec3d c = 0.5 * (box.lo + box.hi);
  const double s = 1.0 / box.max_side();
  for (Vec3d& p : mesh.points) p = (p - c) * s;
}

SurfaceMesh make_horn(int detail) {
  constexpr double kBend = 0.6, kBaseRadius = 0.22;
  constexpr double kArc = 100.0 * kPi / 180.0;  // bend angle of the spine
  const int segments = 12 * detail, rings_count = 17 * detail;
  // Spine: circular arc in the xz-plane from the origin, leaving along +z and bending to +x;
  // frame (n1, n2, tangent) right-handed, so rings turn counter-clockwise around the tangent.
  auto spine = [&](double u) {
    return Vec3d{kBend * (1.0 - std::cos(kArc * u)), 0.0, kBend * std::sin(kArc * u)};
  };
  auto n1 = [&](double u) { return Vec3d{std::cos(kArc * u), 0.0, -std::sin(kArc * u)}; };
  const Vec3d n2{0.0, 1.0, 0.0};
  auto ring_point = [&](double u, double radius, double phi) {
    return spine(u) + radius * (std::cos(phi) * n1(u) + std::sin(phi) * n2);
  };
  MeshBuilder mb;
  std::vector<Ring> rings;
  for (int k = 0; k < rings_count; ++k) {
    const double u = static_cast<double>(k) / rings_count;
    const double radius = kBaseRadius * (1.0 - u);
    rings.push_back(
        mb.ring(segments, [&](int m) { return ring_point(u, radius, 2.0 * kPi * m / segments); }));
  }
  for (int k = 0; k + 1 < rings_count; ++k) mb.stitch(rings[k], rings[k + 1]);
  mb.stitch(rings.back(), {mb.add(spine(1.0))});  // the sharp tip
  constexpr int kCapSectors = 12;
  const std::uint32_t centre = mb.add(spine(0.0));
  fan_disk(
      mb, kCapSectors, detail, centre, rings.front(),
      [&](int j, int sector, int i) {
        const double phi = 2.0 * kPi * (sector * j + i) / (kCapSectors * j);
        return ring_point(0.0, kBaseRadius * j / detail, phi);
      },
      true);
  SurfaceMesh mesh = mb.take();
  normalize_to_unit_cube(mesh);
  return mesh;
}

SurfaceMesh make_pointy(int detail) {
  constexpr double kBodyRadius = 0.45, kSpikeRadius = 0.2;
  constexpr double kBottom = -0.5, kShoulder = -0.2, kTip = 0.5;
  const int segments = 8 * detail, spike_rings = 4 * detail;
  MeshBuilder mb;
  // Profile counter-clockwise in (r, z): up the body, in along the shoulder, up the spike.
  std::vector<Ring> rings;
  for (int k = 0; k <= detail; ++k) {
    rings.push_back(
        ring_z(mb, segments, kBodyRadius, kBottom + (kShoulder - kBottom) * k / detail));
  }
  for (int k = 1; k <= detail; ++k) {
    rings.push_back(
        ring_z(mb, segments, kBodyRadius + (kSpikeRadius - kBodyRadius) * k / detail, kShoulder));
  }
  for (int k = 1; k < spike_rings; ++k) {
    const double u = static_cast<double>(k) / spike_rings;
    rings.push_back(ring_z(mb, segments, kSpikeRadius * std::pow(1.0 - u, 1.5),
                           kShoulder + (kTip - kShoulder) * u));
  }
  rings.push_back({mb.add({0.0, 0.0, kTip})});
  for (std::size_t k = 0; k + 1 < rings.size(); ++k) mb.stitch(rings[k], rings[k + 1]);
  polar_cap(mb, 8, detail, kBodyRadius, kBottom, rings.front(), true);
  return mb.take();
}

SurfaceMesh make_propeller(int detail) {
  constexpr double kHubRadius = 0.1, kHalfHeight = 0.15, kTipRadius = 0.5;
  constexpr int kBlades = 3;
  const int segments = 24 * detail, rows = 8 * detail;
  const int width = detail, chord_rows = 6 * detail, first_row = detail;  // blade root patch
  const int layers = 8 * detail;
  MeshBuilder mb;
  std::vector<Ring> hub;
  for (int k = 0; k <= rows; ++k) {
    hub.push_back(ring_z(mb, segments, kHubRadius, -kHalfHeight + 2.0 * kHalfHeight * k / rows));
  }
  auto in_root = [&](int row, int segment) {
    if (row < first_row || row >= first_row + chord_rows) return false;
    for (int b = 0; b < kBlades; ++b) {
      const int m0 = b * segments / kBlades;
      if (segment >= m0 && segment < m0 + width) return true;
    }
    return false;
  };
  for (int k = 0; k < rows; ++k) {
    for (int m = 0; m < segments; ++m) {
      if (in_root(k, m)) continue;
      const std::size_t a = static_cast<std::size_t>(m);
      const std::size_t b = static_cast<std::size_t>((m + 1) % segments);
      mb.quad(hub[k][a], hub[k][b], hub[k + 1][b], hub[k + 1][a]);
    }
  }
  polar_cap(mb, 8, 3 * detail, kHubRadius, -kHalfHeight, hub.front(), true);
  polar_cap(mb, 8, 3 * detail, kHubRadius, kHalfHeight, hub.back(), false);

  // The root patch boundary in patch coordinates (a across the blade, c along its chord),
  // counter-clockwise seen from outside (a along the hub's tangent, c along +z).
  std::vector<std::pair<int, int>> loop;
  for (int a = 0; a < width; ++a) loop.emplace_back(a, 0);
  for (int c = 0; c < chord_rows; ++c) loop.emplace_back(width, c);
  for (int a = width; a > 0; --a) loop.emplace_back(a, chord_rows);
  for (int c = chord_rows; c > 0; --c) loop.emplace_back(0, c);

  for (int b = 0; b < kBlades; ++b) {
    const int m0 = b * segments / kBlades;
    const double theta = 2.0 * kPi * (m0 + 0.5 * width) / segments;
    const Vec3d radial{std::cos(theta), std::sin(theta), 0.0};
    const Vec3d tangent{-std::sin(theta), std::cos(theta), 0.0};
    const Vec3d up{0.0, 0.0, 1.0};
    Ring previous;
    for (const auto& [a, c] : loop) {
      previous.push_back(hub[static_cast<std::size_t>(first_row + c)]
                            [static_cast<std::size_t>((m0 + a) % segments)]);
    }
    // Cross-section at layer l: a thin rectangle perpendicular to the blade axis, twisted by
    // the pitch angle (40 degrees near the hub, 20 at the tip), chord and thickness tapering.
    auto section = [&](int l, int a, int c) {
      const double f = static_cast<double>(l) / layers;
      const double pitch = (40.0 - 20.0 * f) * kPi / 180.0;
      const double chord = 0.26 - 0.12 * f * f, thickness = 0.035 - 0.015 * f;
      const Vec3d across = std::cos(pitch) * tangent - std::sin(pitch) * up;
      const Vec3d along = std::sin(pitch) * tangent + std::cos(pitch) * up;
      const double radius = kHubRadius + (kTipRadius - kHubRadius) * f;
      return radius * radial + (double(a) / width - 0.5) * thickness * across +
             (double(c) / chord_rows - 0.5) * chord * along;
    };
    for (int l = 1; l <= layers; ++l) {
      Ring current;
      for (const auto& [a, c] : loop) current.push_back(mb.add(section(l, a, c)));
      mb.stitch(previous, current);
      previous = std::move(current);
    }
    // Flat blade tip: the (width x chord_rows) grid of the last section, facing outward.
    std::vector<std::vector<std::uint32_t>> grid(
        static_cast<std::size_t>(width + 1),
        std::vector<std::uint32_t>(static_cast<std::size_t>(chord_rows + 1)));
    for (std::size_t k = 0; k < loop.size(); ++k) {
      grid[static_cast<std::size_t>(loop[k].first)][static_cast<std::size_t>(loop[k].second)] =
          previous[k];
    }
    for (int a = 1; a < width; ++a) {
      for (int c = 1; c < chord_rows; ++c) {
        grid[static_cast<std::size_t>(a)][static_cast<std::size_t>(c)] =
            mb.add(section(layers, a, c));
      }
    }
    for (std::size_t a = 0; a < static_cast<std::size_t>(width); ++a) {
      for (std::size_t c = 0; c < static_cast<std::size_t>(chord_rows); ++c) {
        mb.quad(grid[a][c], grid[a + 1][c], grid[a + 1][c + 1], grid[a][c + 1]);
      }
    }
  }
  return mb.take();
}

struct ShapeEntry {
  ShapeInfo info;
  SurfaceMesh (*make)(int detail);
};

const std::vector<ShapeEntry>& registry() {
  static const std::vector<ShapeEntry> entries = {
      {{"box", "cube [-0.5, 0.5]^3, 2N x 2N quads per side", 48}, make_box},
      {{"cylinder", "radius 0.5, height 1, flat caps", 48}, make_cylinder},
      {{"sphere", "UV sphere of radius 0.5", 760}, make_sphere},
      {{"tube", "hollow cylinder, radii 0.3 / 0.5, height 1 (genus 1)", 512}, make_tube},
      {{"torus", "major radius 0.35, minor radius 0.15 (genus 1)", 576}, make_torus},
      {{"bowl", "hemispherical bowl, outer radius 0.5, wall 0.03, flat rim", 2720}, make_bowl},
      {{"funnel", "cone (radius 0.485 to 0.1) and neck, wall 0.03, open ends (genus 1)", 1280},
       make_funnel},
      {{"star", "prism over a regular 5-point star, radius 0.5, thickness 0.3", 560}, make_star},
      {{"horn", "curved cone tapering to a sharp tip along a 100-degree arc", 408}, make_horn},
      {{"pointy", "cylindrical body (radius 0.45) with a sharp concave spike", 96}, make_pointy},
      {{"propeller", "hub (radius 0.1) with 3 twisted blades to radius 0.5", 1200}, make_propeller},
      {{"flap", "domed box with two thin flaps lifted off its top: a folded vertex", 52},
       make_flap},
  };
  return entries;
}

}  // namespace

const std::vector<ShapeInfo>& shape_catalog() {
  static const std::vector<ShapeInfo> catalog = [] {
    std::vector<ShapeInfo> out;
    for (const ShapeEntry& e : registry()) out.push_back(e.info);
    return out;
  }();
  return catalog;
}

SurfaceMesh make_shape(const std::string& name, int detail) {
  const auto& entries = registry();
  const auto found = std::find_if(entries.begin(), entries.end(),
                                  [&](const ShapeEntry& e) { return e.info.name == name; });
  if (found == entries.end()) {
    std::ostringstream msg;
    msg << "unknown shape '" << name << "': known shapes are ";
    for (std::size_t k = 0; k < entries.size(); ++k) {
      msg << (k == 0 ? "" : ", ") << entries[k].info.name;
    }
    msg << " (vdb_shell_shapes --list describes them)";
    throw InputError(msg.str());
  }
  if (detail < 1 || detail > kMaxShapeDetail) {
    throw InputError("shape detail must be an integer in [1, " + std::to_string(kMaxShapeDetail) +
                     "], got " + std::to_string(detail));
  }
  SurfaceMesh mesh = found->make(detail);
  if (!(signed_volume(mesh) > 0.0)) {
    throw InternalError("shape '" + name + "' at detail " + std::to_string(detail) +
                        " is not outward oriented (non-positive signed volume)");
  }
  return mesh;
}

}  // namespace vdb_shell
