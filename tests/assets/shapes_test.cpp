// shapes_test.cpp — the procedural test shapes (assets/shapes.h) and vdb_shell_shapes.
//
// Every shape at detail 1 and 2 must be a valid input of the pipeline: no problem reported by
// find_surface_problems(), every directed edge used once and its reverse once (checked here too,
// independently of the validator), positive volume, the expected genus, no sliver, no two
// triangles intersecting. Analytic checks where they are cheap: exact box volume, sphere radius,
// prism volumes of the cylinder, tube and star, the bowl's and funnel's wall thickness.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <map>
#include <ostream>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "assets/shapes.h"
#include "core/base/errors.h"
#include "core/base/surface_mesh.h"
#include "core/base/vec3.h"
#include "core/read/load_surface.h"
#include "core/read/polygon_soup.h"
#include "tests/test_support.h"

namespace vdb_shell {
namespace {

struct Expected {
  const char* name;
  int genus;
  int paper_faces;  ///< Table 1 of the paper; 0 when the paper has no such shape
};

/// GetParam() in test listings and failure messages: "horn (genus 0, paper 408 faces)".
void PrintTo(const Expected& e, std::ostream* os) {
  *os << e.name << " (genus " << e.genus << ", ";
  if (e.paper_faces > 0)
    *os << "paper " << e.paper_faces << " faces)";
  else
    *os << "not in the paper)";
}

const Expected kExpected[] = {
    {"box", 0, 48},   {"cylinder", 0, 48}, {"sphere", 0, 760},     {"tube", 1, 512},
    {"torus", 1, 0},  {"bowl", 0, 2680},   {"funnel", 1, 1280},    {"star", 0, 588},
    {"horn", 0, 408}, {"pointy", 0, 96},   {"propeller", 0, 1200}, {"flap", 0, 0},
};

std::string describe(const std::vector<SurfaceProblem>& problems) {
  std::string out;
  for (const SurfaceProblem& p : problems) {
    out += p.rule + " (" + std::to_string(p.count) + "): " + p.first + "; ";
  }
  return out;
}

/// Number of directed edges that are not used exactly once with their reverse used exactly once
/// (0 for a closed, 2-manifold, consistently oriented surface).
std::size_t bad_directed_edges(const SurfaceMesh& mesh) {
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> directed;
  for (const Triangle& t : mesh.triangles) {
    for (int k = 0; k < 3; ++k) ++directed[{t[k], t[(k + 1) % 3]}];
  }
  std::size_t bad = 0;
  for (const auto& [edge, count] : directed) {
    const auto reverse = directed.find({edge.second, edge.first});
    if (count != 1 || reverse == directed.end() || reverse->second != 1) ++bad;
  }
  return bad;
}

/// V - E + F, counting only vertices some triangle uses.
long euler_characteristic(const SurfaceMesh& mesh) {
  std::set<std::pair<std::uint32_t, std::uint32_t>> edges;
  std::set<std::uint32_t> vertices;
  for (const Triangle& t : mesh.triangles) {
    for (int k = 0; k < 3; ++k) {
      vertices.insert(t[k]);
      edges.insert(std::minmax(t[k], t[(k + 1) % 3]));
    }
  }
  return static_cast<long>(vertices.size()) - static_cast<long>(edges.size()) +
         static_cast<long>(mesh.num_faces());
}

double triangle_area(const SurfaceMesh& mesh, std::size_t f) {
  return 0.5 * norm(face_normal_area(mesh, f));
}

// The checks above must be able to fail.
TEST(ShapesSelfCheck, IntersectionTestSeesCrossingsAndNotNeighbours) {
  const std::array<Vec3d, 3> flat = {Vec3d{0, 0, 0}, Vec3d{1, 0, 0}, Vec3d{0, 1, 0}};
  const std::array<Vec3d, 3> piercing = {Vec3d{0.2, 0.2, -1}, Vec3d{0.3, 0.2, 1},
                                         Vec3d{0.2, 0.3, 1}};
  const std::array<Vec3d, 3> above = {Vec3d{0.2, 0.2, 0.1}, Vec3d{0.3, 0.2, 1}, Vec3d{0.2, 0.3, 1}};
  const std::array<Vec3d, 3> overlapping = {Vec3d{0.2, 0.2, 0}, Vec3d{1.2, 0.2, 0},
                                            Vec3d{0.2, 1.2, 0}};
  const std::array<Vec3d, 3> beside = {Vec3d{1, 1, 0}, Vec3d{2, 1, 0}, Vec3d{1, 2, 0}};
  EXPECT_TRUE(test::triangles_intersect(flat, piercing));
  EXPECT_FALSE(test::triangles_intersect(flat, above));
  EXPECT_TRUE(test::triangles_intersect(flat, overlapping));
  EXPECT_FALSE(test::triangles_intersect(flat, beside));
  // Two boxes overlapping in space, and one box with a face folded over its neighbour.
  SurfaceMesh two = make_shape("box");
  const SurfaceMesh other = make_shape("box");
  const auto offset = static_cast<std::uint32_t>(two.num_vertices());
  for (const Vec3d& p : other.points) two.points.push_back(p + Vec3d{0.3, 0.2, 0.1});
  for (Triangle t : other.triangles) {
    for (std::uint32_t& v : t) v += offset;
    two.triangles.push_back(t);
  }
  EXPECT_FALSE(test::self_intersections(two).empty());
  SurfaceMesh folded = make_shape("box", 2);
  const std::uint32_t corner = folded.triangles[5][1];
  // Push a vertex out through the opposite side, off the lattice (the test counts proper
  // crossings, not contacts exactly along edges).
  folded.points[corner] = folded.points[corner] * -1.5 + Vec3d{0.013, 0.029, 0.041};
  EXPECT_FALSE(test::self_intersections(folded).empty());
}

TEST(ShapesSelfCheck, ValidatorSeesAFlippedTriangle) {
  SurfaceMesh mesh = make_shape("tube");
  std::swap(mesh.triangles[7][0], mesh.triangles[7][1]);
  EXPECT_FALSE(find_surface_problems(polygon_soup_of(mesh)).empty());
  EXPECT_GT(bad_directed_edges(mesh), 0u);
}

// ---- tests over every shape ------------------------------------------------------------------

class ShapesEveryShape : public ::testing::TestWithParam<Expected> {};

TEST_P(ShapesEveryShape, IsAValidClosedSurfaceAtDetailOneAndTwo) {
  const Expected& e = GetParam();
  for (int detail : {1, 2}) {
    SCOPED_TRACE(std::string(e.name) + " detail " + std::to_string(detail));
    const SurfaceMesh mesh = make_shape(e.name, detail);
    ASSERT_GT(mesh.num_faces(), 0u);
    const auto problems = find_surface_problems(polygon_soup_of(mesh));
    EXPECT_TRUE(problems.empty()) << describe(problems);
    EXPECT_EQ(bad_directed_edges(mesh), 0u);
    EXPECT_GT(signed_volume(mesh), 0.0);
    EXPECT_EQ(euler_characteristic(mesh), 2 - 2 * e.genus);
    // Every vertex is used (the validator would drop unused ones with a notice).
    std::vector<bool> used(mesh.num_vertices(), false);
    for (const Triangle& t : mesh.triangles) {
      for (std::uint32_t v : t) used[v] = true;
    }
    EXPECT_EQ(std::count(used.begin(), used.end(), false), 0);
    // Fits the unit cube centred at the origin (up to the walls' half thickness).
    const BBox box = bounding_box(mesh);
    for (int a = 0; a < 3; ++a) {
      EXPECT_GE(box.lo[a], -0.5 - 1e-2);
      EXPECT_LE(box.hi[a], 0.5 + 1e-2);
    }
    EXPECT_GT(box.max_side(), 0.85);
    // No sliver: no triangle much smaller than the mean.
    double total = 0.0, smallest = INFINITY;
    for (std::size_t f = 0; f < mesh.num_faces(); ++f) {
      const double area = triangle_area(mesh, f);
      total += area;
      smallest = std::min(smallest, area);
    }
    EXPECT_GT(smallest, 1e-3 * total / static_cast<double>(mesh.num_faces()));
  }
}

TEST_P(ShapesEveryShape, HasNoSelfIntersections) {
  const Expected& e = GetParam();
  for (int detail : {1, 2}) {
    SCOPED_TRACE(std::string(e.name) + " detail " + std::to_string(detail));
    const SurfaceMesh mesh = make_shape(e.name, detail);
    const auto hits = test::self_intersections(mesh);
    EXPECT_TRUE(hits.empty()) << hits.size() << " intersecting pairs, first: triangles "
                              << hits.front().first << " and " << hits.front().second;
  }
}

TEST_P(ShapesEveryShape, MatchesThePaperAndGrowsWithDetail) {
  const Expected& e = GetParam();
  const std::size_t f1 = make_shape(e.name, 1).num_faces();
  const std::size_t f2 = make_shape(e.name, 2).num_faces();
  const std::size_t f3 = make_shape(e.name, 3).num_faces();
  if (e.paper_faces > 0) {
    EXPECT_NEAR(static_cast<double>(f1), e.paper_faces, 0.1 * e.paper_faces);
  }
  // About detail^2 times the faces.
  EXPECT_GE(static_cast<double>(f2), 3.5 * static_cast<double>(f1));
  EXPECT_LE(static_cast<double>(f2), 4.5 * static_cast<double>(f1));
  EXPECT_GE(static_cast<double>(f3), 8.0 * static_cast<double>(f1));
  EXPECT_LE(static_cast<double>(f3), 10.0 * static_cast<double>(f1));
}

TEST_P(ShapesEveryShape, IsDeterministic) {
  const Expected& e = GetParam();
  const SurfaceMesh a = make_shape(e.name, 2), b = make_shape(e.name, 2);
  EXPECT_EQ(a.triangles, b.triangles);
  ASSERT_EQ(a.points.size(), b.points.size());
  for (std::size_t v = 0; v < a.points.size(); ++v) ASSERT_EQ(a.points[v], b.points[v]) << v;
}

INSTANTIATE_TEST_SUITE_P(Shapes, ShapesEveryShape, ::testing::ValuesIn(kExpected),
                         [](const ::testing::TestParamInfo<Expected>& info) {
                           return std::string(info.param.name);
                         });

// ---- catalogue and errors --------------------------------------------------------------------

TEST(ShapesCatalog, ListsEveryShapeWithItsDetailOneFaceCount) {
  const auto& catalog = shape_catalog();
  ASSERT_EQ(catalog.size(), std::size(kExpected));
  std::set<std::string> names;
  for (const ShapeInfo& info : catalog) {
    names.insert(info.name);
    EXPECT_FALSE(info.description.empty()) << info.name;
    EXPECT_EQ(make_shape(info.name).num_faces(), static_cast<std::size_t>(info.default_faces))
        << info.name;
  }
  for (const Expected& e : kExpected) EXPECT_EQ(names.count(e.name), 1u) << e.name;
}

TEST(ShapesErrors, UnknownNameThrowsInputErrorNamingTheShapes) {
  try {
    make_shape("dodecahedron");
    FAIL() << "no exception";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("dodecahedron"), std::string::npos) << what;
    for (const Expected& s : kExpected) EXPECT_NE(what.find(s.name), std::string::npos) << what;
  }
  EXPECT_THROW(make_shape(""), InputError);
  EXPECT_THROW(make_shape("Box"), InputError);
}

TEST(ShapesErrors, DetailOutOfRangeThrowsInputError) {
  EXPECT_THROW(make_shape("box", 0), InputError);
  EXPECT_THROW(make_shape("box", -3), InputError);
  EXPECT_THROW(make_shape("box", kMaxShapeDetail + 1), InputError);
}

// ---- analytic checks -------------------------------------------------------------------------

TEST(ShapesAnalytic, BoxIsTheUnitCubeAndReachesOneHundredThousandFaces) {
  for (int detail : {1, 3}) {
    const SurfaceMesh box = make_shape("box", detail);
    const int n = 2 * detail;
    EXPECT_EQ(box.num_faces(), static_cast<std::size_t>(12 * n * n));
    EXPECT_EQ(box.num_vertices(), static_cast<std::size_t>(6 * n * n + 2));
    EXPECT_NEAR(signed_volume(box), 1.0, 1e-12);
    for (const Vec3d& p : box.points) {
      const double m = std::max({std::fabs(p.x), std::fabs(p.y), std::fabs(p.z)});
      EXPECT_DOUBLE_EQ(m, 0.5);
    }
  }
  const SurfaceMesh big = make_shape("box", 46);
  EXPECT_GE(big.num_faces(), 100000u);
  EXPECT_EQ(big.num_faces(), 101568u);
  EXPECT_NEAR(signed_volume(big), 1.0, 1e-10);
}

TEST(ShapesAnalytic, SphereVerticesLieOnTheRadius) {
  for (int detail : {1, 2}) {
    const SurfaceMesh sphere = make_shape("sphere", detail);
    EXPECT_EQ(sphere.num_faces(), static_cast<std::size_t>(800 * detail * detail - 40 * detail));
    for (const Vec3d& p : sphere.points) EXPECT_NEAR(norm(p), 0.5, 1e-14);
    // Inscribed polyhedron: a little less than the ball's volume.
    const double ball = 4.0 / 3.0 * kPi * 0.125;
    EXPECT_LT(signed_volume(sphere), ball);
    EXPECT_GT(signed_volume(sphere), 0.95 * ball);
  }
}

/// Area of the regular polygon with `sides` corners on the circle of radius r.
double polygon_area(int sides, double r) { return 0.5 * sides * r * r * std::sin(2 * kPi / sides); }

TEST(ShapesAnalytic, PrismVolumesAreExact) {
  for (int detail : {1, 2}) {
    EXPECT_NEAR(signed_volume(make_shape("cylinder", detail)), polygon_area(8 * detail, 0.5) * 1.0,
                1e-12);
    EXPECT_NEAR(signed_volume(make_shape("tube", detail)),
                (polygon_area(16 * detail, 0.5) - polygon_area(16 * detail, 0.3)) * 1.0, 1e-12);
    // Star {5/2}: ten triangles (centre, tip, notch) of sides R and r at 36 degrees.
    const double r = 0.5 * std::cos(0.4 * kPi) / std::cos(0.2 * kPi);
    const double star_area = 10 * 0.5 * 0.5 * r * std::sin(0.2 * kPi);
    EXPECT_NEAR(signed_volume(make_shape("star", detail)), star_area * 0.3, 1e-12);
  }
}

TEST(ShapesAnalytic, BowlHasAThinWall) {
  // Every vertex lies on the outer sphere (radius 0.5), the inner one (0.47), both centred on
  // the rim's centre (0, 0, 0.25), or on the rim plane between them: the wall is 3% of the size.
  for (int detail : {1, 2}) {
    const SurfaceMesh bowl = make_shape("bowl", detail);
    const Vec3d centre{0.0, 0.0, 0.25};
    for (const Vec3d& p : bowl.points) {
      const double d = norm(p - centre);
      const bool on_sphere = std::fabs(d - 0.5) < 1e-12 || std::fabs(d - 0.47) < 1e-12;
      const bool on_rim = p.z == 0.25 && d >= 0.47 - 1e-12 && d <= 0.5 + 1e-12;
      EXPECT_TRUE(on_sphere || on_rim) << p.x << ' ' << p.y << ' ' << p.z;
    }
    const double shell = 2.0 / 3.0 * kPi * (0.125 - 0.47 * 0.47 * 0.47);
    EXPECT_NEAR(signed_volume(bowl), shell, 0.03 * shell);
  }
}

TEST(ShapesAnalytic, FunnelHasAThinWall) {
  // Volume of a 0.03 thick wall around the mid-surface (Pappus), for the 32N-gon cross-section.
  const double neck = 2 * kPi * 0.1 * 0.35;
  const double cone = 2 * kPi * 0.5 * (0.1 + 0.485) * std::hypot(0.385, 0.65);
  for (int detail : {1, 2}) {
    const double angle = 2 * kPi / (32 * detail);
    const double expected = 0.03 * (neck + cone) * std::sin(angle) / angle;
    EXPECT_NEAR(signed_volume(make_shape("funnel", detail)), expected, 0.03 * expected);
  }
}

// ---- the executable --------------------------------------------------------------------------

std::ptrdiff_t count_entries(const std::filesystem::path& dir) {
  const std::filesystem::directory_iterator it(dir);
  return std::distance(begin(it), end(it));
}

TEST(ShapesTool, WritesAReadableObj) {
  test::TempDir dir;
  const std::string out = dir.file("horn.obj");
  const auto r =
      test::run_command("'" + test::vdb_shell_shapes_bin() + "' horn -o '" + out + "' --detail 2");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("horn"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("1656"), std::string::npos) << r.out;
  const PolygonSoup soup = read_polygon_soup(out);
  const SurfaceMesh mesh = make_shape("horn", 2);
  ASSERT_EQ(soup.points.size(), mesh.num_vertices());
  ASSERT_EQ(soup.polygons.size(), mesh.num_faces());
  for (std::size_t v = 0; v < mesh.num_vertices(); ++v) {
    EXPECT_NEAR(norm(soup.points[v] - mesh.points[v]), 0.0, 1e-15) << v;
  }
  const auto problems = find_surface_problems(soup);
  EXPECT_TRUE(problems.empty()) << describe(problems);
  // Only the OBJ is left: no temporary file.
  EXPECT_EQ(count_entries(dir.path()), 1);
}

TEST(ShapesTool, BadInputExitsTwoAndWritesNothing) {
  test::TempDir dir;
  const std::string bin = "'" + test::vdb_shell_shapes_bin() + "'";
  const std::string out = dir.file("x.obj");
  for (const std::string& args :
       {std::string("dodecahedron -o '") + out + "'",
        std::string("box --detail 0 -o '") + out + "'",
        std::string("box --detail many -o '") + out + "'", std::string("box"),
        std::string("box -o '") + dir.file("missing/x.obj") + "'"}) {
    SCOPED_TRACE(args);
    const auto r = test::run_command(bin + " " + args);
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_FALSE(r.err.empty());
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_EQ(count_entries(dir.path()), 0);
  }
}

TEST(ShapesTool, ListsTheShapes) {
  const auto r = test::run_command("'" + test::vdb_shell_shapes_bin() + "' --list");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const ShapeInfo& s : shape_catalog()) {
    EXPECT_NE(r.out.find(s.name), std::string::npos) << s.name;
    EXPECT_NE(r.out.find(std::to_string(s.default_faces)), std::string::npos) << s.name;
  }
  const auto help = test::run_command("'" + test::vdb_shell_shapes_bin() + "' --help");
  EXPECT_EQ(help.exit_code, 0);
  EXPECT_NE(help.out.find("--detail"), std::string::npos) << help.out;
}

}  // namespace
}  // namespace vdb_shell
