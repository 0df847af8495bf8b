// repair_test.cpp — vdb_ops/repair.h and load_repaired_surface() on broken inputs made here from
// the shapes (punched holes, seams stored twice, two overlapping parts, an open sheet, a clean
// sphere) and the shared meshes, each checked by computations of the test's own: the repaired
// surface validates (closed, 2-manifold, not crossing itself), its distances to the input by
// brute force over point-triangle pairs, and its enclosed volume.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "assets/shapes.h"
#include "core/base/errors.h"
#include "core/base/geometry.h"
#include "core/read/load_surface.h"
#include "tests/test_support.h"
#include "vdb_ops/repair.h"
#include "vdb_shell/vdb_shell.h"

namespace vdb_shell {
namespace {

/// Largest distance from the points of `from` to the triangles of `to`, by brute force.
double max_distance(const std::vector<Vec3d>& from, const PolygonSoup& to) {
  double worst = 0;
  for (const Vec3d& p : from) {
    double best = INFINITY;
    for (const auto& f : to.polygons)
      for (std::size_t k = 1; k + 1 < f.size(); ++k)
        best = std::min(best, point_triangle_distance2(p, to.points[std::size_t(f[0])],
                                                       to.points[std::size_t(f[k])],
                                                       to.points[std::size_t(f[k + 1])]));
    worst = std::max(worst, std::sqrt(best));
  }
  return worst;
}

/// What test_support's independent check finds wrong with the shell of `surface` at
/// `resolution` ("" for none).
std::string shell_problems(const SurfaceMesh& surface, int resolution, double* coverage = nullptr) {
  ShellOptions options;
  options.fields.resolution = resolution;
  const ShellResult shell = build_shell(surface, options);
  if (coverage) *coverage = test::independent_coverage(surface, shell.mesh);
  return test::independent_shell_problems(surface, shell.mesh, 2 * shell.validity.sectors);
}

struct Repaired {
  LoadedSurface surface;
  RepairReport report;
  double h = 0;
};

Repaired repair(const PolygonSoup& soup, int resolution = 48, double closing = 2.0,
                double adaptivity = 0.0) {
  ShellOptions options;
  options.fields.resolution = resolution;
  options.repair = true;
  options.repair_closing = closing;
  options.adaptivity = adaptivity;
  Repaired r;
  r.surface = load_repaired_surface(soup, "test", options, r.report);
  r.h = r.report.voxel_size;
  return r;
}

TEST(Repair, ACleanSurfaceIsKeptAsItIs) {
  const SurfaceMesh sphere = make_shape("sphere");
  const Repaired r = repair(polygon_soup_of(sphere));
  EXPECT_TRUE(r.report.kept);
  EXPECT_EQ(r.surface.mesh.points, sphere.points);
  EXPECT_EQ(r.surface.mesh.triangles, sphere.triangles);
  EXPECT_EQ(r.report.faces, sphere.triangles.size());
  EXPECT_EQ(r.report.distance_max, 0.0);
  EXPECT_EQ(r.report.input_distance_max, 0.0);
}

TEST(Repair, ACleanSphereRebuiltStaysWithinAVoxel) {
  // The volume path itself (repair_surface(), which load_repaired_surface() skips for a clean
  // input) on the clean sphere at 48 voxels across.
  const SurfaceMesh sphere = make_shape("sphere");
  const PolygonSoup input = polygon_soup_of(sphere);
  RepairOptions options;
  options.voxel_size = bounding_box(sphere).max_side() / 48;
  RepairReport report;
  const LoadedSurface rebuilt =
      make_surface(repair_surface(input, options, "sphere", report), "sphere (repaired)");
  const double h = options.voxel_size;
  EXPECT_FALSE(report.kept);
  EXPECT_EQ(rebuilt.stats.components, 1u);
  EXPECT_EQ(rebuilt.stats.genus, 0);
  EXPECT_EQ(report.holes_closed, 0u);
  const double out = max_distance(rebuilt.mesh.points, input);
  const double back = max_distance(input.points, polygon_soup_of(rebuilt.mesh));
  EXPECT_LT(out, 1.0 * h) << out / h << " voxels";
  EXPECT_LT(back, 1.0 * h) << back / h << " voxels";
  // The report's sampled distances agree with the brute force.
  EXPECT_NEAR(report.distance_max, out, 0.25 * h);
  EXPECT_NEAR(report.input_distance_max, back, 0.25 * h);
  const double volume = make_surface(input, "sphere").stats.enclosed_volume;
  EXPECT_NEAR(rebuilt.stats.enclosed_volume, volume, 0.02 * volume);
}

TEST(Repair, PunchedHolesAreCapped) {
  // Two faces of the sphere removed, far apart: two triangular holes, edges of about 4 voxels at
  // resolution 48, which a closing of 3 voxels caps.
  const SurfaceMesh sphere = make_shape("sphere");
  PolygonSoup input = polygon_soup_of(sphere);
  input.polygons.erase(input.polygons.begin() + 500);
  input.polygons.erase(input.polygons.begin() + 100);
  EXPECT_THROW(make_surface(input, "holes"), InputError);
  const Repaired r = repair(input, 48, 3.0);
  EXPECT_EQ(r.report.holes_closed, 2u);
  EXPECT_EQ(r.surface.stats.components, 1u);
  EXPECT_EQ(r.surface.stats.genus, 0);
  EXPECT_LT(max_distance(r.surface.mesh.points, input), (3.0 + 1.0) * r.h);
  EXPECT_LT(max_distance(input.points, polygon_soup_of(r.surface.mesh)), 1.0 * r.h);
  const double volume = make_surface(polygon_soup_of(sphere), "sphere").stats.enclosed_volume;
  EXPECT_NEAR(r.surface.stats.enclosed_volume, volume, 0.03 * volume);
}

TEST(Repair, ATinyInputIsRepairedAsItselfScaledExactly) {
  // The punched sphere at 2^-30 (~1e-9 across): its volume's voxels are below the smallest
  // OpenVDB accepts, so it is repaired at its own size and scaled back — the same surface, to the
  // bit, and the report's lengths scaled.
  PolygonSoup input = polygon_soup_of(make_shape("sphere"));
  input.polygons.erase(input.polygons.begin() + 500);
  const double s = std::ldexp(1.0, -30);
  PolygonSoup tiny = input;
  for (Vec3d& p : tiny.points) p *= s;
  const Repaired big = repair(input, 48, 3.0), r = repair(tiny, 48, 3.0);
  ASSERT_EQ(r.surface.mesh.triangles, big.surface.mesh.triangles);
  ASSERT_EQ(r.surface.mesh.points.size(), big.surface.mesh.points.size());
  for (std::size_t i = 0; i < r.surface.mesh.points.size(); ++i)
    ASSERT_EQ(r.surface.mesh.points[i], big.surface.mesh.points[i] * s) << i;
  EXPECT_EQ(r.report.voxel_size, big.report.voxel_size * s);
  EXPECT_EQ(r.report.distance_max, big.report.distance_max * s);
  EXPECT_EQ(r.report.input_distance_max, big.report.input_distance_max * s);
  EXPECT_EQ(r.report.solid_input_distance_max, big.report.solid_input_distance_max * s);
  EXPECT_EQ(r.report.holes_closed, 1u);
  EXPECT_LT(max_distance(tiny.points, polygon_soup_of(r.surface.mesh)), 1.0 * r.h);
}

TEST(Repair, SeamsStoredTwiceAndOverlappingPartsBecomeOneSolid) {
  // Each triangle with corners of its own (an STL-like soup), and a second sphere moved by a
  // radius: two overlapping parts. The repair is their union: one component whose volume lies
  // between one sphere's and two.
  const SurfaceMesh sphere = make_shape("sphere");
  PolygonSoup input;
  for (int copy = 0; copy < 2; ++copy)
    for (const auto& t : sphere.triangles) {
      std::vector<std::int64_t> f;
      for (int k = 0; k < 3; ++k) {
        input.points.push_back(sphere.points[std::size_t(t[k])] + Vec3d{0.5 * copy, 0, 0});
        f.push_back(std::int64_t(input.points.size()) - 1);
      }
      input.polygons.push_back(f);
    }
  EXPECT_THROW(make_surface(input, "soup"), InputError);
  const Repaired r = repair(input);
  EXPECT_EQ(r.surface.stats.components, 1u);
  EXPECT_EQ(r.surface.stats.genus, 0);
  const double one = 4.0 / 3.0 * M_PI * 0.125;
  EXPECT_GT(r.surface.stats.enclosed_volume, 1.3 * one);
  EXPECT_LT(r.surface.stats.enclosed_volume, 1.9 * one);
  EXPECT_LT(max_distance(r.surface.mesh.points, input), 1.5 * r.h);
}

TEST(Repair, AnOpenSheetBecomesAThinSlab) {
  PolygonSoup sheet;
  sheet.points = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  sheet.polygons = {{0, 1, 2, 3}};
  const Repaired r = repair(sheet, 32);
  EXPECT_EQ(r.surface.stats.components, 1u);
  double lo = INFINITY, hi = -INFINITY;
  for (const Vec3d& p : r.surface.mesh.points) lo = std::min(lo, p.z), hi = std::max(hi, p.z);
  EXPECT_GT(hi - lo, 0.5 * r.h);  // a solid, about the closing (2 voxels) thick
  EXPECT_LT(hi - lo, 4.0 * r.h);
}

TEST(Repair, TheSolidFiguresLeaveOutAnOpenSheet) {
  // A closed box and, apart from it, an open sheet: the sheet becomes a slab with the sheet
  // inside it, more than a voxel from the slab's faces, while the box is rebuilt within a voxel.
  // The report's solid figures cover the box's vertices only; all figures agree with the brute
  // force over each part's vertices.
  const SurfaceMesh box = make_shape("box", 2);
  PolygonSoup input = polygon_soup_of(box);
  const std::size_t box_points = input.points.size();
  const int n = 6;  // the sheet: n x n quads over [0.8, 1.6] x {0} x [-0.4, 0.4]
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i)
      input.points.push_back({0.8 + 0.8 * i / n, 0.0, -0.4 + 0.8 * j / n});
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const std::int64_t a = std::int64_t(box_points) + j * (n + 1) + i;
      input.polygons.push_back({a, a + 1, a + n + 2, a + n + 1});
    }
  const Repaired r = repair(input, 48);
  const PolygonSoup repaired = polygon_soup_of(r.surface.mesh);
  const std::vector<Vec3d> box_part(input.points.begin(), input.points.begin() + box_points),
      sheet_part(input.points.begin() + box_points, input.points.end());
  const double on_box = max_distance(box_part, repaired),
               on_sheet = max_distance(sheet_part, repaired);
  EXPECT_LT(on_box, 1.0 * r.h) << on_box / r.h << " voxels";
  EXPECT_GT(on_sheet, 1.0 * r.h) << on_sheet / r.h << " voxels";
  EXPECT_EQ(r.report.solid_input_points, box_points);
  EXPECT_NEAR(r.report.solid_input_distance_max, on_box, 0.25 * r.h);
  EXPECT_NEAR(r.report.input_distance_max, on_sheet, 0.25 * r.h);
}

TEST(Repair, NothingToRepairAndTooLargeAClosingAreBadInput) {
  PolygonSoup line;
  line.points = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}};
  line.polygons = {{0, 1, 2}};
  try {
    repair(line);
    ADD_FAILURE() << "a degenerate input was repaired";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("test"), std::string::npos) << e.what();
  }
  PolygonSoup none;
  none.points = {{0, 0, 0}};
  none.polygons = {{0, 5, 7}};
  EXPECT_THROW(repair(none), InputError);
  PolygonSoup holed =
      polygon_soup_of(make_shape("sphere"));  // a clean one is kept, whatever the closing
  holed.polygons.pop_back();
  try {
    repair(holed, 48, 20.0);
    ADD_FAILURE() << "a closing of 20 voxels on a 48-voxel model was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("use at most 12"), std::string::npos) << e.what();
  }
}

TEST(Repair, TwentyRandomDefectMixesGiveValidSurfaces) {
  // Shapes with 2 to 4 defects drawn at random (seeded): holes, flipped faces, an offset copy
  // overlapping the original, vertices pushed through the far side (folds), a loose sheet, a
  // duplicated face, every triangle with corners of its own. Each is refused as it is (but for
  // mixes that loading mends) and repaired into a valid surface; every fifth is shelled and
  // checked independently.
  const char* shapes[] = {"sphere", "torus", "box", "horn", "star"};
  std::mt19937 rng(2026);
  const auto pick = [&](int n) { return std::uniform_int_distribution<int>(0, n - 1)(rng); };
  for (int mix = 0; mix < 20; ++mix) {
    const SurfaceMesh shape = make_shape(shapes[pick(5)]);
    PolygonSoup soup = polygon_soup_of(shape);
    std::vector<int> defects = {0, 1, 2, 3, 4, 5, 6};
    std::shuffle(defects.begin(), defects.end(), rng);
    defects.resize(std::size_t(2 + pick(3)));
    std::string what;
    for (const int d : defects) {
      if (d == 0) {
        what += " holes";
        for (int k = 1 + pick(4); k > 0; --k)
          soup.polygons.erase(soup.polygons.begin() + pick(int(soup.polygons.size())));
      } else if (d == 1) {
        what += " flips";
        for (std::size_t k = 0; k < soup.polygons.size(); k += 17)
          std::reverse(soup.polygons[k].begin(), soup.polygons[k].end());
      } else if (d == 2) {
        what += " overlap";
        const Vec3d shift{0.1 * pick(5) - 0.2, 0.1 * pick(5) - 0.2, 0.15};
        const std::int64_t n = std::int64_t(soup.points.size());
        for (std::int64_t i = 0; i < n; ++i)
          soup.points.push_back(soup.points[std::size_t(i)] + shift);
        const std::size_t faces = soup.polygons.size();
        for (std::size_t f = 0; f < faces; ++f) {
          auto copy = soup.polygons[f];
          for (auto& i : copy) i += n;
          soup.polygons.push_back(copy);
        }
      } else if (d == 3) {
        what += " folds";
        for (std::size_t i = 0; i < shape.points.size(); i += 29)
          soup.points[i] = soup.points[i] * -0.8;
      } else if (d == 4) {
        what += " sheet";
        const std::int64_t n = std::int64_t(soup.points.size());
        for (const Vec3d& p :
             {Vec3d{-.6, -.6, .7}, Vec3d{.6, -.6, .7}, Vec3d{.6, .6, .7}, Vec3d{-.6, .6, .7}})
          soup.points.push_back(p);
        soup.polygons.push_back({n, n + 1, n + 2, n + 3});
      } else if (d == 5) {
        what += " duplicate";
        soup.polygons.push_back(soup.polygons.front());
      } else {
        what += " seams";
        PolygonSoup apart;
        for (const auto& f : soup.polygons) {
          std::vector<std::int64_t> g;
          for (const std::int64_t i : f) {
            apart.points.push_back(soup.points[std::size_t(i)]);
            g.push_back(std::int64_t(apart.points.size()) - 1);
          }
          apart.polygons.push_back(g);
        }
        soup = apart;
      }
    }
    // Flipped faces and seams alone are mended as the file is loaded, and folds that happen not
    // to cross anything are no defect: such a mix may load; any other is refused.
    if (!std::all_of(defects.begin(), defects.end(),
                     [](int d) { return d == 1 || d == 3 || d == 6; })) {
      EXPECT_THROW(make_surface(soup, "mix"), InputError) << mix << what;
    }
    const Repaired r = repair(soup, 32);  // \throw InternalError if the result did not validate
    EXPECT_GT(r.surface.stats.enclosed_volume, 0.0) << mix << what;
    std::vector<Vec3d> some;  // every 4th repaired vertex, against every input triangle
    for (std::size_t i = 0; i < r.surface.mesh.points.size(); i += 4)
      some.push_back(r.surface.mesh.points[i]);
    EXPECT_LT(max_distance(some, soup), 4.0 * r.h) << mix << what;
    if (mix % 5 == 0) {
      EXPECT_EQ(shell_problems(r.surface.mesh, 32), "") << mix << what;
    }
  }
}

TEST(Repair, SharedBrokenMeshesGiveValidShells) {
  const auto dir = test::shared_meshes_dir();
  if (dir.empty()) GTEST_SKIP() << "../shared/meshes is absent";
  for (const char* name : {"suzanne.obj", "teapot.obj", "beetle.obj"}) {
    const PolygonSoup input = read_polygon_soup((dir / name).string());
    EXPECT_THROW(make_surface(input, name), InputError) << name;
    const Repaired r = repair(input, 48);
    double coverage = 0;
    EXPECT_EQ(shell_problems(r.surface.mesh, 48, &coverage), "") << name;
    EXPECT_GT(coverage, 0.5) << name;
  }
}

/// Tets of `shell` under 1e-12 of the cube of its box's diagonal (the independent checker's
/// "degenerate").
std::size_t flat_tets(const TetMesh& shell) {
  BBox box;
  for (const Vec3d& p : shell.points) box.expand(p);
  const double flat = 1e-12 * std::pow(box.diagonal(), 3);
  std::size_t count = 0;
  for (const Tet& t : shell.tets)
    count += std::abs(tet_volume(shell.points[t[0]], shell.points[t[1]], shell.points[t[2]],
                                 shell.points[t[3]])) <= flat;
  return count;
}

/// `soup` with its points moved at random by up to `fraction` of its mean edge in each axis.
PolygonSoup jittered(const PolygonSoup& soup, double edge, double fraction, unsigned seed) {
  PolygonSoup out = soup;
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> jitter(-fraction * edge, fraction * edge);
  for (Vec3d& p : out.points) p += Vec3d{jitter(random), jitter(random), jitter(random)};
  return out;
}

TEST(Repair, TheRepairedSurfaceHasNoSliversOrSpecks) {
  // The sphere with two holes and its points moved at random by up to a fifth of an edge (its
  // faces crossing), repaired at 64 voxels across: contouring leaves edges of a thousandth of a
  // voxel there. By the test's own measures: no edge under 0.05 voxels, no part enclosing under
  // a voxel's volume, and a shell without flat tets.
  const SurfaceMesh sphere = make_shape("sphere");
  PolygonSoup input = jittered(polygon_soup_of(sphere), mean_edge_length(sphere), 0.2, 11);
  input.polygons.erase(input.polygons.begin() + 500);
  input.polygons.erase(input.polygons.begin() + 100);
  const Repaired r = repair(input, 64);
  const SurfaceMesh& mesh = r.surface.mesh;
  EXPECT_GT(r.report.collapsed_edges, 0u);
  double shortest = INFINITY;
  for (const Triangle& t : mesh.triangles)
    for (int k = 0; k < 3; ++k)
      shortest = std::min(shortest, distance(mesh.points[t[k]], mesh.points[t[(k + 1) % 3]]));
  EXPECT_GE(shortest, 0.05 * r.h) << shortest / r.h << " voxels";
  // Parts: points joined by triangles, and the volume each encloses.
  std::vector<std::size_t> part(mesh.points.size());
  for (std::size_t i = 0; i < part.size(); ++i) part[i] = i;
  const auto root = [&](std::size_t v) {
    while (part[v] != v) v = part[v];
    return v;
  };
  for (const Triangle& t : mesh.triangles)
    for (int k = 1; k < 3; ++k) part[root(t[k])] = root(t[0]);
  std::map<std::size_t, double> volume;
  for (const Triangle& t : mesh.triangles)
    volume[root(t[0])] +=
        tet_volume({0, 0, 0}, mesh.points[t[0]], mesh.points[t[1]], mesh.points[t[2]]);
  for (const auto& [at, v] : volume) EXPECT_GE(std::abs(v), r.h * r.h * r.h) << at;
  ShellOptions options;
  options.fields.resolution = 64;
  EXPECT_EQ(flat_tets(build_shell(mesh, options).mesh), 0u);
}

TEST(Repair, ANoisyKnightsSpecksAreDroppedAndItsShellHasNoFlatTets) {
  // The shared knight, its points moved by up to 0.15 of an edge, repaired at 128^3: 17 specks
  // around lone grid points, on which the shell had 322 tets of no volume.
  const auto dir = test::shared_meshes_dir();
  if (dir.empty()) GTEST_SKIP() << "../shared/meshes is absent";
  const PolygonSoup knight = read_polygon_soup((dir / "decimated-knight.off").string());
  const SurfaceMesh clean = make_surface(knight, "knight").mesh;
  const Repaired r = repair(jittered(knight, mean_edge_length(clean), 0.15, 7), 128);
  EXPECT_GT(r.report.dropped_parts, 0u);
  ShellOptions options;
  options.fields.resolution = 128;
  EXPECT_EQ(flat_tets(build_shell(r.surface.mesh, options).mesh), 0u);
}

TEST(Repair, AnAdaptiveMeshThatCrossesItselfIsMeshedLessAdaptively) {
  // The beetle rebuilt at 96^3 and meshed at adaptivity 0.8 crosses itself (polygons merged
  // across its slabs); meshed again with less merging the mesh is clean, and still coarser than
  // at 0.
  const auto dir = test::shared_meshes_dir();
  if (dir.empty()) GTEST_SKIP() << "../shared/meshes is absent";
  const PolygonSoup input = read_polygon_soup((dir / "beetle.obj").string());
  const std::size_t dense = repair(input, 96).surface.mesh.triangles.size();
  const SurfaceMesh adaptive = repair(input, 96, 2.0, 0.8).surface.mesh;
  EXPECT_LT(adaptive.triangles.size(), dense * 3 / 4);
  // Closed and 2-manifold, counted here: every edge in exactly two faces, once each way.
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> edges;
  for (const Triangle& t : adaptive.triangles)
    for (int k = 0; k < 3; ++k) ++edges[{t[k], t[(k + 1) % 3]}];
  for (const auto& [e, n] : edges) {
    ASSERT_EQ(n, 1) << e.first << "-" << e.second;
    ASSERT_EQ(edges.count({e.second, e.first}), 1u) << e.first << "-" << e.second;
  }
}

TEST(Repair, AdaptiveMeshDefectsAreMendedWhereTheyAre) {
  // The teapot rebuilt at 128^3 and meshed at adaptivity 0.2 has crossing faces in a few places.
  // Merging is turned off only around them, so the mesh keeps under a third of the faces at
  // adaptivity 0 (lowering the adaptivity everywhere, to 0.1, kept 42%), crosses itself nowhere
  // and its shell passes the independent checks.
  const auto dir = test::shared_meshes_dir();
  if (dir.empty()) GTEST_SKIP() << "../shared/meshes is absent";
  const PolygonSoup input = read_polygon_soup((dir / "teapot.obj").string());
  const std::size_t dense = repair(input, 128).surface.mesh.triangles.size();
  const SurfaceMesh adaptive = repair(input, 128, 2.0, 0.2).surface.mesh;
  EXPECT_LT(adaptive.triangles.size(), dense / 3) << dense;
  EXPECT_TRUE(test::self_intersections(adaptive).empty());
  EXPECT_EQ(shell_problems(adaptive, 64), "");
}

TEST(Repair, CrossingSectorsOfTheRebuiltBeetleGoOnTheSurface) {
  // The beetle rebuilt at 96^3 has folded vertices whose sectors' directions cross: their
  // prisms overlap at any depth, the floor's too, so the search keeps those sectors on the
  // surface (search.h) rather than failing. Checked independently.
  const auto dir = test::shared_meshes_dir();
  if (dir.empty()) GTEST_SKIP() << "../shared/meshes is absent";
  const Repaired r = repair(read_polygon_soup((dir / "beetle.obj").string()), 96);
  ShellOptions options;
  options.fields.resolution = 96;
  const ShellResult shell = build_shell(r.surface, options);
  EXPECT_GE(shell.validity.sectors, 2u);
  EXPECT_GE(shell.validity.on_surface_vertices, 1u);
  EXPECT_EQ(
      test::independent_shell_problems(r.surface.mesh, shell.mesh, 2 * shell.validity.sectors), "");
  EXPECT_GT(test::independent_coverage(r.surface.mesh, shell.mesh), 0.6);
}

TEST(Repair, CapPointsOfTheRebuiltBeetleMoveCloserToTheirFaces) {
  // The beetle rebuilt at 96^3 and meshed at adaptivity 0.2: a face whose three corners stay on
  // the surface gets a cap point below it, which at its first depth leaves the surface through
  // a thin part; it moves closer to its face as a floor does (search.h). Checked independently.
  const auto dir = test::shared_meshes_dir();
  if (dir.empty()) GTEST_SKIP() << "../shared/meshes is absent";
  const Repaired r = repair(read_polygon_soup((dir / "beetle.obj").string()), 96, 2.0, 0.2);
  ShellOptions options;
  options.fields.resolution = 96;
  const ShellResult shell = build_shell(r.surface, options);
  EXPECT_GE(shell.validity.cap_faces, 1u);
  EXPECT_EQ(
      test::independent_shell_problems(r.surface.mesh, shell.mesh, 2 * shell.validity.sectors), "");
}

}  // namespace
}  // namespace vdb_shell
