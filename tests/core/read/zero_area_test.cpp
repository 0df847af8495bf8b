// zero_area_test.cpp — core/read/zero_area.h and make_surface()'s use of it: zero-area faces and
// folded slivers flipped away, the flat tets that keep them, and the surfaces still refused.
#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "assets/shapes.h"
#include "core/base/errors.h"
#include "core/read/load_surface.h"
#include "tests/test_support.h"

namespace vdb_shell {
namespace {

double twice_area(const SurfaceMesh& mesh, const Triangle& t) {
  const Vec3d& a = mesh.points[t[0]];
  return norm(cross(mesh.points[t[1]] - a, mesh.points[t[2]] - a));
}

/// The oriented triangles of `faces` as sorted corner triples -> how many times each appears
/// with each orientation (+1 as given, -1 the other way round).
std::map<std::array<std::uint32_t, 3>, int> oriented(const std::vector<Triangle>& faces) {
  std::map<std::array<std::uint32_t, 3>, int> out;
  for (const Triangle& f : faces) {
    std::array<std::uint32_t, 3> key = f;
    std::sort(key.begin(), key.end());
    // Even permutations of the sorted triple run one way round, odd ones the other.
    const bool even = (f[0] == key[0] && f[1] == key[1]) || (f[0] == key[1] && f[1] == key[2]) ||
                      (f[0] == key[2] && f[1] == key[0]);
    out[key] += even ? 1 : -1;
  }
  return out;
}

/// Checks, with computations of its own, that the flips of `mesh` glue together: the flat tets'
/// outward faces are the input's faces less the flipped surface's (as oriented sums: the faces
/// the flips did not touch cancel out, the tets glue to each other and to the flipped surface
/// along the others); every flipped face lies in the plane of the input face it is said to
/// cover; no face of the flipped surface has zero area; every flat tet has zero volume.
void expect_flips_glue(const SurfaceMesh& mesh, const ZeroAreaFlips& flips, double min_twice_area) {
  std::vector<Triangle> faces;
  for (const Tet& t : flips.tets)
    for (const auto& f : kTetOutwardFace) faces.push_back({t[f[0]], t[f[1]], t[f[2]]});
  faces.insert(faces.end(), flips.triangles.begin(), flips.triangles.end());
  std::map<std::array<std::uint32_t, 3>, int> sum = oriented(faces);
  for (const auto& [key, count] : oriented(mesh.triangles)) sum[key] -= count;
  for (const auto& [key, count] : sum)
    EXPECT_EQ(count, 0) << "face (" << key[0] << ", " << key[1] << ", " << key[2] << ")";
  ASSERT_EQ(flips.triangles.size(), mesh.triangles.size());
  for (std::size_t f = 0; f < flips.triangles.size(); ++f) {
    const Triangle& t = flips.triangles[f];
    EXPECT_GT(twice_area(mesh, t), min_twice_area) << "face " << f;
    const Triangle& in = mesh.triangles[flips.face_of[f]];
    const Vec3d& o = mesh.points[in[0]];
    const Vec3d n = normalized(cross(mesh.points[in[1]] - o, mesh.points[in[2]] - o));
    for (const std::uint32_t v : t) EXPECT_NEAR(dot(mesh.points[v] - o, n), 0.0, 1e-12);
  }
  for (const Tet& t : flips.tets) {
    const Vec3d& a = mesh.points[t[0]];
    EXPECT_NEAR(dot(mesh.points[t[1]] - a, cross(mesh.points[t[2]] - a, mesh.points[t[3]] - a)),
                0.0, 1e-14);
  }
}

TEST(ZeroArea, AVertexOnAnEdgeIsFlippedAwayAndKeptByAFlatTet) {
  // The unit box's faces with a vertex m exactly at the middle of one face's edge (a, b): that
  // face becomes (a, b, m), of zero area, and two faces fanned from m.
  std::vector<test::InsertedVertex> inserted;
  const SurfaceMesh box = test::with_caps(make_shape("box", 1), 100, 0.0, 1, inserted);
  ASSERT_EQ(inserted.size(), 1u);
  const double min_twice_area = 1e-14;
  std::size_t zero = 0;
  for (const Triangle& t : box.triangles) zero += twice_area(box, t) <= min_twice_area;
  ASSERT_EQ(zero, 1u);
  const std::optional<ZeroAreaFlips> flips = flip_zero_area_faces(box, min_twice_area);
  ASSERT_TRUE(flips.has_value());
  ASSERT_EQ(flips->tets.size(), 1u);
  // The flat tet: the edge's ends, the neighbour's third corner, m.
  const Tet& tet = flips->tets[0];
  EXPECT_EQ(tet[3], inserted[0].vertex);
  EXPECT_EQ(std::min(tet[0], tet[1]), std::min(inserted[0].near, inserted[0].far));
  EXPECT_EQ(std::max(tet[0], tet[1]), std::max(inserted[0].near, inserted[0].far));
  expect_flips_glue(box, *flips, min_twice_area);
}

TEST(ZeroArea, FansOfZeroAreaFacesOnOneLineAreFlippedFromTheirEnd) {
  // Strips of 3 vertices on an edge of every 5th face, at height 0: fans of zero-area faces on
  // one line (as CAD exports leave along a slot's edge), each flip onto a face with an area.
  for (const char* shape : {"box", "sphere", "torus"}) {
    std::vector<test::InsertedVertex> inserted;
    const SurfaceMesh mesh = test::with_caps(make_shape(shape, 1), 5, 0.0, 3, inserted);
    const double min_twice_area = 2e-14 * norm2(bounding_box(mesh).extent());
    std::size_t zero = 0;
    for (const Triangle& t : mesh.triangles) zero += twice_area(mesh, t) <= min_twice_area;
    ASSERT_GT(zero, 0u) << shape;
    const std::optional<ZeroAreaFlips> flips = flip_zero_area_faces(mesh, min_twice_area);
    ASSERT_TRUE(flips.has_value()) << shape;
    EXPECT_GE(flips->tets.size(), zero) << shape;
    expect_flips_glue(mesh, *flips, min_twice_area);
    // make_surface() takes the same surface, with a notice, and the flips of its own.
    const LoadedSurface loaded = make_surface(polygon_soup_of(mesh), shape);
    EXPECT_EQ(loaded.zero_area.tets.size(), flips->tets.size()) << shape;
    EXPECT_TRUE(std::any_of(loaded.notices.begin(), loaded.notices.end(), [&](const auto& s) {
      return s.find(std::to_string(zero) + " faces have zero area") != std::string::npos;
    })) << shape;
  }
}

TEST(ZeroArea, FacesTurnedTheWrongWayAreMendedFirst) {
  // The fans of zero-area faces with every 7th face running against its neighbours: the faces
  // are turned to agree, then the zero-area ones flipped (it was refused, both faults left).
  std::vector<test::InsertedVertex> inserted;
  const SurfaceMesh mesh = test::with_caps(make_shape("sphere", 1), 5, 0.0, 3, inserted);
  PolygonSoup turned = polygon_soup_of(mesh);
  for (std::size_t f = 0; f < turned.polygons.size(); f += 7)
    std::swap(turned.polygons[f][1], turned.polygons[f][2]);
  const LoadedSurface loaded = make_surface(turned, "turned");
  EXPECT_GT(loaded.reoriented_faces, 0u);
  ASSERT_FALSE(loaded.zero_area.empty());
  EXPECT_EQ(oriented(loaded.mesh.triangles), oriented(mesh.triangles));  // as if never turned
  expect_flips_glue(loaded.mesh, loaded.zero_area, 2e-14 * norm2(bounding_box(mesh).extent()));
}

TEST(ZeroArea, SurfacesThatFlipsCannotMendAreStillRefused) {
  // A face with a repeated corner, and a zero-area face whose flip would give a second copy of
  // an edge (a flat tetrahedron: every face on one plane, two of them of zero area).
  SurfaceMesh repeated = make_shape("box", 1);
  repeated.triangles[0][1] = repeated.triangles[0][0];
  EXPECT_FALSE(flip_zero_area_faces(repeated, 1e-14).has_value());
  PolygonSoup flat;
  flat.points = {{0, 0, 0}, {2, 0, 0}, {1, 0, 0}, {1, 1, 0}};
  flat.polygons = {{0, 1, 2}, {0, 3, 1}, {1, 3, 2}, {2, 3, 0}};
  try {
    make_surface(flat, "flat.obj");
    ADD_FAILURE() << "a flat tetrahedron was taken";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("degenerate (zero-area) faces"), std::string::npos)
        << e.what();
  }
}

TEST(ZeroArea, CrossingsLeftOnceTheFlipsAreMadeAreNamedWithTheZeroAreaFaces) {
  // The box with a zero-area face, and a second box crossing it: crossings are not looked for
  // while zero-area faces are there, so the refusal names what the flips leave too, rather than
  // only the face they would have mended.
  std::vector<test::InsertedVertex> inserted;
  const SurfaceMesh box = test::with_caps(make_shape("box", 1), 100, 0.0, 1, inserted);
  ASSERT_EQ(inserted.size(), 1u);
  PolygonSoup two;
  two.points = box.points;
  for (const Triangle& t : box.triangles) two.polygons.push_back({t[0], t[1], t[2]});
  const SurfaceMesh other = make_shape("box", 1);
  const auto n = static_cast<std::int64_t>(two.points.size());
  for (const Vec3d& p : other.points) two.points.push_back(p + Vec3d{0.3, 0.2, 0.1});
  for (const Triangle& t : other.triangles) two.polygons.push_back({t[0] + n, t[1] + n, t[2] + n});
  try {
    make_surface(two, "two.obj");
    ADD_FAILURE() << "crossing boxes were taken";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("1 degenerate (zero-area) faces"), std::string::npos) << what;
    EXPECT_NE(what.find("self-intersections (pairs of faces that cross) once the zero-area faces "
                        "are flipped away, first: face "),
              std::string::npos)
        << what;
  }
  // Without the second box the flip mends it.
  PolygonSoup one;
  one.points = box.points;
  for (const Triangle& t : box.triangles) one.polygons.push_back({t[0], t[1], t[2]});
  EXPECT_EQ(make_surface(one, "one.obj").zero_area.tets.size(), 1u);
}

TEST(ZeroArea, ASliverFoldedOverItsNeighbourIsFlippedAwayWhereTheSurfaceCrossesItself) {
  // Axis-aligned, and turned off the axes (the sliver then lies on its neighbour's plane only
  // up to rounding, on either side).
  for (const double turn : {0.0, 0.3})
    for (const double across : {1e-5, 1e-6, 1e-9}) {
      Tet flat;
      const SurfaceMesh mesh = test::folded_sliver_box(across, turn, flat);
      ASSERT_FALSE(test::self_intersections(mesh).empty()) << across;
      const LoadedSurface loaded = make_surface(polygon_soup_of(mesh), "folded.obj");
      ASSERT_EQ(loaded.zero_area.tets.size(), 1u) << across;
      EXPECT_EQ(loaded.zero_area.slivers, 1u);
      EXPECT_EQ(loaded.zero_area.tets[0], flat);
      EXPECT_TRUE(test::self_intersections(flipped_surface(loaded.mesh, loaded.zero_area)).empty());
      expect_flips_glue(loaded.mesh, loaded.zero_area, 2e-14 * 3);
      EXPECT_TRUE(std::any_of(loaded.notices.begin(), loaded.notices.end(), [](const auto& s) {
        return s.find("1 slivers") != std::string::npos &&
               s.find("crossing itself at them") != std::string::npos;
      }));
    }
}

TEST(ZeroArea, SliversThatAFlipCannotMendLeaveTheCrossingRefused) {
  // A sliver 1e-3 of its edge high is no rounding (above ValidationOptions::sliver_fraction of
  // the diagonal): the surface crossing itself there is refused as before.
  Tet flat;
  const SurfaceMesh wide = test::folded_sliver_box(1e-3, 0.0, flat);
  ASSERT_FALSE(test::self_intersections(wide).empty());
  try {
    make_surface(polygon_soup_of(wide), "wide.obj");
    ADD_FAILURE() << "a sliver 1e-3 of its edge high was flipped";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("self-intersections"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace vdb_shell
