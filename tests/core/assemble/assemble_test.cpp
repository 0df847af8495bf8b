// assemble_test.cpp — assemble_shell() and split_prism() (core/assemble/assemble.h): the prism
// split (all 720 index orders, welding, every acyclic choice of cuts), whole shells on closed
// surfaces (conformity, orientation, boundary faces, T == 3F), surface vertices and cap faces,
// layers through the thickness (T == 3KF, layer points on the side edges, conformity layer by
// layer), inconsistent input.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <set>
#include <utility>

#include "assets/shapes.h"
#include "core/assemble/assemble.h"
#include "core/assemble/quality.h"
#include "core/base/errors.h"
#include "core/validity/shell_checks.h"

namespace vdb_shell {
namespace {

using Key = std::array<std::uint32_t, 3>;

Key sorted_key(std::uint32_t a, std::uint32_t b, std::uint32_t c) {
  Key k = {a, b, c};
  std::sort(k.begin(), k.end());
  return k;
}

/// The regular octahedron with vertices on the axes at distance 1, outward oriented.
SurfaceMesh octahedron() {
  SurfaceMesh m;
  m.points = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  for (int sx = 0; sx < 2; ++sx)
    for (int sy = 0; sy < 2; ++sy)
      for (int sz = 0; sz < 2; ++sz) {
        const std::uint32_t x = sx, y = 2 + sy, z = 4 + sz;
        if ((sx + sy + sz) % 2 == 0)
          m.triangles.push_back({x, y, z});
        else
          m.triangles.push_back({x, z, y});
      }
  return m;
}

Vec3d centroid(const SurfaceMesh& s) {
  Vec3d c;
  for (const Vec3d& p : s.points) c += p;
  return c / static_cast<double>(s.points.size());
}

/// One inner vertex per surface vertex: the vertex scaled by `factor` about the centroid.
ShellInput scaled_input(const SurfaceMesh& s, double factor) {
  const Vec3d c = centroid(s);
  ShellInput in;
  for (std::size_t v = 0; v < s.points.size(); ++v) {
    in.inner_points.push_back(c + (s.points[v] - c) * factor);
    in.inner_id.push_back(static_cast<std::uint32_t>(v));
  }
  return in;
}

/// Every inner vertex welded into the centroid.
ShellInput centroid_input(const SurfaceMesh& s) {
  ShellInput in;
  in.inner_points = {centroid(s)};
  in.inner_id.assign(s.points.size(), 0);
  return in;
}

double volume(const TetMesh& m, const Tet& t) {
  return tet_volume(m.points[t[0]], m.points[t[1]], m.points[t[2]], m.points[t[3]]);
}

/// How many tets have each triangle as a face.
std::map<Key, int> face_counts(const TetMesh& m) {
  std::map<Key, int> count;
  for (const Tet& t : m.tets)
    for (int k = 0; k < 4; ++k) ++count[sorted_key(t[(k + 1) % 4], t[(k + 2) % 4], t[(k + 3) % 4])];
  return count;
}

/// The invariants of a shell without welding: T == 3F, all positive, each input and inner
/// triangle a face of exactly one tet, every other face of exactly two.
void expect_conforming_shell(const SurfaceMesh& s, const ShellInput& in, const AssembleResult& r) {
  const std::size_t n = s.points.size();
  EXPECT_EQ(r.mesh.tets.size(), 3 * s.num_faces());
  for (const Tet& t : r.mesh.tets) EXPECT_GT(volume(r.mesh, t), 0.0);
  std::map<Key, int> count = face_counts(r.mesh);
  std::set<Key> boundary;
  for (const Triangle& t : s.triangles) {
    const Key outer = sorted_key(t[0], t[1], t[2]);
    const Key inner = sorted_key(static_cast<std::uint32_t>(n + in.inner_id[t[0]]),
                                 static_cast<std::uint32_t>(n + in.inner_id[t[1]]),
                                 static_cast<std::uint32_t>(n + in.inner_id[t[2]]));
    EXPECT_EQ(count[outer], 1);
    EXPECT_EQ(count[inner], 1);
    boundary.insert(outer);
    boundary.insert(inner);
  }
  for (const auto& [key, c] : count) {
    if (!boundary.count(key)) {
      EXPECT_EQ(c, 2) << key[0] << " " << key[1] << " " << key[2];
    }
  }
}

// ---------------------------------------------------------------------------------------------

/// A prism with planar sides: the inner triangle is the outer one shrunk about a point below
/// it, so its volume is known and both diagonals of each side are valid.
struct PlanarPrism {
  std::array<Vec3d, 6> corner;  ///< outer a, b, c, then inner a', b', c'
  double volume = 0;
};
PlanarPrism planar_prism() {
  const std::array<Vec3d, 3> outer = {Vec3d{0, 0, 0}, Vec3d{1, 0, 0}, Vec3d{0.2, 1, 0}};
  const Vec3d apex{0.3, 0.4, -2.0};
  PlanarPrism p;
  for (int k = 0; k < 3; ++k) {
    p.corner[k] = outer[k];
    p.corner[k + 3] = apex + (outer[k] - apex) * 0.6;
  }
  p.volume = tet_volume(outer[0], outer[2], outer[1], apex) * (1.0 - 0.6 * 0.6 * 0.6);
  return p;
}

TEST(Assemble, SplitPrismEveryIndexOrder) {
  const PlanarPrism prism = planar_prism();
  const std::array<Vec3d, 6>& corner = prism.corner;
  const double prism_volume = prism.volume;
  ASSERT_GT(prism_volume, 0.0);

  std::array<std::uint32_t, 6> ids = {0, 1, 2, 3, 4, 5};
  int orders = 0;
  do {
    ++orders;
    const PrismTets split = split_prism(ids);
    ASSERT_EQ(split.count, 3);
    EXPECT_EQ(split.dropped, 0);
    // Corner positions by global id.
    std::array<Vec3d, 6> at;
    for (int k = 0; k < 6; ++k) at[ids[k]] = corner[k];
    double sum = 0.0;
    std::set<std::pair<std::uint32_t, std::uint32_t>> edges;
    std::array<std::array<Vec3d, 4>, 3> geometry;
    for (int t = 0; t < 3; ++t) {
      const Tet& tet = split.tets[t];
      geometry[t] = {at[tet[0]], at[tet[1]], at[tet[2]], at[tet[3]]};
      const double v = tet_volume(at[tet[0]], at[tet[1]], at[tet[2]], at[tet[3]]);
      EXPECT_GT(v, 0.0);
      sum += v;
      for (int i = 0; i < 4; ++i)
        for (int j = i + 1; j < 4; ++j)
          edges.insert({std::min(tet[i], tet[j]), std::max(tet[i], tet[j])});
    }
    EXPECT_NEAR(sum, prism_volume, 1e-12);
    for (int i = 0; i < 3; ++i)
      for (int j = i + 1; j < 3; ++j) EXPECT_FALSE(tets_overlap(geometry[i], geometry[j], 1e-12));
    // Each side quad (k, k+1, k+1', k') is cut along the diagonal through its smallest index.
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t q[4] = {ids[k], ids[(k + 1) % 3], ids[3 + (k + 1) % 3], ids[3 + k]};
      const int m = static_cast<int>(std::min_element(q, q + 4) - q);
      const std::uint32_t d0 = q[m], d1 = q[(m + 2) % 4];
      const std::uint32_t o0 = q[(m + 1) % 4], o1 = q[(m + 3) % 4];
      EXPECT_TRUE(edges.count({std::min(d0, d1), std::max(d0, d1)}));
      EXPECT_FALSE(edges.count({std::min(o0, o1), std::max(o0, o1)}));
    }
    // The outer triangle is a face of one tet.
    int with_outer = 0;
    for (const Tet& tet : split.tets) {
      const std::set<std::uint32_t> s(tet.begin(), tet.end());
      with_outer += s.count(ids[0]) && s.count(ids[1]) && s.count(ids[2]);
    }
    EXPECT_EQ(with_outer, 1);
  } while (std::next_permutation(ids.begin(), ids.end()));
  EXPECT_EQ(orders, 720);
}

TEST(Assemble, SplitPrismCutFollowsEveryAcyclicCut) {
  const PlanarPrism prism = planar_prism();  // planar sides: every acyclic cut is a valid split
  const std::array<Vec3d, 6>& corner = prism.corner;
  const double prism_volume = prism.volume;
  std::array<std::uint32_t, 6> ids = {10, 11, 12, 13, 14, 15};
  int orders = 0;
  do {
    ++orders;
    // The global-index rule's cuts give split_prism()'s tets.
    const PrismTets rule = split_prism(ids);
    const int rule_cuts = prism_cuts(ids);
    ASSERT_NE(rule_cuts, kCyclicCuts[0]);
    ASSERT_NE(rule_cuts, kCyclicCuts[1]);
    const PrismTets same = split_prism_cut(ids, rule_cuts);
    ASSERT_EQ(same.count, 3);
    EXPECT_TRUE(std::equal(same.tets.begin(), same.tets.end(), rule.tets.begin()));
    std::map<std::uint32_t, Vec3d> at;
    for (int k = 0; k < 6; ++k) at[ids[k]] = corner[k];
    for (int cuts = 1; cuts < 7; ++cuts) {
      const PrismTets split = split_prism_cut(ids, cuts);
      ASSERT_EQ(split.count, 3);
      double sum = 0;
      std::set<std::pair<std::uint32_t, std::uint32_t>> edges;
      for (const Tet& tet : split.tets) {
        const double v = tet_volume(at[tet[0]], at[tet[1]], at[tet[2]], at[tet[3]]);
        EXPECT_GT(v, 0.0) << cuts;
        sum += v;
        for (int i = 0; i < 4; ++i)
          for (int j = i + 1; j < 4; ++j)
            edges.insert({std::min(tet[i], tet[j]), std::max(tet[i], tet[j])});
      }
      EXPECT_NEAR(sum, prism_volume, 1e-12) << cuts;
      // Quad k is cut along (k, (k + 1)') when bit k is set, else along (k + 1, k').
      for (int k = 0; k < 3; ++k) {
        const int j = (k + 1) % 3;
        std::pair<std::uint32_t, std::uint32_t> cut = {ids[k], ids[3 + j]},
                                                other = {ids[j], ids[3 + k]};
        if (!((cuts >> k) & 1)) std::swap(cut, other);
        EXPECT_TRUE(edges.count({std::min(cut.first, cut.second), std::max(cut.first, cut.second)}))
            << cuts << " quad " << k;
        EXPECT_FALSE(
            edges.count({std::min(other.first, other.second), std::max(other.first, other.second)}))
            << cuts << " quad " << k;
      }
    }
    EXPECT_THROW(split_prism_cut(ids, 0), InternalError);
    EXPECT_THROW(split_prism_cut(ids, 7), InternalError);
  } while (std::next_permutation(ids.begin(), ids.end()));
  EXPECT_EQ(orders, 720);
}

TEST(Assemble, SplitPrismInvertedPrismGivesNegativeTets) {
  // The inner triangle above the outer one: the prism is inverted and no tet may hide it.
  const std::array<Vec3d, 6> at = {Vec3d{0, 0, 0}, Vec3d{1, 0, 0}, Vec3d{0, 1, 0},
                                   Vec3d{0, 0, 1}, Vec3d{1, 0, 1}, Vec3d{0, 1, 1}};
  std::array<std::uint32_t, 6> ids = {0, 1, 2, 3, 4, 5};
  do {
    std::array<Vec3d, 6> p;
    for (int k = 0; k < 6; ++k) p[ids[k]] = at[k];
    const PrismTets split = split_prism(ids);
    for (int t = 0; t < split.count; ++t) {
      const Tet& tet = split.tets[t];
      EXPECT_LT(tet_volume(p[tet[0]], p[tet[1]], p[tet[2]], p[tet[3]]), 0.0);
    }
  } while (std::next_permutation(ids.begin(), ids.end()));
}

TEST(Assemble, SplitPrismWelded) {
  const Vec3d outer[3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  const Vec3d down{0, 0, -1};
  // Two inner corners welded into one vertex below the middle of their outer edge, the third
  // below its own corner; every order of the ids, the shared id taken from either corner.
  for (int lone = 0; lone < 3; ++lone) {
    const int j = (lone + 1) % 3, k = (lone + 2) % 3;
    for (int keep = 0; keep < 2; ++keep) {
      std::array<std::uint32_t, 6> ids = {0, 1, 2, 3, 4, 5};
      do {
        std::array<std::uint32_t, 6> welded = ids;
        welded[3 + j] = welded[3 + k] = keep == 0 ? ids[3 + j] : ids[3 + k];
        std::map<std::uint32_t, Vec3d> at;
        for (int c = 0; c < 3; ++c) at[welded[c]] = outer[c];
        at[welded[3 + lone]] = outer[lone] + down;
        at[welded[3 + j]] = (outer[j] + outer[k]) * 0.5 + down;
        const PrismTets split = split_prism(welded);
        EXPECT_GE(split.count, 1);
        EXPECT_LE(split.count, 2);
        EXPECT_EQ(split.count + split.dropped, 3);
        for (int t = 0; t < split.count; ++t) {
          const Tet& tet = split.tets[t];
          EXPECT_GT(tet_volume(at[tet[0]], at[tet[1]], at[tet[2]], at[tet[3]]), 0.0);
        }
      } while (std::next_permutation(ids.begin(), ids.end()));
    }
  }
  // All three inner corners one vertex: exactly the tet (outer triangle, apex), positive.
  for (std::uint32_t apex : {0u, 7u}) {
    const std::uint32_t o = apex == 0 ? 1 : 0;
    const std::array<std::uint32_t, 6> ids = {o, o + 1, o + 2, apex, apex, apex};
    const PrismTets split = split_prism(ids);
    ASSERT_EQ(split.count, 1);
    EXPECT_EQ(split.dropped, 2);
    std::map<std::uint32_t, Vec3d> at = {
        {o, outer[0]}, {o + 1, outer[1]}, {o + 2, outer[2]}, {apex, Vec3d{0.3, 0.3, -1}}};
    const Tet& t = split.tets[0];
    EXPECT_GT(tet_volume(at[t[0]], at[t[1]], at[t[2]], at[t[3]]), 0.0);
    EXPECT_EQ(std::set<std::uint32_t>(t.begin(), t.end()),
              (std::set<std::uint32_t>{o, o + 1, o + 2, apex}));
  }
}

TEST(Assemble, OctahedronShellIsConforming) {
  const SurfaceMesh s = octahedron();
  ASSERT_GT(signed_volume(s), 0.0);
  const ShellInput in = scaled_input(s, 0.5);
  const AssembleResult r = assemble_shell(s, in);
  expect_conforming_shell(s, in, r);
  EXPECT_EQ(r.dropped_degenerate_tets, 0u);
  EXPECT_EQ(r.welded_inner_vertices, 0u);
  EXPECT_EQ(r.collapsed_prisms, 0u);
  const ShellCheckResult c = check_shell(s, r.mesh);
  EXPECT_TRUE(c.valid()) << describe_problems(c);
}

TEST(Assemble, BoxShellIsConformingWithPerElementData) {
  const SurfaceMesh s = make_shape("box", 1);
  const ShellInput in = scaled_input(s, 0.5);
  const AssembleResult r = assemble_shell(s, in);
  expect_conforming_shell(s, in, r);
  const std::size_t n = s.points.size();
  const TetMesh& m = r.mesh;
  ASSERT_EQ(m.points.size(), 2 * n);
  for (std::size_t v = 0; v < n; ++v) {
    EXPECT_EQ(m.points[v], s.points[v]);
    EXPECT_EQ(m.inner[v], 0);
    EXPECT_EQ(m.thickness[v], 0.0);
    EXPECT_EQ(m.inner[n + v], 1);
    EXPECT_DOUBLE_EQ(m.thickness[n + v], distance(s.points[v], in.inner_points[v]));
  }
  ASSERT_EQ(m.source_triangle.size(), m.tets.size());
  ASSERT_EQ(m.quality.size(), m.tets.size());
  for (std::size_t t = 0; t < m.tets.size(); ++t) {
    EXPECT_EQ(m.source_triangle[t], t / 3);
    const Tet& tet = m.tets[t];
    EXPECT_DOUBLE_EQ(m.quality[t], tet_quality(m.points[tet[0]], m.points[tet[1]], m.points[tet[2]],
                                               m.points[tet[3]]));
    EXPECT_GT(m.quality[t], 0.0);
  }
  const ShellCheckResult c = check_shell(s, m);
  EXPECT_TRUE(c.valid()) << describe_problems(c);
}

TEST(Assemble, SphereShellIsConforming) {
  const SurfaceMesh s = make_shape("sphere", 1);
  const ShellInput in = scaled_input(s, 0.7);
  const AssembleResult r = assemble_shell(s, in);
  expect_conforming_shell(s, in, r);
  const ShellCheckResult c = check_shell(s, r.mesh);
  EXPECT_TRUE(c.valid()) << describe_problems(c);
}

TEST(Assemble, AllInnerVerticesWeldedGiveOneTetPerPrism) {
  for (const SurfaceMesh& s : {octahedron(), make_shape("box", 1), make_shape("sphere", 1)}) {
    const ShellInput in = centroid_input(s);
    const AssembleResult r = assemble_shell(s, in);
    const std::size_t n = s.points.size();
    EXPECT_EQ(r.mesh.tets.size(), s.num_faces());
    EXPECT_EQ(r.collapsed_prisms, s.num_faces());
    EXPECT_EQ(r.dropped_degenerate_tets, 2 * s.num_faces());
    EXPECT_EQ(r.welded_inner_vertices, n - 1);
    EXPECT_EQ(r.unused_inner_points, 0u);
    for (std::size_t t = 0; t < r.mesh.tets.size(); ++t) {
      const Tet& tet = r.mesh.tets[t];
      const Triangle& tri = s.triangles[r.mesh.source_triangle[t]];
      EXPECT_EQ(std::set<std::uint32_t>(tet.begin(), tet.end()),
                (std::set<std::uint32_t>{tri[0], tri[1], tri[2], static_cast<std::uint32_t>(n)}));
      EXPECT_GT(volume(r.mesh, tet), 0.0);
    }
    // Every face through the centre is shared by two tets.
    for (const auto& [key, c] : face_counts(r.mesh)) EXPECT_EQ(c, key[2] == n ? 2 : 1);
    const ShellCheckResult c = check_shell(s, r.mesh);
    EXPECT_TRUE(c.valid()) << describe_problems(c);
    const QualitySummary q = summarize_quality(s, r.mesh);
    EXPECT_NEAR(q.coverage, 1.0, 1e-12);
  }
}

TEST(Assemble, VerticesOnTheSurfaceTurnPrismsIntoPyramidsAndTets) {
  // Octahedron vertices 0 (+x) and 2 (+y) are their own inner vertices: the faces through one
  // of them keep two tets (a pyramid), the two faces through both keep one, the rest three.
  const SurfaceMesh s = octahedron();
  ShellInput in = scaled_input(s, 0.5);
  in.inner_id[0] = kOnSurface;
  in.inner_id[2] = kOnSurface;
  const AssembleResult r = assemble_shell(s, in);
  EXPECT_EQ(r.on_surface_vertices, 2u);
  EXPECT_EQ(r.welded_inner_vertices, 0u);
  EXPECT_EQ(r.unused_inner_points, 2u);
  std::map<std::uint32_t, int> per_face;
  for (std::size_t t = 0; t < r.mesh.tets.size(); ++t) {
    ++per_face[r.mesh.source_triangle[t]];
    EXPECT_GT(volume(r.mesh, r.mesh.tets[t]), 0.0) << "tet " << t;
  }
  std::size_t expected = 0;
  for (std::uint32_t f = 0; f < s.num_faces(); ++f) {
    const Triangle& tri = s.triangles[f];
    const int on = static_cast<int>(
        std::count_if(tri.begin(), tri.end(), [](std::uint32_t v) { return v == 0 || v == 2; }));
    EXPECT_EQ(per_face[f], 3 - on) << "face " << f;
    expected += static_cast<std::size_t>(3 - on);
  }
  EXPECT_EQ(r.mesh.tets.size(), expected);
  EXPECT_EQ(r.dropped_degenerate_tets, 3 * s.num_faces() - expected);
  // Conforming, every surface face a boundary face, no vertex 0 or 2 thickness.
  const ShellCheckResult c = check_shell(s, r.mesh);
  EXPECT_TRUE(c.valid()) << describe_problems(c);
  EXPECT_EQ(r.mesh.inner[0], 0);
  EXPECT_EQ(r.mesh.thickness[0], 0.0);
}

TEST(Assemble, CapFaceIsOneTetToItsCapPoint) {
  // Octahedron vertices 0 (+x), 2 (+y) and 4 (+z) on the surface: the face through all three has
  // no prism of its own, so it gets one tet to a cap point just below its centroid.
  const SurfaceMesh s = octahedron();
  ShellInput in = scaled_input(s, 0.5);
  for (std::uint32_t v : {0u, 2u, 4u}) in.inner_id[v] = kOnSurface;
  std::uint32_t cap = 0;
  while (sorted_key(s.triangles[cap][0], s.triangles[cap][1], s.triangles[cap][2]) != Key{0, 2, 4})
    ++cap;
  in.cap_faces = {cap};
  in.cap_points = {Vec3d{1, 1, 1} * (0.9 / 3.0)};
  const AssembleResult r = assemble_shell(s, in);
  EXPECT_EQ(r.cap_tets, 1u);
  EXPECT_EQ(r.mesh.points.size(), 6u + 6u + 1u);
  EXPECT_EQ(r.mesh.inner[12], 1);
  std::size_t on_cap = 0;
  for (std::size_t t = 0; t < r.mesh.tets.size(); ++t) {
    EXPECT_GT(volume(r.mesh, r.mesh.tets[t]), 0.0) << "tet " << t;
    if (r.mesh.source_triangle[t] == cap) {
      ++on_cap;
      EXPECT_EQ(std::set<std::uint32_t>(r.mesh.tets[t].begin(), r.mesh.tets[t].end()),
                (std::set<std::uint32_t>{0, 2, 4, 12}));
    }
  }
  EXPECT_EQ(on_cap, 1u);
  const ShellCheckResult c = check_shell(s, r.mesh);
  EXPECT_TRUE(c.valid()) << describe_problems(c);

  // A cap face needs all three corners on the surface.
  in.inner_id[4] = 4;
  EXPECT_THROW(assemble_shell(s, in), InputError);
}

TEST(Assemble, UnusedInnerPointsAreKeptAndCounted) {
  const SurfaceMesh s = octahedron();
  ShellInput in = scaled_input(s, 0.5);
  in.inner_points.push_back({0, 0, 0});
  const AssembleResult r = assemble_shell(s, in);
  EXPECT_EQ(r.unused_inner_points, 1u);
  EXPECT_EQ(r.mesh.points.size(), 13u);
  EXPECT_EQ(r.mesh.tets.size(), 24u);
}

TEST(Assemble, LayerFractionsGrowGeometricallyFromTheSurface) {
  const std::vector<double> even = layer_fractions(4, 1.0);
  ASSERT_EQ(even.size(), 5u);
  for (int k = 0; k <= 4; ++k) EXPECT_NEAR(even[k], k / 4.0, 1e-15);
  // Thicknesses 1, 1.5, 2.25 over their sum 4.75.
  const std::vector<double> graded = layer_fractions(3, 1.5);
  ASSERT_EQ(graded.size(), 4u);
  EXPECT_EQ(graded[0], 0.0);
  EXPECT_NEAR(graded[1], 1 / 4.75, 1e-15);
  EXPECT_NEAR(graded[2], 2.5 / 4.75, 1e-15);
  EXPECT_EQ(graded[3], 1.0);
  EXPECT_EQ(layer_fractions(1, 2.0), (std::vector<double>{0.0, 1.0}));
}

TEST(Assemble, LayersStackConformingPrismsAlongTheSideEdges) {
  for (const double ratio : {1.0, 1.5})
    for (const SurfaceMesh& s : {octahedron(), make_shape("sphere", 1)}) {
      const ShellInput in = scaled_input(s, 0.4);
      const int K = 4;
      AssembleOptions o;
      o.layers = K;
      o.layer_ratio = ratio;
      const AssembleResult r = assemble_shell(s, in, o);
      const TetMesh& m = r.mesh;
      const std::size_t n = s.points.size();
      ASSERT_EQ(m.tets.size(), 3 * K * s.num_faces());
      ASSERT_EQ(m.points.size(), 2 * n + n * (K - 1));
      ASSERT_EQ(m.layer.size(), m.tets.size());
      // Layer points: vertex v's, outermost first, on its edge at the fractions.
      const std::vector<double> at = layer_fractions(K, ratio);
      for (std::uint32_t v = 0; v < n; ++v)
        for (int k = 1; k < K; ++k) {
          const std::size_t p = 2 * n + v * (K - 1) + (k - 1);
          const Vec3d want = s.points[v] + (in.inner_points[v] - s.points[v]) * at[k];
          EXPECT_LT(distance(m.points[p], want), 1e-12);
          EXPECT_EQ(m.surface_vertex[p], v);
          EXPECT_EQ(m.inner[p], 1);
        }
      // Positive tets; every face of one tet is an input or inner triangle, all others of two
      // tets (conforming); each prism has 3 tets in each layer.
      for (const Tet& t : m.tets) EXPECT_GT(volume(m, t), 0.0);
      std::set<Key> boundary;
      for (const Triangle& t : s.triangles) {
        boundary.insert(sorted_key(t[0], t[1], t[2]));
        boundary.insert(sorted_key(static_cast<std::uint32_t>(n + t[0]),
                                   static_cast<std::uint32_t>(n + t[1]),
                                   static_cast<std::uint32_t>(n + t[2])));
      }
      for (const auto& [key, c] : face_counts(m)) EXPECT_EQ(c, boundary.count(key) ? 1 : 2);
      std::map<std::pair<std::uint32_t, int>, int> per_layer;
      for (std::size_t t = 0; t < m.tets.size(); ++t)
        ++per_layer[{m.source_triangle[t], m.layer[t]}];
      EXPECT_EQ(per_layer.size(), K * s.num_faces());
      for (const auto& [key, c] : per_layer) EXPECT_EQ(c, 3);
      // Tets of layer k lie between layer boundaries k - 1 and k: every corner of vertex v at
      // fraction at[k - 1] or at[k] of v's edge. Every layer cuts a side quad from the same
      // vertex, the one at boundary k - 1 (a twisted quad then bends alike in every layer).
      const auto level = [&](std::uint32_t p) {
        const std::uint32_t v = m.surface_vertex[p];
        const double f =
            distance(m.points[p], s.points[v]) / distance(in.inner_points[v], s.points[v]);
        for (int k = 0; k <= K; ++k)
          if (std::abs(f - at[k]) < 1e-9) return k;
        return -1;
      };
      std::map<std::array<std::uint32_t, 3>, std::set<std::uint32_t>> cut_from;  // face, side
      for (std::size_t t = 0; t < m.tets.size(); ++t) {
        const int k = m.layer[t];
        for (const std::uint32_t p : m.tets[t]) {
          EXPECT_TRUE(level(p) == k - 1 || level(p) == k) << "tet " << t << " layer " << k;
          for (const std::uint32_t q : m.tets[t]) {
            const std::uint32_t u = m.surface_vertex[p], w = m.surface_vertex[q];
            if (u != w && level(p) == k - 1 && level(q) == k)
              cut_from[{m.source_triangle[t], std::min(u, w), std::max(u, w)}].insert(u);
          }
        }
      }
      EXPECT_EQ(cut_from.size(), 3 * s.num_faces());
      for (const auto& [side, from] : cut_from)
        EXPECT_EQ(from.size(), 1u) << "face " << side[0] << ", side " << side[1] << "-" << side[2];
      ShellCheckOptions layered;
      layered.layers = K;
      const ShellCheckResult c = check_shell(s, m, layered);
      EXPECT_TRUE(c.valid()) << describe_problems(c);
      EXPECT_TRUE(check_shell(s, m).too_many_tets);  // more than 3F for a one-layer check
      // The layers fill the same volume as one layer would (the side quads are planar here).
      EXPECT_NEAR(summarize_quality(s, m).coverage,
                  summarize_quality(s, assemble_shell(s, in).mesh).coverage, 1e-12);
    }
}

TEST(Assemble, LayersKeepSurfaceVerticesAndWeldsAsOneLayerDoes) {
  // Octahedron vertex 0 on the surface, vertices 1 and 3 welded: their prisms lose the tets
  // with a repeated point in every layer (on the surface) or in the innermost one (welded).
  const SurfaceMesh s = octahedron();
  ShellInput in = scaled_input(s, 0.5);
  in.inner_id[0] = kOnSurface;
  in.inner_id[3] = in.inner_id[1];
  in.inner_points[1] = {-0.3, -0.3, 0.05};
  ASSERT_TRUE(check_shell(s, assemble_shell(s, in).mesh).valid());  // as one layer
  AssembleOptions o;
  o.layers = 3;
  const AssembleResult r = assemble_shell(s, in, o);
  for (const Tet& t : r.mesh.tets) EXPECT_GT(volume(r.mesh, t), 0.0);
  ShellCheckOptions layered;
  layered.layers = 3;
  const ShellCheckResult c = check_shell(s, r.mesh, layered);
  EXPECT_TRUE(c.valid()) << describe_problems(c);
  // 5 vertices off the surface, 2 layer points each; no layer point for vertex 0.
  EXPECT_EQ(r.mesh.points.size(), 6u + 6u + 5u * 2u);
  for (std::size_t p = 12; p < r.mesh.points.size(); ++p) EXPECT_NE(r.mesh.surface_vertex[p], 0u);
  EXPECT_EQ(r.on_surface_vertices, 1u);
}

TEST(Assemble, SplitOrderCutsAsTheRelabelledSurfaceDoes) {
  // ShellInput::split_order: the global-index rule follows a given order of the surface vertices
  // instead of their indices. The shell must be, tet for tet and corner for corner, the shell of
  // the surface relabelled in that order (inner points numbered in it, as the search does).
  const SurfaceMesh s = make_shape("sphere", 1);
  const auto n = static_cast<std::uint32_t>(s.points.size());
  std::vector<std::uint32_t> order(n);
  for (std::uint32_t v = 0; v < n; ++v) order[v] = (v * 7 + 3) % n;  // n is not a multiple of 7
  ASSERT_NE(n % 7, 0u);
  const Vec3d c = centroid(s);
  ShellInput in;  // inner point of v: slot order[v]
  in.inner_points.resize(n);
  in.inner_id.resize(n);
  for (std::uint32_t v = 0; v < n; ++v) {
    in.inner_id[v] = order[v];
    in.inner_points[order[v]] = c + (s.points[v] - c) * 0.6;
  }
  in.split_order = order;
  SurfaceMesh relabelled;
  relabelled.points.resize(n);
  for (std::uint32_t v = 0; v < n; ++v) relabelled.points[order[v]] = s.points[v];
  for (const Triangle& t : s.triangles)
    relabelled.triangles.push_back({order[t[0]], order[t[1]], order[t[2]]});
  ShellInput relabelled_in = in;
  relabelled_in.split_order.clear();
  for (std::uint32_t v = 0; v < n; ++v) relabelled_in.inner_id[order[v]] = order[v];
  for (const int layers : {1, 3}) {
    AssembleOptions o;
    o.layers = layers;
    const AssembleResult a = assemble_shell(s, in, o);
    const AssembleResult b = assemble_shell(relabelled, relabelled_in, o);
    ASSERT_EQ(a.mesh.tets.size(), b.mesh.tets.size());
    for (std::size_t t = 0; t < a.mesh.tets.size(); ++t)
      for (int k = 0; k < 4; ++k)
        ASSERT_EQ(a.mesh.points[a.mesh.tets[t][k]], b.mesh.points[b.mesh.tets[t][k]])
            << "tet " << t << " corner " << k << ", " << layers << " layers";
    expect_conforming_shell(s, in, assemble_shell(s, in));
    // Not the index order's shell: the order is used.
    ShellInput index_order = in;
    index_order.split_order.clear();
    EXPECT_NE(assemble_shell(s, index_order, o).mesh.tets, a.mesh.tets);
  }
  in.split_order[5] = in.split_order[6];  // not a permutation
  EXPECT_THROW(assemble_shell(s, in), InputError);
  in.split_order.pop_back();
  EXPECT_THROW(assemble_shell(s, in), InputError);
}

TEST(Assemble, RejectsInconsistentInput) {
  const SurfaceMesh s = octahedron();
  ShellInput in = scaled_input(s, 0.5);
  in.inner_id.pop_back();
  EXPECT_THROW(assemble_shell(s, in), InputError);
  in = scaled_input(s, 0.5);
  in.inner_id[2] = 6;
  EXPECT_THROW(assemble_shell(s, in), InputError);
  in = scaled_input(s, 0.5);
  AssembleOptions o;
  for (const int layers : {0, kMaxLayers + 1}) {
    o.layers = layers;
    EXPECT_THROW(assemble_shell(s, in, o), InputError) << layers;
  }
  o.layers = 2;
  o.layer_ratio = 0;
  EXPECT_THROW(assemble_shell(s, in, o), InputError);
}

}  // namespace
}  // namespace vdb_shell
