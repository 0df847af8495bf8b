// load_surface_test.cpp — core/read/load_surface.h and core/read/polygon_soup.h: every rule of
// the surface validator on tiny hand-made meshes, the readers on every format, and the shared
// mesh corpus classified as its README says.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "assets/shapes.h"
#include "core/base/errors.h"
#include "core/read/load_surface.h"
#include "core/read/polygon_soup.h"
#include "tests/test_support.h"

namespace vdb_shell {
namespace {

using test::TempDir;
using test::write_text;

const char* kCubeVertices =
    "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n";
// Outward-oriented faces (1-based), two triangles per side.
const char* kCubeFaces[12] = {"f 1 3 2", "f 1 4 3", "f 5 6 7", "f 5 7 8", "f 1 2 6", "f 1 6 5",
                              "f 2 3 7", "f 2 7 6", "f 3 4 8", "f 3 8 7", "f 4 1 5", "f 4 5 8"};

std::string cube_obj(int skip = -1, const std::string& extra = "", int flip = -1) {
  std::string s = kCubeVertices;
  for (int i = 0; i < 12; ++i) {
    if (i == skip) continue;
    std::string f = kCubeFaces[i];
    if (i == flip) {  // swap the last two indices
      const std::size_t a = f.find(' ', 2), b = f.rfind(' ');
      f = f.substr(0, a) + " " + f.substr(b + 1) + " " + f.substr(a + 1, b - a - 1);
    }
    s += f + "\n";
  }
  return s + extra;
}

/// Loads `text` saved as `name` and returns the InputError message ("" when it loads).
std::string load_error(const std::string& name, const std::string& text) {
  TempDir dir;
  write_text(dir.file(name), text);
  try {
    load_surface(dir.file(name));
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

bool contains(const std::string& s, const std::string& part) {
  return s.find(part) != std::string::npos;
}

/// Cubes as one soup: cube i has half side half[i], centre centre[i], and faces pointing out of
/// it when outward[i]; its 8 vertices and 12 triangles follow those of cube i - 1.
PolygonSoup cubes_soup(const std::vector<double>& half, const std::vector<Vec3d>& centre,
                       const std::vector<bool>& outward) {
  PolygonSoup soup;
  for (std::size_t c = 0; c < half.size(); ++c) {
    const std::int64_t o = static_cast<std::int64_t>(soup.points.size());
    for (int i = 0; i < 8; ++i) {
      const Vec3d corner{double(i == 1 || i == 2 || i == 5 || i == 6),
                         double(i == 2 || i == 3 || i == 6 || i == 7), double(i >= 4)};
      soup.points.push_back(centre[c] + (2.0 * corner - Vec3d{1, 1, 1}) * half[c]);
    }
    for (const char* f : kCubeFaces) {
      int a = 0, b = 0, d = 0;
      std::sscanf(f, "f %d %d %d", &a, &b, &d);
      if (outward[c])
        soup.polygons.push_back({o + a - 1, o + b - 1, o + d - 1});
      else
        soup.polygons.push_back({o + a - 1, o + d - 1, o + b - 1});
    }
  }
  return soup;
}

/// The enclosed volume of the triangles [12 c, 12 c + 12) of `m` (cube c of cubes_soup()),
/// computed here: sum of the signed volumes of the tets (origin, triangle).
double cube_volume(const SurfaceMesh& m, std::size_t c) {
  double v = 0.0;
  for (std::size_t t = 12 * c; t < 12 * c + 12; ++t) {
    const Vec3d &a = m.points[m.triangles[t][0]], &b = m.points[m.triangles[t][1]],
                &d = m.points[m.triangles[t][2]];
    v += dot(a, cross(b, d)) / 6.0;
  }
  return v;
}

TEST(Validate, CubeIsValidWithExactStats) {
  TempDir dir;
  write_text(dir.file("cube.obj"), cube_obj());
  const LoadedSurface s = load_surface(dir.file("cube.obj"));
  EXPECT_EQ(s.stats.vertices, 8u);
  EXPECT_EQ(s.stats.faces, 12u);
  EXPECT_EQ(s.stats.edges, 18u);
  EXPECT_EQ(s.stats.components, 1u);
  EXPECT_EQ(s.stats.genus, 0);
  EXPECT_NEAR(s.stats.enclosed_volume, 1.0, 1e-12);
  EXPECT_NEAR(s.stats.mean_edge_length, (12.0 + 6.0 * std::sqrt(2.0)) / 18.0, 1e-12);
  EXPECT_FALSE(s.flipped);
  EXPECT_EQ(s.stats.bbox.hi, Vec3d(1, 1, 1));
}

TEST(Validate, MissingFaceIsBoundary) {
  const std::string e = load_error("open.obj", cube_obj(0));
  EXPECT_TRUE(contains(e, "3 boundary edges")) << e;
  EXPECT_TRUE(contains(e, "open.obj")) << e;
  EXPECT_TRUE(contains(e, "edge (")) << e;
}

TEST(Validate, ThreeFacesOnOneEdgeIsNonManifold) {
  // A fin: extra vertex 9 and two faces that hang a third and fourth face on edge (1, 3).
  const std::string e = load_error("fin.obj", cube_obj(-1, "v 0.5 0.5 -1\nf 1 3 9\nf 3 1 9\n"));
  EXPECT_TRUE(contains(e, "non-manifold edges")) << e;
  EXPECT_TRUE(contains(e, "in 4 faces")) << e;
}

TEST(Validate, BowTieVertexIsNonManifoldAndSplitWhenThatIsAll) {
  // Two tetrahedra sharing only vertex 0: the rule names it; loading splits it, one vertex per
  // fan (the copy after the others), and keeps every face.
  const std::string text =
      "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nv -1 0 0\nv 0 -1 0\nv 0 0 -1\n"
      "f 1 3 2\nf 1 2 4\nf 2 3 4\nf 3 1 4\n"
      "f 1 6 5\nf 1 5 7\nf 5 6 7\nf 6 1 7\n";
  TempDir dir;
  write_text(dir.file("bowtie.obj"), text);
  const std::vector<SurfaceProblem> problems =
      find_surface_problems(read_polygon_soup(dir.file("bowtie.obj")));
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_TRUE(contains(problems[0].rule, "non-manifold vertices")) << problems[0].rule;
  EXPECT_TRUE(contains(problems[0].first, "vertex 0 at (0, 0, 0)")) << problems[0].first;

  const LoadedSurface s = load_surface(dir.file("bowtie.obj"));
  EXPECT_EQ(s.pinched_vertices, 1u);
  ASSERT_EQ(s.mesh.points.size(), 8u);
  EXPECT_EQ(s.mesh.points[7], (Vec3d{0, 0, 0}));
  EXPECT_EQ(s.stats.components, 2u);
  ASSERT_EQ(s.mesh.triangles.size(), 8u);
  for (std::size_t t = 0; t < 8; ++t) {
    // The first tet keeps vertex 0, the second uses the copy; the other corners as written.
    const std::uint32_t pinch = t < 4 ? 0u : 7u;
    EXPECT_EQ(std::count(s.mesh.triangles[t].begin(), s.mesh.triangles[t].end(), pinch),
              t == 2 || t == 6 ? 0 : 1)
        << t;
  }
  // The second tet is written inside out as well: turned, with a notice of its own.
  EXPECT_EQ(s.flipped_components, 1u);
  ASSERT_EQ(s.notices.size(), 2u);
  EXPECT_TRUE(contains(s.notices[1],
                       "1 vertices where parts of the surface meet only at that "
                       "point were split"))
      << s.notices[1];

  // With a face missing as well, splitting is no fix: refused with both problems as written.
  const std::string open = text.substr(0, text.rfind("f 5 6 7"));
  const std::string e = load_error("open_bowtie.obj", open + "f 6 1 7\n");
  EXPECT_TRUE(contains(e, "boundary edges")) << e;
}

TEST(Validate, FlippedFaceIsInconsistentAndTurnedWhenThatIsAll) {
  // The cube with face 3 written the other way round: the rule names it; loading turns it back
  // (the fewer of the faces that disagree), and the cube encloses its volume again.
  TempDir dir;
  write_text(dir.file("flip.obj"), cube_obj(-1, "", 3));
  const std::vector<SurfaceProblem> problems =
      find_surface_problems(read_polygon_soup(dir.file("flip.obj")));
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_TRUE(contains(problems[0].rule, "inconsistently oriented")) << problems[0].rule;
  const LoadedSurface s = load_surface(dir.file("flip.obj"));
  EXPECT_EQ(s.reoriented_faces, 1u);
  EXPECT_FALSE(s.flipped);
  // "f 5 8 7" runs again as "f 5 7 8" does (its corners in reverse, from the last).
  EXPECT_EQ(s.mesh.triangles[3], (Triangle{6, 7, 4}));
  EXPECT_NEAR(cube_volume(s.mesh, 0), 1.0, 1e-12);
  ASSERT_EQ(s.notices.size(), 1u);
  EXPECT_TRUE(contains(s.notices[0], "1 faces ran against their neighbours")) << s.notices[0];

  // A one-sided surface (the projective plane in 6 vertices, 10 triangles, immersed crossing
  // itself) has no orientation to agree on: refused as written.
  const std::string rp2 =
      "v 0 0 0\nv 1 0.1 0.2\nv 0.3 1 0.1\nv 0.2 0.4 1\nv 0.9 0.8 0.7\nv 0.6 0.1 0.9\n"
      "f 1 2 3\nf 1 3 4\nf 1 4 5\nf 1 5 6\nf 1 6 2\nf 2 3 5\nf 3 4 6\nf 4 5 2\nf 5 6 3\n"
      "f 6 2 4\n";
  const std::string e = load_error("rp2.obj", rp2);
  EXPECT_TRUE(contains(e, "inconsistently oriented")) << e;
}

TEST(Validate, NanVertexIsNamed) {
  std::string text = cube_obj();
  text.replace(text.find("v 1 1 1"), 7, "v 1 nan 1");
  const std::string e = load_error("nan.obj", text);
  EXPECT_TRUE(contains(e, "NaN/Inf")) << e;
  EXPECT_TRUE(contains(e, "vertex 6")) << e;
}

TEST(Validate, NanInSoupIsNamed) {
  PolygonSoup soup;
  soup.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, NAN}};
  soup.polygons = {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {2, 0, 3}};
  const auto problems = find_surface_problems(soup);
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_EQ(problems[0].rule, "NaN/Inf coordinates");
  EXPECT_TRUE(contains(problems[0].first, "vertex 3")) << problems[0].first;
}

TEST(Validate, IndexOutOfRange) {
  std::string text = cube_obj();
  text.replace(text.find("f 4 5 8"), 7, "f 4 5 80");
  const std::string e = load_error("range.obj", text);
  EXPECT_TRUE(contains(e, "out-of-range")) << e;
  EXPECT_TRUE(contains(e, "face 11")) << e;
}

TEST(Validate, DegenerateAndDuplicateFaces) {
  PolygonSoup soup;
  soup.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {2, 0, 0}};
  soup.polygons = {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {2, 0, 3}, {0, 1, 4}, {1, 2, 3}};
  const auto problems = find_surface_problems(soup);
  bool degenerate = false, duplicate = false;
  for (const auto& p : problems) {
    if (contains(p.rule, "degenerate")) degenerate = contains(p.first, "face 4");
    if (contains(p.rule, "duplicate")) duplicate = contains(p.first, "face 5 repeats face 2");
  }
  EXPECT_TRUE(degenerate);
  EXPECT_TRUE(duplicate);
}

TEST(Validate, EdgesTooShortForReadersThatWeldAreRefused) {
  // Vertices inserted next to edge ends of a box: 5e-11 from the end (3e-11 of the diagonal)
  // readers that weld positions within 1e-9 of the diagonal join, and the faces collapse for
  // them; 5e-9 away they stay apart, and the surface is valid.
  for (const double t : {1e-10, 1e-8}) {
    std::vector<test::InsertedVertex> inserted;
    const SurfaceMesh m = test::with_vertices_near_edge_ends(make_shape("box", 1), 5, t, inserted);
    ASSERT_GE(inserted.size(), 5u);
    PolygonSoup soup;
    soup.points = m.points;
    for (const Triangle& tri : m.triangles) soup.polygons.push_back({tri[0], tri[1], tri[2]});
    const std::vector<SurfaceProblem> problems = find_surface_problems(soup);
    if (t < 1e-9) {
      ASSERT_EQ(problems.size(), 1u) << t;
      EXPECT_TRUE(contains(problems[0].rule, "readers that weld positions")) << problems[0].rule;
      EXPECT_TRUE(contains(problems[0].first, "vertices " + std::to_string(inserted[0].near) +
                                                  " and " + std::to_string(inserted[0].vertex)) ||
                  contains(problems[0].first, "vertices " + std::to_string(inserted[0].vertex) +
                                                  " and " + std::to_string(inserted[0].near)))
          << problems[0].first;
      EXPECT_THROW(make_surface(soup, "short"), InputError);
    } else {
      EXPECT_TRUE(problems.empty()) << problems[0].rule;
    }
  }
}

/// cube_obj() and a second unit cube at `corner`, as one OBJ.
std::string two_cubes_obj(const Vec3d& corner) {
  std::string s = cube_obj();
  for (int i = 0; i < 8; ++i) {
    const Vec3d p = corner + Vec3d{double(i == 1 || i == 2 || i == 5 || i == 6),
                                   double(i == 2 || i == 3 || i == 6 || i == 7), double(i >= 4)};
    s += "v " + std::to_string(p.x) + " " + std::to_string(p.y) + " " + std::to_string(p.z) + "\n";
  }
  for (const char* f : kCubeFaces) {
    int a = 0, b = 0, c = 0;
    std::sscanf(f, "f %d %d %d", &a, &b, &c);
    s += "f " + std::to_string(a + 8) + " " + std::to_string(b + 8) + " " + std::to_string(c + 8) +
         "\n";
  }
  return s;
}

TEST(Validate, CrossingSurfaceIsRefusedNamingFacesAndAPoint) {
  // Two unit cubes, the second at (0.5, 0.25, 0.25): closed, consistently oriented and manifold,
  // but the parts cross.
  const std::string e = load_error("crossing.obj", two_cubes_obj({0.5, 0.25, 0.25}));
  EXPECT_TRUE(contains(e, "crossing.obj: not a closed 2-manifold")) << e;
  EXPECT_TRUE(contains(e, "self-intersections (pairs of faces that cross)")) << e;
  // The first listed point lies on both cubes' surfaces: on a face plane of each (coordinates
  // 0 or 1 for the first; 0.5 or 1.5, 0.25 or 1.25 for the second).
  const std::size_t at = e.find(" cross at (");
  ASSERT_NE(at, std::string::npos) << e;
  double x = 0, y = 0, z = 0;
  ASSERT_EQ(std::sscanf(e.c_str() + at, " cross at (%lf, %lf, %lf)", &x, &y, &z), 3) << e;
  const auto on = [](double v, double a) {
    return std::abs(v - a) < 1e-9 || std::abs(v - a - 1) < 1e-9;
  };
  EXPECT_TRUE(on(x, 0) || on(y, 0) || on(z, 0)) << e;
  EXPECT_TRUE(on(x, 0.5) || on(y, 0.25) || on(z, 0.25)) << e;
  EXPECT_FALSE(contains(e, "at least")) << e;  // a few crossings: all counted
  // Side by side, touching along the plane x = 1, they load.
  EXPECT_EQ(load_error("touching.obj", two_cubes_obj({1, 0.25, 0.25})), "");
}

TEST(Validate, CrumpledSurfaceCountsItsCrossingsOnlySoFar) {
  // A sphere with its points dealt to other vertices: closed and manifold, every face across the
  // ball, crossing a good share of the others (tens of thousands of pairs of 760 faces).
  SurfaceMesh crumpled = make_shape("sphere");
  const std::vector<Vec3d> points = crumpled.points;
  const std::size_t n = points.size();
  for (std::size_t i = 0; i < n; ++i) crumpled.points[i] = points[(i * 7919 + 13) % n];
  ASSERT_NE(n % 7919, 0u);
  const std::vector<SurfaceProblem> problems = find_surface_problems(polygon_soup_of(crumpled));
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_TRUE(contains(problems[0].rule, "self-intersections")) << problems[0].rule;
  EXPECT_EQ(problems[0].count, 10000u);
  EXPECT_TRUE(problems[0].at_least);
  // The first pair named crosses, by the tests' own predicate.
  unsigned f = 0, g = 0;
  ASSERT_EQ(std::sscanf(problems[0].first.c_str(), "face %u and face %u", &f, &g), 2)
      << problems[0].first;
  const auto corners = [&](unsigned t) {
    const Triangle& tri = crumpled.triangles[t];
    return std::array<Vec3d, 3>{crumpled.points[tri[0]], crumpled.points[tri[1]],
                                crumpled.points[tri[2]]};
  };
  EXPECT_TRUE(test::triangles_intersect(corners(f), corners(g))) << f << " " << g;
  try {
    make_surface(polygon_soup_of(crumpled), "crumpled.obj");
    ADD_FAILURE() << "loaded";
  } catch (const InputError& e) {
    EXPECT_TRUE(contains(e.what(),
                         "crumpled.obj: not a closed 2-manifold triangle surface: at "
                         "least 10000 self-intersections"))
        << std::string(e.what()).substr(0, 300);
  }
}

/// `text`'s OBJ vertices times 2^k (std::ldexp: exact), as a soup.
PolygonSoup scaled_obj_soup(const std::string& text, int k) {
  TempDir dir;
  write_text(dir.file("m.obj"), text);
  PolygonSoup soup = read_polygon_soup(dir.file("m.obj"));
  for (Vec3d& p : soup.points) p = {std::ldexp(p.x, k), std::ldexp(p.y, k), std::ldexp(p.z, k)};
  return soup;
}

TEST(Validate, VerdictsAndMessagesHoldInAnyUnit) {
  // Squared lengths, areas and the crossing predicates overflow beyond ~1e150 and underflow
  // below ~1e-150: a surface given in such units once drew false "degenerate faces" and
  // "self-intersections". The same surfaces at 2^k times their size, k from -1000 (1e-301) to
  // 1000 (1e301), must draw the same verdicts as at their own size, with points named in the
  // input's coordinates.
  const std::string crossing = two_cubes_obj({0.5, 0.25, 0.25});
  const std::string touching = two_cubes_obj({1, 0.25, 0.25});
  const std::string inward =
      "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 4 2\nf 2 4 3\nf 3 4 1\n";
  for (const int k : {-1000, -500, -200, 0, 200, 500, 1000}) {
    SCOPED_TRACE("at 2^" + std::to_string(k));
    const double s = std::ldexp(1.0, k);
    // Clean: the touching cubes, with exact lengths; the inward tet flipped, its volume positive.
    const LoadedSurface cubes = make_surface(scaled_obj_soup(touching, k), "touching");
    EXPECT_EQ(cubes.stats.mean_edge_length,
              std::ldexp(make_surface(scaled_obj_soup(touching, 0), "").stats.mean_edge_length, k));
    const LoadedSurface tet = make_surface(scaled_obj_soup(inward, k), "inward");
    EXPECT_TRUE(tet.flipped);
    EXPECT_EQ(tet.stats.enclosed_volume, std::ldexp(1.0 / 6.0, 3 * k));
    // Crossing: refused, the crossing point on a face plane of each cube, in input coordinates.
    const std::vector<SurfaceProblem> problems =
        find_surface_problems(scaled_obj_soup(crossing, k));
    ASSERT_EQ(problems.size(), 1u);
    EXPECT_TRUE(contains(problems[0].rule, "self-intersections")) << problems[0].rule;
    double x = 0, y = 0, z = 0;
    ASSERT_EQ(std::sscanf(problems[0].first.c_str() + problems[0].first.find(" cross at ("),
                          " cross at (%lf, %lf, %lf)", &x, &y, &z),
              3)
        << problems[0].first;
    x /= s;
    y /= s;
    z /= s;
    const auto on = [](double v, double a) {
      return std::abs(v - a) < 1e-5 || std::abs(v - a - 1) < 1e-5;  // "%.6g" in the message
    };
    EXPECT_TRUE(on(x, 0) || on(y, 0) || on(z, 0)) << problems[0].first;
    EXPECT_TRUE(on(x, 0.5) || on(y, 0.25) || on(z, 0.25)) << problems[0].first;
    // A missing face: three boundary edges, named at the input's positions.
    const std::vector<SurfaceProblem> open = find_surface_problems(scaled_obj_soup(cube_obj(0), k));
    ASSERT_EQ(open.size(), 1u);
    EXPECT_EQ(open[0].count, 3u);
    char corner[64];
    std::snprintf(corner, sizeof corner, "-(%.6g, %.6g, %.6g)", s, 0.0, 0.0);  // edge (0, 1)
    EXPECT_TRUE(contains(open[0].first, corner)) << open[0].first;
    // A zero-area face among faces of the 1e-14 fraction's area, as at unit size.
    PolygonSoup sliver;
    sliver.points = {{0, 0, 0}, {s, 0, 0}, {0, s, 0}, {0, 0, s}, {2 * s, 0, 0}};
    sliver.polygons = {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {2, 0, 3}, {0, 1, 4}};
    std::size_t degenerate = 0;
    for (const SurfaceProblem& p : find_surface_problems(sliver))
      if (contains(p.rule, "degenerate")) degenerate = p.count;
    EXPECT_EQ(degenerate, 1u);
  }
}

TEST(Validate, InwardSurfaceIsFlippedWithNotice) {
  PolygonSoup soup;
  soup.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  soup.polygons = {{0, 1, 2}, {0, 3, 1}, {1, 3, 2}, {2, 3, 0}};  // all faces point inward
  const LoadedSurface s = make_surface(soup, "tet");
  EXPECT_TRUE(s.flipped);
  ASSERT_EQ(s.notices.size(), 1u);
  EXPECT_TRUE(contains(s.notices[0], "flipped"));
  EXPECT_NEAR(s.stats.enclosed_volume, 1.0 / 6.0, 1e-12);
}

/// The cube with every face's corners written apart (a file with seams everywhere: each corner
/// stored once per face, as exporters split vertices along UV or normal seams).
PolygonSoup cube_written_apart() {
  const double corner[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                               {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
  PolygonSoup soup;
  for (const char* f : kCubeFaces) {
    int a, b, c;
    std::sscanf(f, "f %d %d %d", &a, &b, &c);
    std::vector<std::int64_t> face;
    for (const int v : {a, b, c}) {
      soup.points.push_back({corner[v - 1][0], corner[v - 1][1], corner[v - 1][2]});
      face.push_back(std::int64_t(soup.points.size()) - 1);
    }
    soup.polygons.push_back(face);
  }
  return soup;
}

TEST(Validate, SeamsWrittenTwiceAreWeldedWithNotice) {
  const PolygonSoup apart = cube_written_apart();
  ASSERT_EQ(apart.points.size(), 36u);
  // As written: every edge is a boundary edge.
  const std::vector<SurfaceProblem> problems = find_surface_problems(apart);
  ASSERT_FALSE(problems.empty());
  EXPECT_TRUE(contains(problems[0].rule, "boundary edges"));

  const LoadedSurface s = make_surface(apart, "apart");
  EXPECT_EQ(s.seam_vertices, 28u);  // 36 corners written, 8 distinct
  EXPECT_EQ(s.mesh.points.size(), 8u);
  ASSERT_EQ(s.mesh.triangles.size(), 12u);
  EXPECT_EQ(s.stats.genus, 0);
  EXPECT_NEAR(s.stats.enclosed_volume, 1.0, 1e-12);
  ASSERT_FALSE(s.notices.empty());
  EXPECT_TRUE(contains(s.notices[0], "28 vertices")) << s.notices[0];
  EXPECT_TRUE(contains(s.notices[0], "seams")) << s.notices[0];
  // The triangles are the file's, corner for corner (by position), in the file's order.
  for (std::size_t f = 0; f < 12; ++f)
    for (int c = 0; c < 3; ++c) {
      const Vec3d& p = s.mesh.points[s.mesh.triangles[f][std::size_t(c)]];
      const Vec3d& q = apart.points[std::size_t(apart.polygons[f][std::size_t(c)])];
      EXPECT_TRUE(p == q) << f << " " << c;
    }

  // Through a file, with --repair's "kept" path in mind: the same surface.
  TempDir dir;
  std::string text;
  for (const Vec3d& p : apart.points)
    text +=
        "v " + std::to_string(p.x) + " " + std::to_string(p.y) + " " + std::to_string(p.z) + "\n";
  for (int f = 0; f < 12; ++f)
    text += "f " + std::to_string(3 * f + 1) + " " + std::to_string(3 * f + 2) + " " +
            std::to_string(3 * f + 3) + "\n";
  write_text(dir.file("apart.obj"), text);
  EXPECT_EQ(load_surface(dir.file("apart.obj")).seam_vertices, 28u);
}

/// `mesh` cut in two along its vertices shared by faces on both sides of x = 0: the faces with
/// their centroid at x >= 0 get copies of those vertices, moved by `apart` times the bounding box
/// diagonal (a crack between two patches). Returns the soup and how many vertices were copied.
std::pair<PolygonSoup, std::size_t> cracked(const SurfaceMesh& mesh, double apart) {
  PolygonSoup soup = polygon_soup_of(mesh);
  const double d = apart * bounding_box(mesh).diagonal();
  std::vector<char> left(mesh.points.size(), 0), right(mesh.points.size(), 0);
  const auto side = [&](const Triangle& t) {
    return mesh.points[t[0]].x + mesh.points[t[1]].x + mesh.points[t[2]].x >= 0;
  };
  for (const Triangle& t : mesh.triangles)
    for (const std::uint32_t v : t) (side(t) ? right : left)[v] = 1;
  std::vector<std::int64_t> copy(mesh.points.size(), -1);
  for (std::size_t v = 0; v < mesh.points.size(); ++v)
    if (left[v] && right[v]) {
      copy[v] = std::int64_t(soup.points.size());
      // A different direction per vertex, of length d.
      const double a = 0.7 * double(v), b = 1.3 * double(v);
      soup.points.push_back(
          mesh.points[v] +
          Vec3d{std::cos(a) * std::sin(b), std::sin(a) * std::sin(b), std::cos(b)} * d);
    }
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f)
    if (side(mesh.triangles[f]))
      for (std::int64_t& v : soup.polygons[f])
        if (copy[std::size_t(v)] >= 0) v = copy[std::size_t(v)];
  return {soup, soup.points.size() - mesh.points.size()};
}

TEST(Validate, CracksBetweenPatchesWrittenARoundingApartAreWelded) {
  for (const char* name : {"sphere", "torus", "box"}) {
    const SurfaceMesh mesh = make_shape(name);
    const auto [crack, copies] = cracked(mesh, 1e-8);
    ASSERT_GE(copies, 8u) << name;
    ASSERT_TRUE(contains(find_surface_problems(crack)[0].rule, "boundary edges")) << name;
    const LoadedSurface s = make_surface(crack, name);
    EXPECT_EQ(s.crack_vertices, copies) << name;
    EXPECT_EQ(s.seam_vertices, 0u) << name;
    ASSERT_FALSE(s.notices.empty()) << name;
    EXPECT_TRUE(contains(s.notices[0], std::to_string(copies) + " vertices of open edges"))
        << s.notices[0];
    // The input mesh back: its points (the copies gone), its triangles in order.
    EXPECT_EQ(s.mesh.points, mesh.points) << name;
    EXPECT_EQ(s.mesh.triangles, mesh.triangles) << name;
    // Cracks wider than the tolerance stay open edges.
    const auto [wide, wide_copies] = cracked(mesh, 1e-6);
    ASSERT_EQ(wide_copies, copies);
    try {
      make_surface(wide, name);
      ADD_FAILURE() << name << ": loaded";
    } catch (const InputError& e) {
      EXPECT_TRUE(contains(e.what(), std::to_string(2 * copies) + " boundary edges")) << e.what();
    }
  }
}

TEST(Validate, OnlyCracksAlongALineAreClosedBySlivers) {
  // The sphere with 3 vertices on an edge of every 5th face, `height` of the edge off it: the
  // face fanned, its neighbour whole, the caps between them left out (test::with_caps()).
  const auto cracked = [](double height, std::size_t& caps) {
    std::vector<test::InsertedVertex> inserted;
    const SurfaceMesh capped = test::with_caps(make_shape("sphere"), 5, height, 3, inserted);
    SurfaceMesh out = capped;
    out.triangles.clear();
    // A cap has its three corners on one strip: the edge's ends and the vertices on it.
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::set<std::uint32_t>> strips;
    for (const test::InsertedVertex& m : inserted)
      strips[{m.near, m.far}].insert({m.near, m.far, m.vertex});
    for (const Triangle& t : capped.triangles) {
      bool cap = false;
      for (const auto& [edge, on] : strips)
        cap = cap || (on.count(t[0]) && on.count(t[1]) && on.count(t[2]));
      if (!cap) out.triangles.push_back(t);
    }
    caps = capped.triangles.size() - out.triangles.size();
    return out;
  };
  std::size_t caps = 0;
  const SurfaceMesh on_line = cracked(0.0, caps);
  ASSERT_GT(caps, 20u);
  const LoadedSurface s = make_surface(polygon_soup_of(on_line), "on_line");
  EXPECT_EQ(s.crack_faces, caps);
  EXPECT_EQ(s.zero_area.tets.size(), caps);  // every sliver of zero area, flipped away
  ASSERT_EQ(s.mesh.triangles.size(), on_line.triangles.size() + caps);
  for (std::size_t f = on_line.triangles.size(); f < s.mesh.triangles.size(); ++f) {
    const Triangle& t = s.mesh.triangles[f];
    const Vec3d &a = s.mesh.points[t[0]], &b = s.mesh.points[t[1]], &c = s.mesh.points[t[2]];
    EXPECT_LT(norm(cross(b - a, c - a)), 1e-15) << f;
  }
  ASSERT_FALSE(s.notices.empty());
  EXPECT_TRUE(contains(s.notices.back(), std::to_string(caps) + " slivers were added"))
      << s.notices.back();
  // 1e-3 of the edge off it, the cracks are no line: left open.
  const SurfaceMesh off_line = cracked(1e-3, caps);
  try {
    make_surface(polygon_soup_of(off_line), "off_line");
    ADD_FAILURE() << "loaded";
  } catch (const InputError& e) {
    EXPECT_TRUE(contains(e.what(), "boundary edges")) << e.what();
  }
}

TEST(Validate, FacesWrittenTwiceAreDropped) {
  // Faces 0 and 5 written again, the second from another corner: 14 faces, 4 edges in 3 faces.
  const std::string twice = cube_obj(-1, "f 1 3 2\nf 6 5 1\n");
  ASSERT_FALSE(find_surface_problems(scaled_obj_soup(twice, 0)).empty());
  const LoadedSurface s = make_surface(scaled_obj_soup(twice, 0), "twice.obj");
  EXPECT_EQ(s.repeated_faces, 2u);
  ASSERT_EQ(s.mesh.triangles.size(), 12u);
  EXPECT_NEAR(s.stats.enclosed_volume, 1.0, 1e-12);
  // The file's first 12 faces, as written.
  const LoadedSurface cube = make_surface(scaled_obj_soup(cube_obj(), 0), "cube.obj");
  EXPECT_EQ(s.mesh.triangles, cube.mesh.triangles);
  ASSERT_FALSE(s.notices.empty());
  EXPECT_TRUE(contains(s.notices[0], "2 faces repeated an earlier face")) << s.notices[0];
  EXPECT_TRUE(contains(s.notices[0], "polygon 12")) << s.notices[0];
  // Written again the other way round, a face is no repeat: refused.
  const std::string e = load_error("reversed.obj", cube_obj(-1, "f 1 2 3\n"));
  EXPECT_TRUE(contains(e, "duplicate faces")) << e;
  EXPECT_TRUE(contains(e, "non-manifold edges")) << e;
}

TEST(Validate, WeldingIsNotAFixForOtherProblems) {
  // Seams and a hole: still refused, with the problems as written.
  PolygonSoup holed = cube_written_apart();
  holed.polygons.pop_back();
  try {
    make_surface(holed, "holed");
    ADD_FAILURE() << "accepted";
  } catch (const InputError& e) {
    EXPECT_TRUE(contains(e.what(), "33 boundary edges")) << e.what();  // 3 * 11 as written
  }
  // Two tets touching at one corner, each with its own vertex there: valid as written, and kept
  // apart (welded, the corner would be non-manifold).
  PolygonSoup touching;
  touching.points = {{0, 0, 0}, {1, 0, 0},  {0, 1, 0},  {0, 0, 1},
                     {0, 0, 0}, {-1, 0, 0}, {0, -1, 0}, {0, 0, -1}};
  touching.polygons = {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {2, 0, 3},
                       {4, 5, 6}, {4, 7, 5}, {5, 7, 6}, {6, 7, 4}};
  const LoadedSurface kept = make_surface(touching, "touching");
  EXPECT_EQ(kept.seam_vertices, 0u);
  EXPECT_EQ(kept.mesh.points.size(), 8u);
  EXPECT_EQ(kept.stats.components, 2u);
  // The same with a hole in one tet: welding the shared corner does not make it valid either.
  touching.polygons.pop_back();
  EXPECT_THROW(make_surface(touching, "touching, holed"), InputError);
}

TEST(Validate, SeveralComponentsAndQuadsAreAllowed) {
  // Two disjoint cubes written with quads.
  std::string text;
  for (int c = 0; c < 2; ++c)
    for (int i = 0; i < 8; ++i)
      text += "v " + std::to_string((i & 1) ^ ((i >> 1) & 1)) + " " + std::to_string((i >> 1) & 1) +
              " " + std::to_string((i >> 2) + 3 * c) + "\n";
  for (int c = 0; c < 2; ++c) {
    const int o = 8 * c;
    const int quads[6][4] = {{1, 4, 3, 2}, {5, 6, 7, 8}, {1, 2, 6, 5},
                             {2, 3, 7, 6}, {3, 4, 8, 7}, {4, 1, 5, 8}};
    for (const auto& q : quads)
      text += "f " + std::to_string(q[0] + o) + " " + std::to_string(q[1] + o) + " " +
              std::to_string(q[2] + o) + " " + std::to_string(q[3] + o) + "\n";
  }
  TempDir dir;
  write_text(dir.file("two.obj"), text);
  const LoadedSurface s = load_surface(dir.file("two.obj"));
  EXPECT_EQ(s.stats.components, 2u);
  EXPECT_EQ(s.stats.faces, 24u);
  EXPECT_EQ(s.triangulated_polygons, 12u);
  EXPECT_NEAR(s.stats.enclosed_volume, 2.0, 1e-12);
}

TEST(Validate, ComponentsFacingIntoTheSolidAreFlippedByTheirNesting) {
  const Vec3d o{0, 0, 0};
  struct Case {
    const char* what;
    std::vector<double> half;
    std::vector<Vec3d> centre;
    std::vector<bool> outward;
    std::vector<double> volume;  // after loading
    bool flipped;
    std::size_t flipped_components;
  };
  const std::vector<Case> cases = {
      {"a body in a body: the inner one bounds a cavity",
       {1, 0.5},
       {o, o},
       {true, true},
       {8, -1},
       false,
       1},
      {"a body, a cavity in it, and an island in the cavity, all facing out",
       {1, 0.6, 0.3},
       {o, o, o},
       {true, true, true},
       {8, -1.728, 0.216},
       false,
       1},
      {"two bodies apart, the second inward",
       {1, 0.5},
       {o, {5, 0, 0}},
       {true, false},
       {8, 1},
       false,
       1},
      {"a hollow cube written inside out", {1, 0.5}, {o, o}, {false, true}, {8, -1}, true, 0},
      {"a hollow cube as it should be", {1, 0.5}, {o, o}, {true, false}, {8, -1}, false, 0},
      {"cubes touching along an edge and at a face, far from the origin",
       {1, 1, 0.5},
       {{1e4, 1e4, 1e4}, {1e4 + 2, 1e4 + 2, 1e4}, {1e4, 1e4, 1e4 + 1.5}},
       {true, true, true},
       {8, 8, 1},
       false,
       0},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.what);
    const LoadedSurface s = make_surface(cubes_soup(c.half, c.centre, c.outward), "cubes");
    ASSERT_EQ(s.mesh.triangles.size(), 12 * c.half.size());
    for (std::size_t k = 0; k < c.half.size(); ++k) {
      // Volumes about the cube's own centre (the far cubes' sums would cancel badly at the origin).
      SurfaceMesh local = s.mesh;
      for (Vec3d& p : local.points) p = p - c.centre[k];
      EXPECT_NEAR(cube_volume(local, k), c.volume[k], 1e-9) << "cube " << k;
    }
    EXPECT_EQ(s.flipped, c.flipped);
    EXPECT_EQ(s.flipped_components, c.flipped_components);
    EXPECT_EQ(s.notices.size(), c.flipped || c.flipped_components ? 1u : 0u);
  }
  // The notice counts the components and names the first one turned by a face.
  const LoadedSurface s =
      make_surface(cubes_soup({1, 0.6, 0.3}, {o, o, o}, {true, true, true}), "nested");
  ASSERT_EQ(s.notices.size(), 1u);
  EXPECT_TRUE(contains(s.notices[0], "1 of 3 components faced into the solid")) << s.notices[0];
  EXPECT_TRUE(contains(s.notices[0], "component of face 12")) << s.notices[0];
}

TEST(Validate, PartsTouchingFaceToFaceAreDuplicateFaces) {
  // Two unit cubes, the second on top of the first, each with its own vertices: the top face of
  // the first lies on the bottom face of the second, triangle on triangle.
  PolygonSoup soup = cubes_soup({0.5, 0.5}, {{0.5, 0.5, 0.5}, {0.5, 0.5, 1.5}}, {true, true});
  std::string first;
  for (const auto& p : find_surface_problems(soup))
    if (contains(p.rule, "duplicate")) first = p.first;
  EXPECT_TRUE(contains(first, "face 12 lies on face 2")) << first;
  EXPECT_THROW(make_surface(soup, "stacked"), InputError);
  // Welding the touching corners does not make it a surface either: still refused as it is.
  try {
    make_surface(soup, "stacked");
  } catch (const InputError& e) {
    EXPECT_TRUE(contains(e.what(), "lies on")) << e.what();
  }
}

TEST(Validate, GenusOfATorusLikeBlock) {
  // A 3x3x1 block of unit cells with the centre cell removed: genus 1 (built as quads).
  PolygonSoup soup;
  auto vid = [](int i, int j, int k) { return static_cast<std::int64_t>((k * 4 + j) * 4 + i); };
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j < 4; ++j)
      for (int i = 0; i < 4; ++i) soup.points.push_back({double(i), double(j), double(k)});
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) {
      if (i == 1 && j == 1) continue;
      soup.polygons.push_back(
          {vid(i, j, 0), vid(i, j + 1, 0), vid(i + 1, j + 1, 0), vid(i + 1, j, 0)});
      soup.polygons.push_back(
          {vid(i, j, 1), vid(i + 1, j, 1), vid(i + 1, j + 1, 1), vid(i, j + 1, 1)});
    }
  // Outward = right of (i0, j0) -> (i1, j1) seen from +z.
  auto wall = [&](int i0, int j0, int i1, int j1) {
    soup.polygons.push_back({vid(i0, j0, 0), vid(i1, j1, 0), vid(i1, j1, 1), vid(i0, j0, 1)});
  };
  for (int i = 0; i < 3; ++i) {
    wall(i, 0, i + 1, 0);
    wall(i + 1, 3, i, 3);
  }
  for (int j = 0; j < 3; ++j) {
    wall(3, j, 3, j + 1);
    wall(0, j + 1, 0, j);
  }
  wall(1, 1, 1, 2);
  wall(1, 2, 2, 2);
  wall(2, 2, 2, 1);
  wall(2, 1, 1, 1);  // the hole, inward
  const LoadedSurface s = make_surface(soup, "block");
  EXPECT_EQ(s.stats.genus, 1);
  EXPECT_NEAR(s.stats.enclosed_volume, 8.0, 1e-12);
}

TEST(Readers, EmptyFile) {
  const std::string e = load_error("empty.obj", "");
  EXPECT_TRUE(contains(e, "empty")) << e;
}

TEST(Readers, NotAMesh) {
  const std::string e = load_error("text.off", "hello, this is not a mesh\n");
  EXPECT_FALSE(e.empty());
  EXPECT_TRUE(contains(e, "text.off")) << e;
}

TEST(Readers, UnknownExtensionAndMissingFile) {
  EXPECT_TRUE(contains(load_error("a.xyz", "1 2 3\n"), "unknown surface format"));
  EXPECT_THROW(load_surface("/nonexistent/file.obj"), InputError);
}

std::string binary_stl_tet(std::uint32_t announced, std::size_t keep_triangles) {
  const float p[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  const int f[4][3] = {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {2, 0, 3}};
  std::string s(80, ' ');
  s.append(reinterpret_cast<const char*>(&announced), 4);
  for (std::size_t t = 0; t < keep_triangles; ++t) {
    const float n[3] = {0, 0, 0};
    s.append(reinterpret_cast<const char*>(n), 12);
    for (int k = 0; k < 3; ++k) s.append(reinterpret_cast<const char*>(p[f[t][k]]), 12);
    s.append(2, '\0');
  }
  return s;
}

TEST(Readers, BinaryStlAndTruncatedBinaryStl) {
  TempDir dir;
  write_text(dir.file("tet.stl"), binary_stl_tet(4, 4));
  const LoadedSurface s = load_surface(dir.file("tet.stl"));
  EXPECT_EQ(s.stats.vertices, 4u);  // STL corners are welded by position
  EXPECT_NEAR(s.stats.enclosed_volume, 1.0 / 6.0, 1e-7);
  std::string cut = binary_stl_tet(4, 4);
  cut.resize(cut.size() - 30);
  const std::string e = load_error("cut.stl", cut);
  EXPECT_TRUE(contains(e, "truncated")) << e;
}

TEST(Readers, HostileOffAndObjFilesAreBadInputNamingTheLine) {
  // Headers and face lines that announce more than the file holds: refused before anything is
  // allocated for them, each naming the line.
  const std::string tet_off = "OFF\n4 4 0\n0 0 0\n2 0 0\n0 2 0\n0 0 2\n";
  const std::string tet_faces = "3 0 2 1\n3 0 1 3\n3 1 2 3\n3 2 0 3\n";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"OFF\n", "no vertex and face counts"},
      {"OFF\n100000000 100000000 0\n", "more than the file's"},
      {"OFF\n-5 -3 0\n", "vertex count '-5' (line 2)"},
      {"OFF\n99999999999999999999 1 0\n", "is not a number of elements"},
      {"OFF\n4 x 0\n", "face count 'x'"},
      {"OFF\x8a" + tet_off.substr(3), "not an OFF file: line 1 starts with"},
      {"OFF\n4 4 0\n0 0\n2 0 0\n0 2 0\n0 0 2\n" + tet_faces,
       "vertex 0 (line 3) has fewer than 3 coordinates"},
      {tet_off + "2000000000 0 1 2\n3 0 1 3\n3 1 2 3\n3 2 0 3\n",
       "face 0 (line 7) announces '2000000000' corners but lists 3"},
      {tet_off + "3 0 2 1\n", "announces 4 faces, the file ends after 1"},
      {tet_off + "0 0 2\n3 0 2777777777777 1\n3 1 2 3\n3 2 0 3\n",
       "face 0 (line 7) announces '0' corners"},
      {tet_off + "3 0 2 1\n3 0 9 3\n3 1 2 3\n3 2 0 3\n",
       "face 1 (line 8): out-of-range vertex index '9'"},
      {"OFF\n4 4 0\n0 0 0\n2 0 0\n" + std::string(40, ' ') + "\n",
       "announces 4 vertices, the file ends after 2"},
  };
  for (const auto& [text, want] : cases) {
    const std::string e = load_error("hostile.off", text);
    EXPECT_TRUE(contains(e, want)) << text << "\n-> " << e;
    EXPECT_TRUE(contains(e, "hostile.off: ")) << e;
  }
  EXPECT_EQ(load_error("tet.off", tet_off + tet_faces), "");
  // Counts on the keyword's line, even glued to it, and comments and blank lines in the header
  // (as meshio writes) are read.
  EXPECT_EQ(load_error("same_line.off", "OFF 4 4 0\n" + tet_off.substr(10) + tet_faces), "");
  EXPECT_EQ(load_error("glued.off", "OFF4 4 0\n" + tet_off.substr(10) + tet_faces), "");
  EXPECT_EQ(load_error("meshio.off",
                       "OFF\n# Created by meshio\n\n4 4 0\n\n" + tet_off.substr(10) + tet_faces),
            "");
  // OBJ: an index past the vertices (or 0, or counting back too far) is named, not dropped.
  for (const std::string bad : {"f 1 2 99999999999", "f 1 0 2", "f -1 -2 -9"}) {
    const std::string e = load_error("bad.obj", cube_obj(-1, bad + "\n"));
    EXPECT_TRUE(contains(e, "face 12 (line 21): out-of-range vertex index")) << bad << " -> " << e;
  }
  // Cut short: an OBJ ending inside a face line, a PLY with fewer faces than its header says.
  std::string cut = cube_obj();
  cut.resize(cut.size() - 4);  // "f 4 5 8\n" -> "f 4 "
  EXPECT_TRUE(contains(load_error("cut.obj", cut), "face 11 (line 20) has 1 corners")) << cut;
  const std::string ply =
      "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
      "property float z\nelement face 4\nproperty list uchar int vertex_indices\nend_header\n"
      "0 0 0\n2 0 0\n0 2 0\n0 0 2\n3 0 2 1\n3 0 1 3\n";
  EXPECT_TRUE(contains(load_error("cut.ply", ply),
                       "truncated: the header announces 4 vertices and 4 faces"));
  // Broken PLY headers: refused naming the line.
  const std::string head = ply.substr(0, ply.find("end_header"));
  EXPECT_TRUE(contains(load_error("cut_header.ply", head.substr(0, head.rfind("property") + 9)),
                       "PLY header line 8: not a property of a known type"));
  EXPECT_TRUE(contains(load_error("word.ply", "ply\nforma} ascii 1.0\n" + ply.substr(20)),
                       "PLY header line 2: unknown keyword 'forma}'"));
  // An element the reader does not use (between the vertices and the faces) is skipped.
  std::string camera = ply.substr(0, ply.find("3 0 2 1")) + "5\n" + tet_faces;
  camera.replace(camera.find("element face"), 0, "element camera 1\nproperty float x\n");
  EXPECT_EQ(load_error("camera.ply", camera), "");
  std::string huge = ply;
  huge.replace(huge.find("vertex 4"), 8, "vertex 4000000000");
  EXPECT_TRUE(contains(load_error("huge.ply", huge), "more than the file's"));
  EXPECT_EQ(load_error("relative.obj", std::string(kCubeVertices) + "f -8 -6 -7\n" +
                                           "f 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\n"
                                           "f 2 3 7\nf 2 7 6\nf 3 4 8\nf 3 8 7\nf 4 1 5\n"
                                           "f 4 5 8\n"),
            "");
}

TEST(Readers, PlyTriangleStripsAreRead) {
  // A tetrahedron as one strip (0 2 1 3 0 2), in ASCII, and in big- and little-endian binary
  // followed by a restart (-1) and a strip whose one triangle is degenerate (skipped).
  const std::string head =
      "ply\nformat FORMAT 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
      "property float z\nelement tristrips 1\nproperty list int int vertex_indices\n"
      "end_header\n";
  const auto with_format = [&](const std::string& format) {
    std::string h = head;
    h.replace(h.find("FORMAT"), 6, format);
    return h;
  };
  const auto check = [&](const std::string& name, const std::string& text) {
    TempDir dir;
    write_text(dir.file(name), text);
    const LoadedSurface s = load_surface(dir.file(name));
    EXPECT_EQ(s.mesh.triangles.size(), 4u) << name;
    EXPECT_NEAR(s.stats.enclosed_volume, 8.0 / 6.0, 1e-12) << name;
    EXPECT_FALSE(s.flipped) << name;
  };
  check("ascii.ply", with_format("ascii") + "0 0 0\n2 0 0\n0 2 0\n0 0 2\n6 0 2 1 3 0 2\n");
  for (const bool big : {false, true}) {
    std::string bytes = with_format(big ? "binary_big_endian" : "binary_little_endian");
    const auto put = [&](const void* p) {
      const char* c = static_cast<const char*>(p);
      std::string four(c, c + 4);
      if (big) std::reverse(four.begin(), four.end());
      bytes += four;
    };
    for (const float f : {0.f, 0.f, 0.f, 2.f, 0.f, 0.f, 0.f, 2.f, 0.f, 0.f, 0.f, 2.f}) put(&f);
    // The same strip, a restart (-1) and a strip 1 1 2 whose one triangle repeats 1: skipped.
    for (const int i : {10, 0, 2, 1, 3, 0, 2, -1, 1, 1, 2}) put(&i);
    check(big ? "big.ply" : "little.ply", bytes);
  }
}

TEST(Readers, AsciiStlOffPlyAgree) {
  TempDir dir;
  write_text(dir.file("t.stl"),
             "solid t\n"
             "facet normal 0 0 -1\nouter loop\n"
             "vertex 0 0 0\nvertex 0 1 0\nvertex 1 0 0\nendloop\nendfacet\n"
             "facet normal 0 -1 0\nouter loop\n"
             "vertex 0 0 0\nvertex 1 0 0\nvertex 0 0 1\nendloop\nendfacet\n"
             "facet normal 1 1 1\nouter loop\n"
             "vertex 1 0 0\nvertex 0 1 0\nvertex 0 0 1\nendloop\nendfacet\n"
             "facet normal -1 0 0\nouter loop\n"
             "vertex 0 1 0\nvertex 0 0 0\nvertex 0 0 1\nendloop\nendfacet\n"
             "endsolid t\n");
  write_text(dir.file("t.off"),
             "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n"
             "3 0 2 1\n3 0 1 3\n3 1 2 3\n3 2 0 3\n");
  write_text(dir.file("t.ply"),
             "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
             "property float z\nelement face 4\nproperty list uchar int vertex_indices\n"
             "end_header\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 1 2 3\n3 2 0 3\n");
  for (const char* name : {"t.stl", "t.off", "t.ply"}) {
    const LoadedSurface s = load_surface(dir.file(name));
    EXPECT_EQ(s.stats.faces, 4u) << name;
    EXPECT_NEAR(s.stats.enclosed_volume, 1.0 / 6.0, 1e-7) << name;
  }
}

TEST(Readers, ObjAndOffKeepDoublePrecision) {
  TempDir dir;
  write_text(dir.file("t.obj"),
             "v 0.12345678901234567 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n"
             "f 1 3 2\nf 1 2 4\nf 2 3 4\nf 3 1 4\n");
  EXPECT_EQ(read_polygon_soup(dir.file("t.obj")).points[0].x, 0.12345678901234567);
  write_text(dir.file("t.off"),
             "OFF\n4 4 0\n0.12345678901234567 0 0\n1 0 0\n0 1 0\n0 0 1\n"
             "3 0 2 1\n3 0 1 3\n3 1 2 3\n3 2 0 3\n");
  EXPECT_EQ(read_polygon_soup(dir.file("t.off")).points[0].x, 0.12345678901234567);
}

// The shared corpus, classified as ../shared/meshes/README.md says.
TEST(Corpus, SharedMeshesClassifiedAsDocumented) {
  const auto dir = test::shared_meshes_dir();
  if (dir.empty()) GTEST_SKIP() << "../shared/meshes is absent";
  struct Expect {
    const char* file;
    bool valid;
    std::size_t faces;
    int genus;
  };
  const Expect expected[] = {
      {"fandisk.obj", true, 12946, 0},  {"decimated-knight.off", true, 1000, 0},
      {"fertility.off", true, 9000, 4}, {"spot.obj", true, 5856, 0},
      {"suzanne.obj", false, 0, 0},     {"teapot.obj", false, 0, 0}};
  for (const Expect& e : expected) {
    const std::string path = (dir / e.file).string();
    if (e.valid) {
      const LoadedSurface s = load_surface(path);
      EXPECT_EQ(s.stats.faces, e.faces) << e.file;
      EXPECT_EQ(s.stats.genus, e.genus) << e.file;
      EXPECT_EQ(s.stats.components, 1u) << e.file;
      EXPECT_GT(s.stats.enclosed_volume, 0.0) << e.file;
      EXPECT_FALSE(s.flipped) << e.file;
    } else {
      try {
        load_surface(path);
        ADD_FAILURE() << e.file << " was accepted";
      } catch (const InputError& err) {
        EXPECT_TRUE(contains(err.what(), "boundary edges")) << err.what();
      }
    }
  }
  // The README's exact counts for the two broken meshes.
  const auto suzanne = find_surface_problems(read_polygon_soup((dir / "suzanne.obj").string()));
  std::size_t boundary = 0, nm_edges = 0, dup = 0;
  for (const auto& p : suzanne) {
    if (contains(p.rule, "boundary")) boundary = p.count;
    if (contains(p.rule, "non-manifold edges")) nm_edges = p.count;
    if (contains(p.rule, "duplicate")) dup = p.count;
  }
  EXPECT_EQ(boundary, 42u);
  EXPECT_EQ(nm_edges, 1u);
  EXPECT_EQ(dup, 1u);
  const auto teapot = find_surface_problems(read_polygon_soup((dir / "teapot.obj").string()));
  std::size_t teapot_boundary = 0, teapot_nm_vertices = 0;
  for (const auto& p : teapot) {
    if (contains(p.rule, "boundary")) teapot_boundary = p.count;
    if (contains(p.rule, "non-manifold vertices")) teapot_nm_vertices = p.count;
  }
  EXPECT_EQ(teapot_boundary, 1036u);
  EXPECT_EQ(teapot_nm_vertices, 38u);
}

}  // namespace
}  // namespace vdb_shell
