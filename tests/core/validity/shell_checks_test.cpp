// shell_checks_test.cpp — check_shell() on valid shells (nothing reported) and on shells broken
// one way at a time (each problem caught and located); the point-in-surface and tet-overlap
// predicates on touching and degenerate configurations; determinism across thread counts.
#include <gtest/gtest.h>

#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <random>
#include <string>
#include <utility>

#include "assets/shapes.h"
#include "core/assemble/assemble.h"
#include "core/base/errors.h"
#include "core/validity/check_steps.h"
#include "core/validity/shell_checks.h"
#include "core/validity/tet_predicates.h"

namespace vdb_shell {
namespace {

/// The shell between `s` and the inner vertices inner(p) of its points p.
template <class Inner>
TetMesh mapped_shell(const SurfaceMesh& s, const Inner& inner) {
  ShellInput in;
  for (std::size_t v = 0; v < s.points.size(); ++v) {
    in.inner_points.push_back(inner(s.points[v]));
    in.inner_id.push_back(static_cast<std::uint32_t>(v));
  }
  return assemble_shell(s, in).mesh;
}

/// The shell between `s` and its copy scaled by `factor` about the origin (the shapes' centre).
TetMesh scaled_shell(const SurfaceMesh& s, double factor) {
  return mapped_shell(s, [factor](const Vec3d& p) { return p * factor; });
}

/// The torus's shell: every point moved halfway towards the tube's core circle.
TetMesh torus_shell(const SurfaceMesh& s) {
  return mapped_shell(s, [](const Vec3d& p) {
    const Vec3d core = normalized(Vec3d{p.x, p.y, 0.0}) * 0.35;
    return core + (p - core) * 0.5;
  });
}

void expect_nothing_reported(const ShellCheckResult& r) {
  EXPECT_EQ(r.inverted_tets, 0u);
  EXPECT_EQ(r.zero_volume_tets, 0u);
  EXPECT_EQ(r.outside_inner_vertices, 0u);
  EXPECT_EQ(r.moved_surface_points, 0u);
  EXPECT_EQ(r.missing_triangles, 0u);
  EXPECT_EQ(r.shared_triangles, 0u);
  EXPECT_EQ(r.misoriented_triangles, 0u);
  EXPECT_EQ(r.nonmanifold_faces, 0u);
  EXPECT_EQ(r.overlapping_pairs, 0u);
  EXPECT_EQ(r.leaking_tets, 0u);
  EXPECT_FALSE(r.too_many_tets);
  EXPECT_TRUE(r.valid());
  EXPECT_EQ(describe_problems(r), "");
}

/// A mesh of the given tets over the given points, checked for overlaps only.
std::size_t overlapping_pairs(const std::vector<Vec3d>& points, const std::vector<Tet>& tets) {
  TetMesh m;
  m.points = points;
  m.tets = tets;
  m.inner.assign(points.size(), 0);
  return check_shell(SurfaceMesh{}, m).overlapping_pairs;
}

const Vec3d kA{0, 0, 0}, kB{1, 0, 0}, kC{0, 1, 0}, kD{0, 0, 1};

TEST(ShellChecks, SelfIntersectionsOfTheSurface) {
  // Every generated shape is embedded: nothing, although neighbours share edges and vertices.
  for (const ShapeInfo& info : shape_catalog())
    EXPECT_TRUE(surface_self_intersections(make_shape(info.name, 1), 10).empty()) << info.name;
  // Two boxes, the second shifted by half a side, as one mesh: their faces cross.
  SurfaceMesh two = make_shape("box", 1);
  const SurfaceMesh box = two;
  const auto n = static_cast<std::uint32_t>(two.points.size());
  for (const Vec3d& p : box.points) two.points.push_back(p + Vec3d{0.3, 0.2, 0.1});
  for (const Triangle& t : box.triangles) two.triangles.push_back({t[0] + n, t[1] + n, t[2] + n});
  const auto pairs = surface_self_intersections(two, 1000);
  ASSERT_FALSE(pairs.empty());
  for (const auto& pair : pairs) {
    EXPECT_LT(pair[0], box.triangles.size());  // one face of each box
    EXPECT_GE(pair[1], box.triangles.size());
  }
  EXPECT_EQ(surface_self_intersections(two, 1).size(), 1u);
  // Merely touching (the second box moved a whole side along x, sharing a face plane) is not
  // crossing.
  const double side = bounding_box(box).extent().x;
  for (std::size_t i = 0; i < box.points.size(); ++i)
    two.points[n + i] = box.points[i] + Vec3d{side, 0, 0};
  EXPECT_TRUE(surface_self_intersections(two, 10).empty());
}

TEST(ShellChecks, ASurfaceTouchingItselfFromInsideIsFoundWhereItTouches) {
  // The box (outward) with a small tet added: the tet's apex, or an edge of it, on a face of the
  // box's top, inside its edges. Hanging below the top (a cavity touching it from inside: the
  // wall has no thickness there) it touches from inside; standing on the top (a part touching
  // the box from outside) it does not, nor does it a hair below the face, or where the apex sits
  // on an edge of the top's triangles (a T-junction, within the margin).
  const SurfaceMesh box = make_shape("box", 1);
  const BBox bounds = bounding_box(box);
  const double side = bounds.extent().x, h = 0.05 * side, margin = 1e-4 * side;
  std::array<Vec3d, 3> face{};
  for (std::size_t f = 0; f < box.triangles.size(); ++f) {
    face = triangle_corners(box, f);
    if (face[0].z == bounds.hi.z && face[1].z == bounds.hi.z && face[2].z == bounds.hi.z) break;
  }
  ASSERT_EQ(face[0].z, bounds.hi.z);
  const Vec3d on_top = (face[0] + face[1] + face[2]) / 3.0;
  // The midpoint of the face's edge farthest in from the top's rim (an edge of two top faces).
  Vec3d on_edge;
  double inset = -1;
  for (int k = 0; k < 3; ++k) {
    const Vec3d m = (face[k] + face[(k + 1) % 3]) * 0.5;
    const double in =
        std::min({m.x - bounds.lo.x, bounds.hi.x - m.x, m.y - bounds.lo.y, bounds.hi.y - m.y});
    if (in > inset) inset = in, on_edge = m;
  }
  ASSERT_GT(inset, 2 * h);
  const auto with_tet = [&](const std::array<Vec3d, 4>& corners) {
    SurfaceMesh m = box;
    const auto n = static_cast<std::uint32_t>(m.points.size());
    for (const Vec3d& p : corners) m.points.push_back(p);
    for (const Triangle& t : std::vector<Triangle>{{0, 1, 2}, {0, 3, 1}, {1, 3, 2}, {2, 3, 0}})
      m.triangles.push_back({t[0] + n, t[1] + n, t[2] + n});
    return m;
  };
  const auto apex_tet = [&](const Vec3d& apex, double down) {
    return with_tet(
        {apex, apex + Vec3d{h, 0, -down}, apex + Vec3d{0, h, -down}, apex + Vec3d{-h, -h, -down}});
  };
  const std::size_t box_faces = box.triangles.size();
  const auto touching = [&](const SurfaceMesh& m) {
    const auto pairs = surface_inside_contacts(m, margin, 100);
    for (const auto& [f, g] : pairs) {
      EXPECT_LT(f, box_faces);  // a face of the top and one of the tet
      EXPECT_GE(g, box_faces);
    }
    return pairs.size();
  };
  // The apex hanging from the top: the three faces at the apex touch the face it lies on, there.
  const SurfaceMesh hanging = apex_tet(on_top, h);
  EXPECT_EQ(touching(hanging), 3u);
  for (const auto& [f, g] : surface_inside_contacts(hanging, margin, 100)) {
    const auto at = surface_triangles_touch_inside(hanging, f, g, margin);
    ASSERT_TRUE(at.has_value());
    EXPECT_LT(distance(*at, on_top), 1e-12 * side);
  }
  EXPECT_EQ(touching(apex_tet(on_top, -h)), 0u);                            // standing on it
  EXPECT_EQ(touching(apex_tet(on_top - Vec3d{0, 0, 1e-6 * side}, h)), 0u);  // a wall 1e-6 thick
  EXPECT_EQ(touching(apex_tet(on_edge, h)), 0u);
  // An edge of the tet along the top, the other two corners below (a notch cut up to the
  // face): the faces on that edge touch; the same edge with the tet above does not.
  const Vec3d along = normalized(face[1] - face[0]) * h;
  const auto edge_tet = [&](double down) {
    const Vec3d across = normalized(cross(Vec3d{0, 0, 1}, along)) * h;
    return with_tet({on_top - along, on_top + along, on_top + across + Vec3d{0, 0, -down},
                     on_top - across + Vec3d{0, 0, -down}});
  };
  EXPECT_EQ(touching(edge_tet(h)), 4u);  // every face has a corner on the edge, one below
  EXPECT_EQ(touching(edge_tet(-h)), 0u);
}

TEST(ShellChecks, AFaceFoldedOntoItsNeighbourCrossesIt) {
  // Two faces of the edge (0, 0, 0)-(1, 0, 0), oriented alike; the second's third corner on the
  // first's side of the edge, in its plane: a sliver turned over (as rounding leaves CAD
  // exports), whose interior lies on its neighbour's. Across the edge (flat) or 0.6 degrees out
  // of the plane (a razor-thin wedge) they only touch.
  const auto two_faces = [](const Vec3d& q) {
    SurfaceMesh m;
    m.points = {{0, 0, 0}, {1, 0, 0}, {0.5, 1, 0}, q};
    m.triangles = {{0, 1, 2}, {1, 0, 3}};
    return m;
  };
  const SurfaceMesh folded = two_faces({0.3, 1e-4, 0});
  EXPECT_EQ(surface_self_intersections(folded, 10).size(), 1u);
  // Named at the folded corner, not at a shared one.
  EXPECT_EQ(distance(triangles_crossing_point(folded, 0, 1), folded.points[3]), 0.0);
  EXPECT_TRUE(surface_self_intersections(two_faces({0.3, -0.5, 0}), 10).empty());
  EXPECT_TRUE(surface_self_intersections(two_faces({0.3, 0.5, 0.005}), 10).empty());
}

TEST(ShellChecks, ValidShellsReportNothing) {
  for (const auto& [name, detail] :
       {std::pair<const char*, int>{"box", 2}, {"sphere", 2}, {"cylinder", 1}, {"torus", 1}}) {
    SCOPED_TRACE(name);
    const SurfaceMesh s = make_shape(name, detail);
    // The torus is not star-shaped about its centre: shrink its tube instead.
    const TetMesh m = std::string(name) == "torus" ? torus_shell(s) : scaled_shell(s, 0.5);
    const ShellCheckResult r = check_shell(s, m);
    expect_nothing_reported(r);
    EXPECT_TRUE(r.overlaps_checked);
    EXPECT_GT(r.overlap_candidate_pairs, m.tets.size());
    EXPECT_EQ(r.checked_inner_vertices, s.points.size());
    EXPECT_EQ(r.tets, 3 * s.num_faces());
  }
}

TEST(ShellChecks, SwappedTetIsInverted) {
  const SurfaceMesh s = make_shape("box", 1);
  TetMesh m = scaled_shell(s, 0.5);
  std::swap(m.tets[7][2], m.tets[7][3]);
  const ShellCheckResult r = check_shell(s, m);
  EXPECT_EQ(r.inverted_tets, 1u);
  EXPECT_EQ(r.first_inverted_tets, std::vector<std::uint32_t>{7});
  EXPECT_EQ(r.zero_volume_tets, 0u);
  EXPECT_EQ(r.overlapping_pairs, 0u);  // the same point set: still no overlap
  EXPECT_FALSE(r.valid());
  EXPECT_NE(describe_problems(r).find("1 inverted tets (first: 7)"), std::string::npos);
}

TEST(ShellChecks, HandMadeInvertedAndFlatTets) {
  TetMesh m;
  m.points = {kA, kB, kC, kD, {1, 1, 0}};
  m.tets = {{0, 1, 2, 3}, {0, 2, 1, 3}, {0, 1, 2, 4}, {0, 1, 1, 3}};
  m.inner.assign(m.points.size(), 0);
  ShellCheckOptions options;
  options.check_overlaps = false;
  const ShellCheckResult r = check_shell(SurfaceMesh{}, m, options);
  EXPECT_EQ(r.inverted_tets, 1u);
  EXPECT_EQ(r.first_inverted_tets, std::vector<std::uint32_t>{1});
  EXPECT_EQ(r.zero_volume_tets, 2u);
  EXPECT_EQ(r.first_zero_volume_tets, (std::vector<std::uint32_t>{2, 3}));
  EXPECT_FALSE(r.overlaps_checked);
}

TEST(ShellChecks, InnerVertexPushedOutsideIsCaught) {
  const SurfaceMesh s = make_shape("box", 1);
  TetMesh m = scaled_shell(s, 0.5);
  const std::size_t n = s.points.size();
  // Surface vertex 0's inner vertex, pushed far beyond its corner.
  m.points[n] = s.points[0] * 1.6;
  const ShellCheckResult r = check_shell(s, m);
  EXPECT_EQ(r.outside_inner_vertices, 1u);
  EXPECT_EQ(r.first_outside_vertices, std::vector<std::uint32_t>{static_cast<std::uint32_t>(n)});
  EXPECT_GT(r.inverted_tets, 0u);
  EXPECT_FALSE(r.valid());
}

TEST(ShellChecks, InnerVertexOnTheSurfaceIsNotOutside) {
  const SurfaceMesh s = make_shape("box", 1);
  TetMesh m = scaled_shell(s, 0.5);
  const std::size_t n = s.points.size();
  m.points[n] = s.points[0];  // zero thickness at vertex 0
  const ShellCheckResult r = check_shell(s, m);
  EXPECT_EQ(r.outside_inner_vertices, 0u);
  EXPECT_GT(r.zero_volume_tets, 0u);
}

TEST(ShellChecks, PointInBoxOnFacesEdgesAndCorners) {
  // The box's vertices lie on a grid of step 0.5: axis rays through grid points hit vertices
  // and edges, which forces the ambiguous paths.
  const SurfaceMesh s = make_shape("box", 1);
  const double tol = 1e-9;
  for (double x : {-0.5, -0.25, 0.0, 0.25, 0.5})
    for (double y : {-0.5, -0.25, 0.0, 0.25, 0.5})
      for (double z : {-0.5, -0.25, 0.0, 0.25, 0.5}) {
        EXPECT_FALSE(point_outside_surface(s, {x, y, z}, tol)) << x << " " << y << " " << z;
        const Vec3d out{x >= 0.0 ? 0.5 + 1e-6 : -0.5 - 1e-6, y, z};
        EXPECT_TRUE(point_outside_surface(s, out, tol)) << out.x << " " << y << " " << z;
      }
  EXPECT_TRUE(point_outside_surface(s, {3, 0, 0}, tol));
  EXPECT_TRUE(point_outside_surface(s, {0.5 + 1e-7, 0.5, 0.5}, tol));
  EXPECT_FALSE(point_outside_surface(s, {0.5 - 1e-7, 0.5 - 1e-7, 0.5 - 1e-7}, tol));
}

TEST(ShellChecks, PointInSphereAgreesWithRadius) {
  const SurfaceMesh s = make_shape("sphere", 2);  // inscribed in radius 0.5
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-0.7, 0.7);
  int tested = 0;
  for (int i = 0; i < 800; ++i) {
    const Vec3d p{u(rng), u(rng), u(rng)};
    const double r = norm(p);
    if (r > 0.49 && r <= 0.5) continue;  // between the facets and the sphere
    ++tested;
    EXPECT_EQ(point_outside_surface(s, p, 1e-9), r > 0.5) << r;
  }
  EXPECT_GT(tested, 600);
  // Exactly on the axis, through the poles (vertices of many triangles).
  EXPECT_FALSE(point_outside_surface(s, {0, 0, 0.2}, 1e-9));
  EXPECT_TRUE(point_outside_surface(s, {0, 0, 0.6}, 1e-9));
}

TEST(ShellChecks, InsideIsByParityAlsoInsideTwoComponentsFacingTheSameWay) {
  // A box in a box, both facing out, as the loader meets them before it orients them: a point in
  // the inner one is outside by parity (two crossings on every ray; winding number 2), in
  // between inside. Points on the boxes' lattice lines have their rays along edges.
  const SurfaceMesh outer = make_shape("box", 5);
  SurfaceMesh s = outer;
  const std::uint32_t n = static_cast<std::uint32_t>(outer.points.size());
  for (const Vec3d& p : outer.points) s.points.push_back(p * 0.5);
  for (const Triangle& t : outer.triangles) s.triangles.push_back({t[0] + n, t[1] + n, t[2] + n});
  for (const double x : {-0.2, 0.0, 0.2})
    for (const double y : {-0.2, 0.0, 0.2})
      for (const double z : {-0.2, 0.0, 0.2}) {
        EXPECT_TRUE(point_outside_surface(s, {x, y, z}, 1e-9)) << x << " " << y << " " << z;
        EXPECT_FALSE(point_outside_surface(s, {2 * x + 0.05, 2 * y + 0.05, 0.4}, 1e-9))
            << x << " " << y;
      }
}

TEST(ShellChecks, PointsInLineWithEdgesOnEveryAxisAreJudgedFromPointsNearThem) {
  // The box at detail 5 has its vertices on a lattice of step 0.1. A point on lattice lines in
  // two coordinates and 0.004 from a face in the third has every axis ray running along edges,
  // so its verdict comes from rays cast from points within its clearance (0.004): the points
  // just inside each face must stay inside (a shift past the clearance would carry some out),
  // those just outside must stay outside.
  const SurfaceMesh s = make_shape("box", 5);
  ASSERT_EQ(s.triangles.size(), 1200u);
  int tested = 0;
  for (int axis = 0; axis < 3; ++axis)
    for (const double side : {-1.0, 1.0})
      for (int i = -4; i <= 4; i += 2)
        for (int j = -4; j <= 4; j += 2)
          for (const double delta : {-0.004, 0.004}) {  // inside, outside
            Vec3d p;
            p[(axis + 1) % 3] = 0.1 * i;
            p[(axis + 2) % 3] = 0.1 * j;
            p[axis] = side * (0.5 + delta);
            EXPECT_EQ(point_outside_surface(s, p, 1e-9), delta > 0.0)
                << p.x << " " << p.y << " " << p.z;
            ++tested;
          }
  EXPECT_EQ(tested, 300);
}

TEST(ShellChecks, MissingSharedAndMisorientedTriangles) {
  const SurfaceMesh s = make_shape("box", 1);
  const TetMesh valid = scaled_shell(s, 0.5);
  // The tet holding input triangle 3 (one of triangle 3's three tets).
  auto holder = [&](std::size_t f) {
    const Triangle& t = s.triangles[f];
    for (std::size_t i = 3 * f; i < 3 * f + 3; ++i) {
      const Tet& q = valid.tets[i];
      if (std::count(q.begin(), q.end(), t[0]) && std::count(q.begin(), q.end(), t[1]) &&
          std::count(q.begin(), q.end(), t[2]))
        return i;
    }
    return std::size_t{0};
  };
  {
    TetMesh m = valid;
    m.tets.erase(m.tets.begin() + static_cast<std::ptrdiff_t>(holder(3)));
    const ShellCheckResult r = check_shell(s, m);
    EXPECT_EQ(r.missing_triangles, 1u);
    EXPECT_EQ(r.first_missing_triangles, std::vector<std::uint32_t>{3});
  }
  {
    TetMesh m = valid;
    m.tets.push_back(m.tets[holder(5)]);
    const ShellCheckResult r = check_shell(s, m);
    EXPECT_EQ(r.shared_triangles, 1u);
    EXPECT_EQ(r.first_shared_triangles, std::vector<std::uint32_t>{5});
    EXPECT_GT(r.nonmanifold_faces, 0u);
    EXPECT_EQ(r.overlapping_pairs, 1u);
    ASSERT_EQ(r.first_overlapping_pairs.size(), 1u);
    EXPECT_EQ(r.first_overlapping_pairs[0][1], m.tets.size() - 1);
  }
  {
    // Tets repeated once and twice: each vertex triple held by three or more tets counts once,
    // against a count of every tet's faces by triple.
    TetMesh m = valid;
    for (const std::size_t f : {1, 5, 5, 7, 7, 7}) m.tets.push_back(m.tets[holder(f)]);
    std::map<std::array<std::uint32_t, 3>, int> holders;
    for (const Tet& t : m.tets)
      for (int k = 0; k < 4; ++k) {
        std::array<std::uint32_t, 3> key = {t[(k + 1) % 4], t[(k + 2) % 4], t[(k + 3) % 4]};
        std::sort(key.begin(), key.end());
        ++holders[key];
      }
    const auto nonmanifold = static_cast<std::size_t>(
        std::count_if(holders.begin(), holders.end(), [](const auto& h) { return h.second > 2; }));
    ASSERT_GE(nonmanifold, 6u);
    EXPECT_EQ(check_shell(s, m).nonmanifold_faces, nonmanifold);
  }
  {
    TetMesh m = valid;
    Tet& t = m.tets[holder(2)];
    std::swap(t[0], t[1]);
    const ShellCheckResult r = check_shell(s, m);
    EXPECT_EQ(r.misoriented_triangles, 1u);
    EXPECT_EQ(r.first_misoriented_triangles, std::vector<std::uint32_t>{2});
    EXPECT_EQ(r.inverted_tets, 1u);
  }
  {
    TetMesh m = valid;
    m.points[4].x += 1e-3;
    const ShellCheckResult r = check_shell(s, m);
    EXPECT_EQ(r.moved_surface_points, 1u);
    EXPECT_EQ(r.first_moved_surface_points, std::vector<std::uint32_t>{4});
  }
}

TEST(ShellChecks, OverlappingPairIsCaught) {
  std::vector<Vec3d> p = {kA, kB, kC, kD};
  for (const Vec3d& x : {kA, kB, kC, kD}) p.push_back(x + Vec3d{0.2, 0.2, 0.2});
  TetMesh m;
  m.points = p;
  m.tets = {{0, 1, 2, 3}, {4, 5, 6, 7}};
  const ShellCheckResult r = check_shell(SurfaceMesh{}, m);
  EXPECT_EQ(r.overlapping_pairs, 1u);
  ASSERT_EQ(r.first_overlapping_pairs.size(), 1u);
  EXPECT_EQ(r.first_overlapping_pairs[0], (std::array<std::uint32_t, 2>{0, 1}));
  EXPECT_NE(describe_problems(r).find("1 overlapping tet pairs (first: (0, 1))"),
            std::string::npos);
}

TEST(ShellChecks, TouchingTetsDoNotOverlap) {
  const Vec3d e{1, 1, 1};  // beyond face (B, C, D) of the corner tet
  // Sharing a face, on opposite sides.
  EXPECT_EQ(overlapping_pairs({kA, kB, kC, kD, e}, {{0, 1, 2, 3}, {4, 1, 3, 2}}), 0u);
  // Sharing a face, folded onto the same side.
  EXPECT_EQ(overlapping_pairs({kA, kB, kC, kD, {0.1, 0.1, 0.1}}, {{0, 1, 2, 3}, {4, 1, 2, 3}}), 1u);
  // Sharing an edge (B, C), apart.
  EXPECT_EQ(overlapping_pairs({kA, kB, kC, kD, e, {1, 1, -1}}, {{0, 1, 2, 3}, {1, 2, 4, 5}}), 0u);
  // Sharing a vertex (B), apart, and sharing it while poking into the other.
  EXPECT_EQ(overlapping_pairs({kA, kB, kC, kD, {2, 0, 0}, {2, 1, 0}, {2, 0, 1}},
                              {{0, 1, 2, 3}, {1, 4, 5, 6}}),
            0u);
  EXPECT_EQ(overlapping_pairs({kA, kB, kC, kD, {0.1, 0.1, 0.1}, {2, 1, 0}, {2, 0, 1}},
                              {{0, 1, 2, 3}, {1, 4, 5, 6}}),
            1u);
  // Face against face without shared vertices (a smaller tet on face (A, B, C), below it).
  EXPECT_EQ(overlapping_pairs(
                {kA, kB, kC, kD, {0.1, 0.1, 0}, {0.5, 0.1, 0}, {0.1, 0.5, 0}, {0.2, 0.2, -1}},
                {{0, 1, 2, 3}, {4, 6, 5, 7}}),
            0u);
  // The same, lifted a little into the first tet.
  EXPECT_EQ(
      overlapping_pairs(
          {kA, kB, kC, kD, {0.1, 0.1, 1e-3}, {0.5, 0.1, 1e-3}, {0.1, 0.5, 1e-3}, {0.2, 0.2, -1}},
          {{0, 1, 2, 3}, {4, 6, 5, 7}}),
      1u);
  // Far apart: never a candidate.
  EXPECT_EQ(overlapping_pairs({kA, kB, kC, kD, {5, 5, 5}, {6, 5, 5}, {5, 6, 5}, {5, 5, 6}},
                              {{0, 1, 2, 3}, {4, 5, 6, 7}}),
            0u);
}

TEST(ShellChecks, TouchingAndOverlappingFarFromTheOrigin) {
  // The same small configurations shifted far away (georeferenced scans, CAD parts in site
  // coordinates): coordinates ~1e6 round at ~1e-10, more than the tolerance of 1e-9 of a
  // 1e-2 edge, so the tests must not project world coordinates. Every corner is exactly
  // representable after the shift (multiples of 2^-10).
  const double h = 1.0 / 128;  // edge length
  for (const Vec3d shift : {Vec3d{0, 0, 0}, Vec3d{1e6, -2e6, 3e5}, Vec3d{-7.5e7, 4e7, 1e7}}) {
    SCOPED_TRACE(shift.x);
    const auto at = [&](double x, double y, double z) { return shift + Vec3d{x, y, z} * h; };
    const Vec3d a = at(0, 0, 0), b = at(1, 0, 0), c = at(0, 1, 0), d = at(0, 0, 1);
    const Vec3d e = at(1, 1, 1);
    // Sharing a face on opposite sides; sharing an edge; sharing a vertex: apart.
    EXPECT_EQ(overlapping_pairs({a, b, c, d, e}, {{0, 1, 2, 3}, {4, 1, 3, 2}}), 0u);
    EXPECT_EQ(overlapping_pairs({a, b, c, d, e, at(1, 1, -1)}, {{0, 1, 2, 3}, {1, 2, 4, 5}}), 0u);
    EXPECT_EQ(overlapping_pairs({a, b, c, d, at(2, 0, 0), at(2, 1, 0), at(2, 0, 1)},
                                {{0, 1, 2, 3}, {1, 4, 5, 6}}),
              0u);
    // Folded onto the same side, by a fraction of the edge: overlapping.
    EXPECT_EQ(overlapping_pairs({a, b, c, d, at(0.1, 0.1, 0.1)}, {{0, 1, 2, 3}, {4, 1, 2, 3}}), 1u);
    // Triangles sharing an edge or a vertex do not cross; one through the other does.
    const double tol = 1e-9 * h;
    EXPECT_FALSE(triangles_cross({a, b, c}, {b, a, d}, tol));
    EXPECT_FALSE(triangles_cross({a, b, c}, {a, d, at(-1, 0, 1)}, tol));
    EXPECT_TRUE(
        triangles_cross({a, b, c}, {at(0.2, 0.2, -0.5), at(0.2, 0.2, 0.5), at(2, 2, 0)}, tol));
  }
}

TEST(ShellChecks, TetAcrossTheTorusHoleLeaks) {
  // Every vertex inside the torus's tube (core radius 0.35, tube radius 0.15), the tet across
  // the hole: the first has its centroid in the hole, the second only crosses the surface.
  const SurfaceMesh s = make_shape("torus", 1);
  for (const bool centroid_inside : {false, true}) {
    SCOPED_TRACE(centroid_inside);
    TetMesh m;
    m.points = s.points;
    const double x = centroid_inside ? 0.45 : 0.35;
    m.points.insert(m.points.end(),
                    {{x, 0, 0.05}, {x, 0.05, -0.05}, {x, -0.05, -0.05}, {-0.35, 0, 0}});
    const auto n = static_cast<std::uint32_t>(s.points.size());
    m.tets = {{n, n + 1, n + 2, n + 3}};
    if (tet_volume(m.points[n], m.points[n + 1], m.points[n + 2], m.points[n + 3]) < 0)
      std::swap(m.tets[0][2], m.tets[0][3]);
    const ShellCheckResult r = check_shell(s, m);
    EXPECT_EQ(r.outside_inner_vertices, 0u);
    EXPECT_EQ(r.inverted_tets, 0u);
    EXPECT_TRUE(r.leaks_checked);
    EXPECT_EQ(r.leaking_tets, 1u);
    EXPECT_EQ(r.first_leaking_tets, std::vector<std::uint32_t>{0});
    EXPECT_NE(describe_problems(r).find("1 tets reaching outside the surface"), std::string::npos);
  }
}

TEST(ShellChecks, ThrowsOnBadIndices) {
  TetMesh m;
  m.points = {kA, kB, kC};
  m.tets = {{0, 1, 2, 3}};
  EXPECT_THROW(check_shell(SurfaceMesh{}, m), InputError);
  m.points.push_back(kD);
  m.inner = {0, 1};
  EXPECT_THROW(check_shell(SurfaceMesh{}, m), InputError);
}

TEST(ShellChecks, TooManyTets) {
  const SurfaceMesh s = make_shape("box", 1);
  TetMesh m = scaled_shell(s, 0.5);
  ShellCheckOptions options;
  options.check_overlaps = false;
  EXPECT_FALSE(check_shell(s, m, options).too_many_tets);
  m.tets.push_back(m.tets[0]);
  EXPECT_TRUE(check_shell(s, m, options).too_many_tets);
}

/// The sphere shell scaled by 0.5, broken in several places: shuffled inner vertices invert and
/// overlap prisms.
TetMesh broken_sphere_shell(const SurfaceMesh& s) {
  TetMesh m = scaled_shell(s, 0.5);
  const std::size_t n = s.points.size();
  for (std::size_t v = 0; v < n; v += 97) m.points[n + v] = m.points[n + (v * 7 + 13) % n];
  return m;
}

TEST(ShellChecks, SameResultForAnyThreadCount) {
  const SurfaceMesh s = make_shape("sphere", 2);
  const TetMesh m = broken_sphere_shell(s);
  ShellCheckOptions options;
  options.max_listed = std::numeric_limits<std::size_t>::max();
  ShellCheckResult serial;
  {
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    serial = check_shell(s, m, options);
  }
  const ShellCheckResult parallel = check_shell(s, m, options);
  EXPECT_GT(serial.overlapping_pairs, 0u);
  EXPECT_GT(serial.inverted_tets, 0u);
  EXPECT_EQ(serial.overlapping_pairs, parallel.overlapping_pairs);
  EXPECT_EQ(serial.first_overlapping_pairs, parallel.first_overlapping_pairs);
  EXPECT_EQ(serial.first_overlapping_pairs.size(), serial.overlapping_pairs);
  EXPECT_EQ(serial.first_inverted_tets, parallel.first_inverted_tets);
  EXPECT_EQ(serial.first_zero_volume_tets, parallel.first_zero_volume_tets);
  EXPECT_EQ(serial.first_outside_vertices, parallel.first_outside_vertices);
  EXPECT_EQ(serial.overlap_candidate_pairs, parallel.overlap_candidate_pairs);
  EXPECT_EQ(describe_problems(serial), describe_problems(parallel));
}

TEST(ShellChecks, TetOrderChangesNothingAndEveryOverlapIsFound) {
  // The broken sphere shell and the same tets shuffled: the same overlapping pairs (mapped back)
  // and leaks — and the pairs are exactly those of a test of every pair of tets.
  const SurfaceMesh s = make_shape("sphere", 2);
  const TetMesh m = broken_sphere_shell(s);
  const std::size_t n = m.tets.size();
  std::vector<std::uint32_t> order(n);  // shuffled position -> tet of m
  std::iota(order.begin(), order.end(), 0u);
  std::shuffle(order.begin(), order.end(), std::mt19937(11));
  TetMesh shuffled = m;
  for (std::size_t i = 0; i < n; ++i) shuffled.tets[i] = m.tets[order[i]];
  ShellCheckOptions options;
  options.max_listed = std::numeric_limits<std::size_t>::max();
  const ShellCheckResult a = check_shell(s, m, options);
  const ShellCheckResult b = check_shell(s, shuffled, options);
  std::vector<std::array<std::uint32_t, 2>> mapped;
  for (const auto& pair : b.first_overlapping_pairs)
    mapped.push_back(
        {std::min(order[pair[0]], order[pair[1]]), std::max(order[pair[0]], order[pair[1]])});
  std::sort(mapped.begin(), mapped.end());
  EXPECT_EQ(mapped, a.first_overlapping_pairs);
  std::vector<std::uint32_t> leaking;
  for (const std::uint32_t t : b.first_leaking_tets) leaking.push_back(order[t]);
  std::sort(leaking.begin(), leaking.end());
  EXPECT_EQ(leaking, a.first_leaking_tets);

  const auto corners = [&](std::uint32_t t) {
    const Tet& v = m.tets[t];
    return std::array<Vec3d, 4>{m.points[v[0]], m.points[v[1]], m.points[v[2]], m.points[v[3]]};
  };
  std::vector<BBox> box(n);
  for (std::uint32_t t = 0; t < n; ++t)
    for (const Vec3d& p : corners(t)) box[t].expand(p);
  const auto apart = [&](std::uint32_t i, std::uint32_t j) {
    for (int a = 0; a < 3; ++a)
      if (box[i].hi[a] < box[j].lo[a] || box[j].hi[a] < box[i].lo[a]) return true;
    return false;
  };
  std::vector<std::array<std::uint32_t, 2>> every;
  for (std::uint32_t i = 0; i < n; ++i)
    for (std::uint32_t j = i + 1; j < n; ++j)
      if (!apart(i, j) && tets_overlap(corners(i), corners(j), options)) every.push_back({i, j});
  EXPECT_GT(every.size(), 10u);
  EXPECT_EQ(a.first_overlapping_pairs, every);
}

TEST(ShellChecks, PrismGroupsFindWhatSingleTetsFind) {
  // check_shell() enters the tets of one source triangle as one group and skips the pairs of two
  // groups a face normal separates. On a shell with overlapping prisms and leaking ones, near the
  // origin and far from it, that finds the same overlapping pairs and leaking tets as testing
  // every tet on its own (no source triangles), from fewer candidate pairs.
  for (const Vec3d shift : {Vec3d{0, 0, 0}, Vec3d{1e6, -2e6, 3e5}}) {
    SCOPED_TRACE(shift.x);
    SurfaceMesh s = make_shape("sphere", 2);
    TetMesh grouped = broken_sphere_shell(s);
    const std::size_t n = s.points.size();
    for (std::size_t v = 5; v < n; v += 89) grouped.points[n + v] = s.points[v] * 1.05;  // out
    for (Vec3d& p : s.points) p = p + shift;
    for (Vec3d& p : grouped.points) p = p + shift;
    ASSERT_EQ(grouped.source_triangle.size(), grouped.tets.size());
    TetMesh single = grouped;
    single.source_triangle.clear();
    ShellCheckOptions options;
    options.max_listed = std::numeric_limits<std::size_t>::max();
    const ShellCheckResult a = check_shell(s, grouped, options);
    const ShellCheckResult b = check_shell(s, single, options);
    EXPECT_GT(a.overlapping_pairs, 10u);
    EXPECT_GT(a.leaking_tets, 10u);
    EXPECT_EQ(a.first_overlapping_pairs, b.first_overlapping_pairs);
    EXPECT_EQ(a.first_leaking_tets, b.first_leaking_tets);
    EXPECT_LT(a.overlap_candidate_pairs, b.overlap_candidate_pairs);
  }
}

TEST(ShellChecks, AddedTetsAreCheckedAsCheckShellChecksThem) {
  // A valid half-thick sphere shell (hollow inside radius ~0.25) and tets added to it: one in
  // the hollow (apart from everything), two more there crossing each other, one poking into the
  // shell, one reaching out through the surface. check_added_tets() must find what check_shell()
  // finds on the same mesh: the same pairs and leaks, every other count alike.
  const SurfaceMesh s = make_shape("sphere", 2);
  TetMesh m = scaled_shell(s, 0.5);
  const std::size_t shell_tets = m.tets.size();
  ShellCheckOptions options;
  options.max_listed = std::numeric_limits<std::size_t>::max();
  options.extra_tets = 5;
  const auto add = [&](const std::array<Vec3d, 4>& corners) {
    const auto first = static_cast<std::uint32_t>(m.points.size());
    for (const Vec3d& p : corners) {
      m.points.push_back(p);
      m.inner.push_back(1);
    }
    Tet t{first, first + 1, first + 2, first + 3};
    if (tet_volume(corners[0], corners[1], corners[2], corners[3]) < 0) std::swap(t[2], t[3]);
    m.tets.push_back(t);
    m.source_triangle.push_back(0);
  };
  const double r = 0.05;
  add({Vec3d{0, 0, 0}, Vec3d{r, 0, 0}, Vec3d{0, r, 0}, Vec3d{0, 0, r}});  // alone in the hollow
  add({Vec3d{-0.1, -0.1, -0.1}, Vec3d{-0.1 + r, -0.1, -0.1}, Vec3d{-0.1, -0.1 + r, -0.1},
       Vec3d{-0.1, -0.1, -0.1 + r}});
  add({Vec3d{-0.09, -0.09, -0.09}, Vec3d{-0.09 + r, -0.09, -0.09}, Vec3d{-0.09, -0.09 + r, -0.09},
       Vec3d{-0.09, -0.09, -0.09 + r}});  // crosses the last
  add({Vec3d{0.2, 0, 0}, Vec3d{0.35, 0, 0}, Vec3d{0.2, 0.05, 0}, Vec3d{0.2, 0, 0.05}});    // shell
  add({Vec3d{0.45, 0, 0}, Vec3d{0.6, 0, 0}, Vec3d{0.45, 0.05, 0}, Vec3d{0.45, 0, 0.05}});  // out
  std::vector<char> added(m.tets.size(), 0);
  std::fill(added.begin() + static_cast<std::ptrdiff_t>(shell_tets), added.end(), 1);

  const ShellCheckResult full = check_shell(s, m, options);
  const ShellCheckResult part = check_added_tets(s, m, added, options);
  const auto t0 = static_cast<std::uint32_t>(shell_tets);
  ASSERT_EQ(full.first_overlapping_pairs.size(), full.overlapping_pairs);
  EXPECT_NE(std::find(full.first_overlapping_pairs.begin(), full.first_overlapping_pairs.end(),
                      std::array<std::uint32_t, 2>{t0 + 1, t0 + 2}),
            full.first_overlapping_pairs.end());
  EXPECT_GT(full.overlapping_pairs, 1u);  // the pair in the hollow and the tet in the shell
  for (const auto& pair : full.first_overlapping_pairs) EXPECT_TRUE(added[pair[1]]);
  EXPECT_EQ(part.first_overlapping_pairs, full.first_overlapping_pairs);
  EXPECT_EQ(part.overlapping_pairs, full.overlapping_pairs);
  EXPECT_NE(std::find(full.first_leaking_tets.begin(), full.first_leaking_tets.end(), t0 + 4),
            full.first_leaking_tets.end());
  EXPECT_EQ(part.first_leaking_tets, full.first_leaking_tets);
  EXPECT_EQ(part.first_outside_vertices, full.first_outside_vertices);
  EXPECT_GT(part.outside_inner_vertices, 0u);  // the leaking tet's corner at x = 0.6
  EXPECT_EQ(part.inverted_tets, full.inverted_tets);
  EXPECT_EQ(part.zero_volume_tets, full.zero_volume_tets);
  EXPECT_EQ(part.missing_triangles, full.missing_triangles);
  EXPECT_EQ(part.nonmanifold_faces, full.nonmanifold_faces);
  EXPECT_EQ(part.too_many_tets, full.too_many_tets);
  EXPECT_EQ(describe_problems(part), describe_problems(full));
  EXPECT_LT(part.overlap_candidate_pairs, full.overlap_candidate_pairs);

  // Without the offenders (and their points): valid both ways.
  m.points.resize(m.points.size() - 16);
  m.inner.resize(m.points.size());
  m.tets.resize(shell_tets + 1);
  m.source_triangle.resize(shell_tets + 1);
  added.resize(shell_tets + 1);
  expect_nothing_reported(check_shell(s, m, options));
  expect_nothing_reported(check_added_tets(s, m, added, options));
  added.pop_back();
  EXPECT_THROW(check_added_tets(s, m, added, options), InputError);
}

TEST(ShellChecks, FortyThousandTetShellsReportNothing) {
  // Sphere at detail 4: 12,640 triangles, 37,920 tets, thick (inner = 0.5 x outer) and thin
  // (0.9 x: long, flat tets whose neighbours' boxes overlap).
  const SurfaceMesh s = make_shape("sphere", 4);
  for (const double factor : {0.5, 0.9}) {
    SCOPED_TRACE("inner = " + std::to_string(factor) + " x outer");
    const TetMesh m = scaled_shell(s, factor);
    ASSERT_EQ(m.tets.size(), 37920u);
    expect_nothing_reported(check_shell(s, m));
  }
}

TEST(ShellChecker, AgreesWithCheckShellAlongASequenceOfMoves) {
  // A valid sphere shell, then steps that each move a few inner vertices — out of the surface,
  // onto another vertex's place (inverting and overlapping prisms), or back home — checked both
  // by a ShellChecker that sees every step and by a fresh check_shell(): the same offenders.
  const SurfaceMesh s = make_shape("sphere", 2);
  const std::size_t n = s.points.size();
  ShellInput in;
  for (std::size_t v = 0; v < n; ++v) {
    in.inner_points.push_back(s.points[v] * 0.6);
    in.inner_id.push_back(static_cast<std::uint32_t>(v));
  }
  const std::vector<Vec3d> home = in.inner_points;
  ShellCheckOptions options;
  options.max_listed = std::numeric_limits<std::size_t>::max();
  ShellChecker checker(s, options);
  std::mt19937 rng(7);
  std::size_t invalid_steps = 0;
  for (int step = 0; step < 24; ++step) {
    SCOPED_TRACE("step " + std::to_string(step));
    if (step > 0) {
      for (int k = 0; k < 3; ++k) {
        const std::size_t v = rng() % n;
        switch (rng() % 3) {
          case 0:
            in.inner_points[v] = s.points[v] * 1.3;
            break;  // outside
          case 1:
            in.inner_points[v] = home[(v * 7 + 13) % n];
            break;  // folds prisms
          default:
            in.inner_points[v] = home[v];
            break;  // back home
        }
      }
    }
    const TetMesh mesh = assemble_shell(s, in).mesh;
    const ShellCheckResult full = check_shell(s, mesh, options);
    const ShellCheckResult incremental = checker.check(mesh);
    EXPECT_EQ(incremental.valid(), full.valid());
    EXPECT_EQ(incremental.first_inverted_tets, full.first_inverted_tets);
    EXPECT_EQ(incremental.first_outside_vertices, full.first_outside_vertices);
    EXPECT_EQ(incremental.first_overlapping_pairs, full.first_overlapping_pairs);
    EXPECT_EQ(incremental.first_leaking_tets, full.first_leaking_tets);
    EXPECT_EQ(describe_problems(incremental), describe_problems(full));
    if (!full.valid()) ++invalid_steps;
  }
  EXPECT_GT(invalid_steps, 5u);  // the sequence did break things
}

TEST(BoundaryFaces, UpdatesAgreeWithACountOfEveryFaceAlongASequenceOfEdits) {
  // A valid sphere shell whose tets are edited a few at a time, the tet count kept: corners
  // swapped (misoriented faces), rotated (the same faces, other records), a tet replaced by a
  // copy of another (shared, missing and non-manifold faces), tets restored. One BoundaryFaces
  // sees every step; each is counted from scratch here, face by face.
  const SurfaceMesh s = make_shape("sphere", 2);
  const TetMesh valid = scaled_shell(s, 0.6);
  const std::size_t T = valid.tets.size();
  ShellCheckOptions options;
  options.max_listed = std::numeric_limits<std::size_t>::max();
  BoundaryFaces faces(s);
  TetMesh m = valid;
  std::mt19937 rng(11);
  std::size_t broken_steps = 0;
  for (int step = 0; step < 40; ++step) {
    SCOPED_TRACE("step " + std::to_string(step));
    // Step 20 edits half the tets' worth (more than BoundaryFaces updates: it starts again).
    const int edits = step == 0 ? 0 : step == 20 ? int(T / 2) : 1 + int(rng() % 4);
    for (int e = 0; e < edits; ++e) {
      const std::size_t t = rng() % T;
      Tet& tet = m.tets[t];
      switch (rng() % 4) {
        case 0:
          std::swap(tet[0], tet[1]);
          break;
        case 1:
          tet = {tet[1], tet[2], tet[0], tet[3]};
          break;  // an even permutation
        case 2:
          tet = valid.tets[rng() % T];
          break;
        default:
          tet = valid.tets[t];
          break;
      }
    }
    // The reference: every face by its vertex triple, with its outward cycle (the face opposite
    // an even corner in corner order, opposite an odd one reversed).
    std::map<std::array<std::uint32_t, 3>, std::vector<std::array<std::uint32_t, 3>>> cycles;
    for (const Tet& tet : m.tets)
      for (int k = 0; k < 4; ++k) {
        std::array<std::uint32_t, 3> c{};
        for (int i = 0, j = 0; i < 4; ++i)
          if (i != k) c[std::size_t(j++)] = tet[std::size_t(i)];
        if (k % 2) std::swap(c[1], c[2]);
        std::array<std::uint32_t, 3> key = c;
        std::sort(key.begin(), key.end());
        cycles[key].push_back(c);
      }
    std::size_t nonmanifold = 0;
    for (const auto& [key, list] : cycles) nonmanifold += list.size() > 2;
    std::vector<std::uint32_t> missing, shared, misoriented;
    for (std::uint32_t f = 0; f < s.triangles.size(); ++f) {
      const Triangle& tri = s.triangles[f];
      std::array<std::uint32_t, 3> key = {tri[0], tri[1], tri[2]};
      std::sort(key.begin(), key.end());
      const auto it = cycles.find(key);
      if (it == cycles.end()) {
        missing.push_back(f);
      } else if (it->second.size() > 1) {
        shared.push_back(f);
      } else {
        const auto& c = it->second[0];
        bool same = false;
        for (int r = 0; r < 3; ++r)
          same = same || (c[0] == tri[r] && c[1] == tri[(r + 1) % 3] && c[2] == tri[(r + 2) % 3]);
        if (!same) misoriented.push_back(f);
      }
    }
    ShellCheckResult r;
    faces.check(m, options, r);
    EXPECT_EQ(r.first_missing_triangles, missing);
    EXPECT_EQ(r.first_shared_triangles, shared);
    EXPECT_EQ(r.first_misoriented_triangles, misoriented);
    EXPECT_EQ(r.missing_triangles, missing.size());
    EXPECT_EQ(r.shared_triangles, shared.size());
    EXPECT_EQ(r.misoriented_triangles, misoriented.size());
    EXPECT_EQ(r.nonmanifold_faces, nonmanifold);
    if (!missing.empty() || !shared.empty() || !misoriented.empty() || nonmanifold) ++broken_steps;
  }
  EXPECT_GT(broken_steps, 20u);  // the edits did break things
  // Back to the valid shell: nothing left over from the edits.
  ShellCheckResult r;
  faces.check(valid, options, r);
  EXPECT_EQ(r.missing_triangles + r.shared_triangles + r.misoriented_triangles, 0u);
  EXPECT_EQ(r.nonmanifold_faces, 0u);
}

TEST(ShellChecker, VolumesOnlyCheckFindsTheInvertedTets) {
  const SurfaceMesh s = make_shape("sphere", 2);
  const TetMesh m = broken_sphere_shell(s);
  ShellCheckOptions options;
  options.max_listed = std::numeric_limits<std::size_t>::max();
  const ShellCheckResult volumes = check_volumes(m, options);
  const ShellCheckResult full = check_shell(s, m, options);
  EXPECT_GT(volumes.inverted_tets, 0u);
  EXPECT_EQ(volumes.first_inverted_tets, full.first_inverted_tets);
  EXPECT_EQ(volumes.first_zero_volume_tets, full.first_zero_volume_tets);
  EXPECT_FALSE(volumes.valid());
  EXPECT_TRUE(check_volumes(scaled_shell(s, 0.5)).valid());
}

TEST(ShellChecker, RejectsAMeshThatIsNotAnAssembledShell) {
  const SurfaceMesh s = make_shape("box", 1);
  TetMesh m = scaled_shell(s, 0.5);
  ShellChecker checker(s);
  m.source_triangle.clear();
  EXPECT_THROW(checker.check(m), InputError);
  for (const int layers : {0, -3, 65}) {
    ShellCheckOptions o;
    o.layers = layers;
    EXPECT_THROW(ShellChecker(s, o), InputError) << layers;
  }
  // A two-layer shell (6 tets per prism) for a one-layer checker.
  TetMesh doubled = scaled_shell(s, 0.5);
  TetMesh two;
  two.points = doubled.points;
  for (std::size_t t = 0; t < doubled.tets.size(); ++t)
    for (int copy = 0; copy < 2; ++copy) {
      two.tets.push_back(doubled.tets[t]);
      two.source_triangle.push_back(doubled.source_triangle[t]);
    }
  ShellChecker one_layer(s);
  EXPECT_THROW(one_layer.check(two), InputError);
}

}  // namespace
}  // namespace vdb_shell
