// fields_test.cpp — the distance, gradient and flux fields (vdb_ops/fields.h).
//
// Analytic references: a sphere of radius R (phi = |x| - R, grad = x / |x|) and the cube
// [-0.5, 0.5]^3 (phi = max |x_i| - 0.5 inside; medial surface where the two largest |x_i| tie).
// Shapes come from assets/shapes.h; fields are built once per shape at 128^3 and shared.
#include <gtest/gtest.h>
#include <stdlib.h>
#include <sys/resource.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <limits>
#include <memory>
#include <mutex>
#include <random>
#include <string>
#include <thread>

#include "assets/shapes.h"
#include "core/base/errors.h"
#include "core/base/geometry.h"
#include "core/base/run_control.h"
#include "core/read/load_surface.h"
#include "tests/test_support.h"
#include "vdb_ops/fields.h"
#include "vdb_ops/fields_diagnostics.h"

namespace vdb_shell {
namespace {

constexpr double kRadius = 0.5;  // make_shape("sphere") radius, world units

const SurfaceMesh& sphere_mesh() {
  static const SurfaceMesh mesh = make_shape("sphere", 4);
  return mesh;
}

const SurfaceMesh& box_mesh() {
  static const SurfaceMesh mesh = make_shape("box", 2);
  return mesh;
}

const Fields& sphere_fields() {
  static const std::unique_ptr<Fields> fields = build_fields(sphere_mesh(), FieldOptions{});
  return *fields;
}

/// Box fields with (almost) every flux value stored, to check the values themselves.
const Fields& box_fields_dense_flux() {
  static const std::unique_ptr<Fields> fields = [] {
    FieldOptions options;
    options.flux_min = 1e-4;
    return build_fields(box_mesh(), options);
  }();
  return *fields;
}

template <typename F>
void for_each_voxel(const Fields& fields, F&& f) {
  const IndexBox b = fields.active_index_box();
  for (int i = b.lo[0]; i <= b.hi[0]; ++i)
    for (int j = b.lo[1]; j <= b.hi[1]; ++j)
      for (int k = b.lo[2]; k <= b.hi[2]; ++k) f(i, j, k);
}

// --- plan and bad options ----------------------------------------------------------------------

TEST(FieldsPlan, VoxelSizeFromResolutionOrGiven) {
  FieldOptions options;
  options.resolution = 64;
  const FieldPlan plan = plan_fields(box_mesh(), options);
  EXPECT_NEAR(plan.voxel_size, 1.0 / 64.0, 1e-12);
  EXPECT_EQ(plan.resolution, 64);
  EXPECT_GE(plan.dims[0], 64);
  EXPECT_GT(plan.estimated_bytes, 0u);
  options.voxel_size = 0.05;
  const FieldPlan given = plan_fields(box_mesh(), options);
  EXPECT_DOUBLE_EQ(given.voxel_size, 0.05);
  EXPECT_EQ(given.resolution, 20);
}

TEST(FieldsPlan, RejectsCoarseResolution) {
  FieldOptions options;
  options.resolution = 7;
  EXPECT_THROW(plan_fields(box_mesh(), options), InputError);
  EXPECT_THROW(build_fields(box_mesh(), options), InputError);
  options.resolution = 128;
  options.voxel_size = 0.2;  // 5 voxels across
  EXPECT_THROW(plan_fields(box_mesh(), options), InputError);
  options.voxel_size = -1.0;
  EXPECT_THROW(plan_fields(box_mesh(), options), InputError);
  options.voxel_size = 0.0;
  options.flux_min = 2.0;
  EXPECT_THROW(plan_fields(box_mesh(), options), InputError);
  EXPECT_THROW(build_fields(SurfaceMesh{}, FieldOptions{}), InputError);
}

TEST(FieldsPlan, VoxelsBelowOpenVdbsSmallestAreBadInputNamingTheFix) {
  // A unit box scaled to 1e-3: at 128^3 the voxel (7.8e-6) is below the 1.44e-5 OpenVDB's maps
  // accept; at 64^3 (1.56e-5) it is not. The message names the unit and the finest resolution.
  SurfaceMesh tiny = box_mesh();
  for (Vec3d& p : tiny.points) p = p * 1e-3;
  FieldOptions options;
  options.resolution = 64;
  EXPECT_NO_THROW(plan_fields(tiny, options));
  EXPECT_NO_THROW(build_fields(tiny, options));
  options.resolution = 128;
  try {
    plan_fields(tiny, options);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("smaller unit"), std::string::npos) << what;
    EXPECT_NE(what.find("--resolution 69"), std::string::npos) << what;
  }
  EXPECT_THROW(build_fields(tiny, options), InputError);
}

TEST(FieldsPlan, RefusesWhatDoesNotFitBeforeAllocating) {
  FieldOptions options;
  options.resolution = 50000;  // ~1e14 voxels: must fail fast, not be OOM-killed
  try {
    build_fields(box_mesh(), options);
    FAIL() << "expected ResourceError";
  } catch (const ResourceError& e) {
    EXPECT_NE(std::string(e.what()).find("--max-memory"), std::string::npos) << e.what();
  }
  options.resolution = 512;
  options.max_memory_gb = 0.01;
  EXPECT_THROW(plan_fields(box_mesh(), options), ResourceError);
}

// --- sphere: SDF, gradient, flux ---------------------------------------------------------------

TEST(FieldsSphere, DistanceWithinHalfVoxelEverywhereInside) {
  const Fields& fields = sphere_fields();
  const double h = fields.voxel_size();
  EXPECT_NEAR(h, 1.0 / 128.0, 1e-9);
  double worst = 0.0;
  std::size_t inside = 0, negative = 0;
  for_each_voxel(fields, [&](int i, int j, int k) {
    const double r = norm(fields.voxel_center(i, j, k));
    if (fields.phi_at_voxel(i, j, k) < 0.0) ++negative;
    if (r >= kRadius) return;
    ++inside;
    worst = std::max(worst, std::abs(fields.phi_at_voxel(i, j, k) - (r - kRadius)));
  });
  EXPECT_GT(inside, 1000000u);
  EXPECT_LT(worst, 0.5 * h) << "worst |phi - (|x| - R)| = " << worst / h << " voxels";
  // Filled to the deepest point: the centre holds -R, not a clamped band value.
  EXPECT_NEAR(fields.probe()->phi({0, 0, 0}), -kRadius, 0.5 * h);
  EXPECT_EQ(fields.stats().interior_voxels, negative);
}

TEST(FieldsSphere, ExteriorBandIsThreeVoxelsWide) {
  // The wavefront widens OpenVDB's 2-voxel seed band to the exterior band; beyond it, phi is the
  // background (kExteriorBandVoxels voxels).
  const Fields& fields = sphere_fields();
  const double h = fields.voxel_size();
  double worst = 0.0;
  std::size_t in_band = 0, beyond = 0, not_clamped = 0;
  for_each_voxel(fields, [&](int i, int j, int k) {
    const double d = norm(fields.voxel_center(i, j, k)) - kRadius;
    const double phi = fields.phi_at_voxel(i, j, k);
    if (d > 0.0 && d < (kExteriorBandVoxels - 0.5) * h) {
      ++in_band;
      worst = std::max(worst, std::abs(phi - d));
    } else if (d > (kExteriorBandVoxels + 0.5) * h) {
      ++beyond;
      if (phi != float(kExteriorBandVoxels * h)) ++not_clamped;
    }
  });
  EXPECT_GT(in_band, 100000u);
  EXPECT_GT(beyond, 0u);
  EXPECT_LT(worst, 0.1 * h) << "worst |phi - (|x| - R)| in the exterior band = " << worst / h
                            << " voxels";
  EXPECT_EQ(not_clamped, 0u);
}

TEST(FieldsSphere, WavefrontInteriorMatchesMeshToVolumeInterior) {
  // Both methods store distances to a closest triangle of the same mesh; OpenVDB's own interior
  // expansion plus refinement is the reference for the wavefront fill.
  const Fields& fields = sphere_fields();
  FieldOptions options;
  options.sdf_method = SdfMethod::kMeshToVolumeInterior;
  const auto reference = build_fields(sphere_mesh(), options);
  const double h = fields.voxel_size();
  double worst = 0.0, sum = 0.0;
  std::size_t n = 0;
  for_each_voxel(fields, [&](int i, int j, int k) {
    const double phi = fields.phi_at_voxel(i, j, k);
    if (!(phi < 0.0)) return;
    const double e = std::abs(phi - reference->phi_at_voxel(i, j, k)) / h;
    worst = std::max(worst, e);
    sum += e;
    ++n;
  });
  EXPECT_GT(n, 1000000u);
  EXPECT_LT(worst, 0.25) << "voxels";
  EXPECT_LT(sum / double(n), 0.01) << "voxels (mean)";
}

TEST(FieldsSphere, FastSweepingInteriorIsFirstOrder) {
  // SdfMethod::kFastSweeping (a narrow band, then OpenVDB's dilateSdf into the interior): exact
  // near the surface, within a few voxels deep inside, and every interior voxel active.
  FieldOptions options;
  options.resolution = 48;
  options.sdf_method = SdfMethod::kFastSweeping;
  const auto sweeping = build_fields(sphere_mesh(), options);
  EXPECT_NE(sweeping->stats().strategy.find("fast sweeping"), std::string::npos);
  const double h = sweeping->voxel_size();
  auto probe = sweeping->probe();
  EXPECT_NEAR(probe->phi({0, 0, 0}), -kRadius, 3.0 * h);
  EXPECT_NEAR(probe->phi({0.45, 0, 0}), -0.05, 0.5 * h);
  EXPECT_GT(probe->flux({0, 0, 0}), 0.5);  // the centre is the medial point
  EXPECT_GT(sweeping->stats().interior_voxels,
            static_cast<std::size_t>(0.9 * 4.0 / 3.0 * kPi * std::pow(kRadius / h, 3)));
}

TEST(FieldsSphere, MeshVerticesOnZeroLevel) {
  const Fields& fields = sphere_fields();
  auto probe = fields.probe();
  double worst = 0.0;
  for (const Vec3d& p : sphere_mesh().points) worst = std::max(worst, std::abs(probe->phi(p)));
  EXPECT_LT(worst, 0.25 * fields.voxel_size());
}

TEST(FieldsSphere, GradientUnitAwayFromCentre) {
  const Fields& fields = sphere_fields();
  const double h = fields.voxel_size();
  auto probe = fields.probe();
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int checked = 0;
  double worst_len = 0.0, worst_dir = 0.0;
  Vec3d worst_at;
  while (checked < 20000) {
    const Vec3d p{u(rng) * kRadius, u(rng) * kRadius, u(rng) * kRadius};
    const double r = norm(p);
    if (r < 4.0 * h || r > kRadius) continue;
    const Vec3d g = probe->gradient(p);
    worst_len = std::max(worst_len, std::abs(norm(g) - 1.0));
    const double dir = 1.0 - dot(normalized(g), p / r);
    if (dir > worst_dir) {
      worst_dir = dir;
      worst_at = p;
    }
    ++checked;
  }
  EXPECT_LT(worst_len, 0.05);
  EXPECT_LT(worst_dir, 1e-3) << "at (" << worst_at.x << ", " << worst_at.y << ", " << worst_at.z
                             << "), r = " << norm(worst_at) / h << " voxels";
}

TEST(FieldsSphere, StoredAndStencilGradientsAgree) {
  FieldOptions options;
  options.resolution = 48;
  const auto on_the_fly = build_fields(sphere_mesh(), options);
  options.store_gradient = true;
  const auto stored = build_fields(sphere_mesh(), options);
  ASSERT_FALSE(on_the_fly->has_gradient_grid());
  ASSERT_TRUE(stored->has_gradient_grid());
  EXPECT_GT(stored->stats().gradient_active_voxels, 0u);
  auto a = on_the_fly->probe();
  auto b = stored->probe();
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-0.5, 0.5);
  for (int n = 0; n < 5000; ++n) {
    const Vec3d p{u(rng), u(rng), u(rng)};
    if (norm(p) > kRadius + on_the_fly->voxel_size()) continue;  // the band's edge differs
    const Vec3d ga = a->gradient(p), gb = b->gradient(p);
    ASSERT_LT(norm(ga - gb), 1e-5) << "at (" << p.x << ", " << p.y << ", " << p.z << ")";
  }
}

TEST(FieldsSphere, FluxPeaksAtCentreAndIsSparse) {
  const Fields& fields = sphere_fields();
  auto probe = fields.probe();
  EXPECT_GT(probe->flux({0, 0, 0}), 0.9);  // all 26 neighbours point straight out
  EXPECT_LT(std::abs(probe->flux({0.3, 0.1, 0.0})), 0.05);
  const FieldStats& s = fields.stats();
  EXPECT_GT(s.flux_active_voxels, 0u);
  EXPECT_LT(double(s.flux_active_voxels), 0.1 * double(s.interior_voxels))
      << s.flux_active_voxels << " flux voxels for " << s.interior_voxels << " inside";
}

// --- box: flux on and off the medial surface -----------------------------------------------------

/// Distance (world units) from voxel centre c to the plane where the two largest |c_i| tie, and
/// whether c lies exactly on it (integer comparison of the voxel's offsets from the centre).
struct MedialInfo {
  bool on = false;
  double plane_distance = 0.0;
};

MedialInfo medial_info(const Fields& fields, int i, int j, int k) {
  const Vec3d c = fields.voxel_center(i, j, k);
  const double h = fields.voxel_size();
  // Voxel offsets from the box centre (the centre is a voxel centre: -0.5 is a multiple of h).
  std::array<long, 3> a = {std::lround(std::abs(c.x) / h), std::lround(std::abs(c.y) / h),
                           std::lround(std::abs(c.z) / h)};
  std::sort(a.begin(), a.end(), std::greater<long>());
  return {a[0] == a[1], double(a[0] - a[1]) * h / std::sqrt(2.0)};
}

TEST(FieldsSliver, TrianglesDegenerateInFloatGetDistancesAndTheFillEnds) {
  // Vertices inserted 1e-7 of an edge's length from its end: at 64^3 the slivers between them
  // and the end have two corners within float rounding in index space. The float distance to
  // such a triangle divided zero by zero (NaN), a voxel whose only candidate it was never got
  // a finite distance, and the interior fill waited for it forever. A watchdog cancels the
  // build after 120 s (it takes well under a second).
  std::vector<test::InsertedVertex> inserted;
  const SurfaceMesh mesh =
      test::with_vertices_near_edge_ends(make_shape("sphere", 1), 3, 1e-7, inserted);
  ASSERT_GE(inserted.size(), 50u);
  std::atomic<bool> cancel{false};
  std::mutex mutex;
  std::condition_variable done;
  bool finished = false;
  std::thread watchdog([&] {
    std::unique_lock<std::mutex> lock(mutex);
    if (!done.wait_for(lock, std::chrono::seconds(120), [&] { return finished; })) cancel = true;
  });
  RunControl control;
  control.cancel = &cancel;
  std::unique_ptr<Fields> fields;
  FieldOptions options;
  options.resolution = 64;
  EXPECT_NO_THROW(fields = build_fields(mesh, options, StageMonitor(control, "fields")));
  {
    std::lock_guard<std::mutex> lock(mutex);
    finished = true;
  }
  done.notify_one();
  watchdog.join();
  ASSERT_TRUE(fields);
  // Inside, phi is the distance to the nearest triangle (computed here, in double) within half a
  // voxel, at every 7th voxel.
  const double h = fields->voxel_size();
  std::size_t checked = 0, n = 0;
  double worst = 0;
  for_each_voxel(*fields, [&](int i, int j, int k) {
    if (n++ % 7 != 0 || !(fields->phi_at_voxel(i, j, k) < 0)) return;
    const Vec3d p = fields->voxel_center(i, j, k);
    double d2 = std::numeric_limits<double>::infinity();
    for (const Triangle& t : mesh.triangles)
      d2 = std::min(
          d2, point_triangle_distance2(p, mesh.points[t[0]], mesh.points[t[1]], mesh.points[t[2]]));
    worst = std::max(worst, std::abs(-fields->phi_at_voxel(i, j, k) - std::sqrt(d2)));
    ++checked;
  });
  EXPECT_GT(checked, 1000u);
  EXPECT_LT(worst, 0.5 * h) << worst / h << " voxels";
}

TEST(FieldsBox, ExactDistanceInside) {
  const Fields& fields = box_fields_dense_flux();
  const double h = fields.voxel_size();
  double worst = 0.0;
  for_each_voxel(fields, [&](int i, int j, int k) {
    const Vec3d c = fields.voxel_center(i, j, k);
    const double m = std::max({std::abs(c.x), std::abs(c.y), std::abs(c.z)});
    if (m >= 0.5) return;
    worst = std::max(worst, std::abs(fields.phi_at_voxel(i, j, k) - (m - 0.5)));
  });
  EXPECT_LT(worst, 0.1 * h);
}

TEST(FieldsBox, FluxMarksTheMedialSurfaceOnly) {
  const Fields& fields = box_fields_dense_flux();
  const double h = fields.voxel_size();
  std::size_t on_count = 0, off_count = 0;
  double min_on = 1.0, max_off = 0.0;
  for_each_voxel(fields, [&](int i, int j, int k) {
    if (!(fields.phi_at_voxel(i, j, k) < 0.0)) return;
    const MedialInfo m = medial_info(fields, i, j, k);
    const double f = fields.flux_at_voxel(i, j, k);
    if (m.on) {
      ++on_count;
      min_on = std::min(min_on, f);
    } else if (m.plane_distance > 2.0 * h) {
      ++off_count;
      max_off = std::max(max_off, std::abs(f));
    }
  });
  EXPECT_GT(on_count, 10000u);
  EXPECT_GT(off_count, 100000u);
  EXPECT_GT(min_on, 0.1);
  EXPECT_LT(max_off, 0.02);
}

TEST(FieldsBox, DefaultFluxGridIsSparse) {
  const auto fields = build_fields(box_mesh(), FieldOptions{});
  const FieldStats& s = fields->stats();
  EXPECT_GT(s.flux_active_voxels, 0u);
  EXPECT_LT(double(s.flux_active_voxels), 0.25 * double(s.interior_voxels))
      << s.flux_active_voxels << " flux voxels for " << s.interior_voxels << " inside";
}

TEST(FieldsBox, SameGridsForAnyThreadCount) {
  FieldOptions options;
  options.resolution = 64;
  options.store_gradient = true;
  std::vector<VdbGridInfo> one, all;
  {
    tbb::global_control serial(tbb::global_control::max_allowed_parallelism, 1);
    one = grid_infos(*build_fields(sphere_mesh(), options));
  }
  all = grid_infos(*build_fields(sphere_mesh(), options));
  ASSERT_EQ(one.size(), 3u);
  ASSERT_EQ(all.size(), 3u);
  for (std::size_t g = 0; g < one.size(); ++g) {
    EXPECT_EQ(one[g].name, all[g].name);
    EXPECT_EQ(one[g].active_voxels, all[g].active_voxels);
    EXPECT_EQ(one[g].checksum, all[g].checksum) << one[g].name;
  }
}

// --- the seed band's voxelization ----------------------------------------------------------------

/// `mesh` and, beside it, a thin triangular prism along z as tall as the unit cube (8 triangles):
/// at 96^3 its side triangles' boxes are taller than 64 voxels, so they take the flood fill.
SurfaceMesh with_tall_prism(SurfaceMesh mesh) {
  const std::uint32_t b = std::uint32_t(mesh.points.size());
  for (const double z : {-0.5, 0.5}) {
    mesh.points.push_back({0.6, -0.05, z});
    mesh.points.push_back({0.7, -0.05, z});
    mesh.points.push_back({0.65, 0.05, z});
  }
  mesh.triangles.push_back({b + 0, b + 2, b + 1});  // bottom, facing -z
  mesh.triangles.push_back({b + 3, b + 4, b + 5});  // top, facing +z
  for (std::uint32_t i = 0; i < 3; ++i) {
    const std::uint32_t j = (i + 1) % 3;
    mesh.triangles.push_back({b + i, b + j, b + 3 + j});
    mesh.triangles.push_back({b + i, b + 3 + j, b + 3 + i});
  }
  return mesh;
}

TEST(FieldsSeedBand, SameAsMeshToVolumeVoxelForVoxel) {
  FieldOptions options;
  options.resolution = 96;
  const SeedBandComparison c = compare_seed_band(with_tall_prism(make_shape("sphere", 2)), options);
  EXPECT_TRUE(c.voxelized_here);
  EXPECT_GE(c.flood_filled, 6u);  // the prism's sides
  EXPECT_GT(c.band_voxels, 20000u);
  EXPECT_EQ(c.differing_voxels, 0u);
}

TEST(FieldsSeedBand, SharedMeshesSameAsMeshToVolume) {
  const auto dir = test::shared_meshes_dir();
  if (dir.empty()) GTEST_SKIP() << "../shared/meshes not found";
  for (const char* name : {"fandisk.obj", "fertility.off", "decimated-knight.off"}) {
    const LoadedSurface s = load_surface((dir / name).string());
    FieldOptions options;
    options.resolution = 160;
    const SeedBandComparison c = compare_seed_band(s.mesh, options);
    EXPECT_TRUE(c.voxelized_here) << name;
    EXPECT_GT(c.band_voxels, 0u) << name;
    EXPECT_EQ(c.differing_voxels, 0u) << name;
  }
}

TEST(FieldsSeedBand, SmallMeshesStayWithMeshToVolume) {
  // Under 1000 triangles OpenVDB measures against parts of large triangles: not replicated.
  const SeedBandComparison c = compare_seed_band(box_mesh(), FieldOptions{});
  EXPECT_FALSE(c.voxelized_here);
  EXPECT_EQ(c.differing_voxels, 0u);
}

// --- .vdb out and in -----------------------------------------------------------------------------

TEST(FieldsVdb, RoundTripKeepsValuesAndMetadata) {
  test::TempDir dir;
  FieldOptions options;
  options.resolution = 32;
  options.store_gradient = true;
  const auto fields = build_fields(box_mesh(), options);
  const std::string path = dir.file("fields.vdb");
  write_grids(path, *fields, {{"vdb_shell_input", "box.obj"}});

  const std::vector<VdbGridInfo> mem = grid_infos(*fields);
  const std::vector<VdbGridInfo> file = read_vdb_grid_infos(path);
  ASSERT_EQ(file.size(), 3u);
  ASSERT_EQ(mem.size(), 3u);
  EXPECT_EQ(file[0].name, "surface");
  EXPECT_EQ(file[0].grid_class, "level set");
  EXPECT_EQ(file[1].name, "flux");
  EXPECT_EQ(file[2].name, "gradient");
  EXPECT_EQ(file[2].value_type, "vec3s");
  for (std::size_t g = 0; g < 3; ++g) {
    EXPECT_EQ(file[g].active_voxels, mem[g].active_voxels) << file[g].name;
    EXPECT_EQ(file[g].checksum, mem[g].checksum) << file[g].name;
    EXPECT_DOUBLE_EQ(file[g].voxel_size, fields->voxel_size());
    EXPECT_EQ(file[g].metadata.at("vdb_shell_input"), "box.obj");
    EXPECT_EQ(file[g].metadata.count("vdb_shell_voxel_size"), 1u);
  }

  // An independent reader.
  const test::CommandResult which = test::run_command("command -v vdb_print");
  if (which.exit_code == 0) {
    const test::CommandResult r = test::run_command("vdb_print -l '" + path + "'");
    EXPECT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.out.find("surface"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("flux"), std::string::npos) << r.out;
  }

  // Read back as the level set of the same mesh: the same SDF and flux.
  const auto back = fields_from_level_set(path, "", box_mesh(), options);
  EXPECT_TRUE(back->stats().notices.empty());
  const std::vector<VdbGridInfo> again = grid_infos(*back);
  ASSERT_EQ(again.size(), 3u);
  for (std::size_t g = 0; g < 3; ++g) EXPECT_EQ(again[g].checksum, mem[g].checksum);
}

TEST(FieldsVdb, RejectsBadLevelSets) {
  test::TempDir dir;
  FieldOptions options;
  options.resolution = 16;
  const auto fields = build_fields(box_mesh(), options);
  const std::string path = dir.file("f.vdb");
  write_grids(path, *fields, {});

  EXPECT_THROW(fields_from_level_set(dir.file("missing.vdb"), "", box_mesh(), options), InputError);
  EXPECT_THROW(fields_from_level_set(path, "nope", box_mesh(), options), InputError);
  try {
    fields_from_level_set(path, "flux", box_mesh(), options);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("grid class to level set"), std::string::npos) << e.what();
  }
  SurfaceMesh moved = box_mesh();
  for (Vec3d& p : moved.points) p.x += 3.0;
  try {
    fields_from_level_set(path, "surface", moved, options);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("does not contain the mesh"), std::string::npos)
        << e.what();
  }
  const std::string junk = dir.file("junk.vdb");
  test::write_text(junk, "not a vdb file");
  EXPECT_THROW(fields_from_level_set(junk, "", box_mesh(), options), InputError);
}

/// The box's grids at 16^3, written to `dir`/good.vdb; returns that path.
std::string write_box_grids(const test::TempDir& dir) {
  FieldOptions options;
  options.resolution = 16;
  const std::string path = dir.file("good.vdb");
  write_grids(path, *build_fields(box_mesh(), options), {});
  return path;
}

TEST(FieldsVdb, CorruptFilesAreBadInputNotACrash) {
  // A level set file cut short at several places, one with its bytes flipped, and the inputs
  // the .vdb fuzz target found (tests/fuzz/regressions/vdb: OpenVDB's reader overflows a
  // buffer on them): each is an InputError naming the file, or (where the damage left a
  // readable grid) a surface; the process survives every one.
  test::TempDir dir;
  const std::string good = write_box_grids(dir);
  std::ifstream in(good, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::vector<std::string> cases;
  for (const double cut : {0.1, 0.5, 0.9}) cases.push_back(bytes.substr(0, bytes.size() * cut));
  std::string flipped = bytes;
  for (std::size_t i = flipped.size() / 3; i < flipped.size(); i += 97) flipped[i] ^= 0x5a;
  cases.push_back(flipped);
  for (const auto& entry : std::filesystem::directory_iterator(
           std::filesystem::path(VDB_SHELL_FUZZ_REGRESSIONS) / "vdb")) {
    std::ifstream file(entry.path(), std::ios::binary);
    cases.emplace_back((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  }
  ASSERT_GT(cases.size(), 4u);
  std::size_t refused = 0;
  for (std::size_t k = 0; k < cases.size(); ++k) {
    const std::string path = dir.file("case" + std::to_string(k) + ".vdb");
    test::write_text(path, cases[k]);
    try {
      EXPECT_FALSE(volume_to_soup(path, "", 0.0, false).soup.polygons.empty()) << k;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
      ++refused;
    }
  }
  EXPECT_GE(refused, 3u);  // at least the cut files
}

TEST(FieldsVdb, ASizeACorruptFileClaimsIsRefusedWithinTheReadersAllowance) {
  // A 38 kB file (found by the .vdb fuzz target) whose grid metadata claims an entry of unknown
  // type some hundreds of MB long: OpenVDB's reader zero-fills a buffer that size and copies it.
  // The reader refuses it once it passes its allowance (64 times the file's size, at least
  // 128 MiB): the largest reader this process started (ru_maxrss of its children) stays below
  // twice that, where a floor of 1 GiB let it fill 1 GiB.
  const std::filesystem::path file =
      std::filesystem::path(VDB_SHELL_FUZZ_REGRESSIONS) / "vdb" / "unknown-metadata-claim";
  ASSERT_LT(std::filesystem::file_size(file), 2u << 20);
  try {
    volume_to_soup(file.string(), "", 0.0, false);
    ADD_FAILURE() << "the corrupt file was read";
  } catch (const InputError& e) {
    // The reader's own message, or under AddressSanitizer (whose allocator aborts the reader
    // instead of throwing) how the reader ended: either names the file.
    EXPECT_NE(std::string(e.what()).find(file.string()), std::string::npos) << e.what();
  }
  rusage children{};
  ASSERT_EQ(::getrusage(RUSAGE_CHILDREN, &children), 0);
  EXPECT_LT(children.ru_maxrss, 256L << 10) << "KiB";  // ru_maxrss is in KiB
}

/// Sets VDB_SHELL_VDB_READER (the .vdb reader program) for its lifetime.
class ReaderOverride {
 public:
  explicit ReaderOverride(const std::string& path) { ::setenv(kName, path.c_str(), 1); }
  ~ReaderOverride() { ::unsetenv(kName); }

 private:
  static constexpr const char* kName = "VDB_SHELL_VDB_READER";
};

TEST(FieldsVdb, TheReaderProgramFailingIsReportedInOneLine) {
  // The .vdb reader is a program of its own (vdb_shell_vdb_reader): one that crashes is a bad
  // file named with the signal, and one that cannot be started is a resource error naming the
  // fix. The file itself is sound: only the reader differs.
  test::TempDir dir;
  const std::string good = write_box_grids(dir);
  ASSERT_FALSE(volume_to_soup(good, "", 0.0, false).soup.polygons.empty());
  const std::string crashing = dir.file("crashing_reader");
  test::write_text(crashing, "#!/bin/sh\nkill -SEGV $$\n");
  std::filesystem::permissions(crashing, std::filesystem::perms::owner_all);
  {
    ReaderOverride reader(crashing);
    try {
      volume_to_soup(good, "", 0.0, false);
      ADD_FAILURE() << "a crashing reader went unnoticed";
    } catch (const InputError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(good), std::string::npos) << what;
      EXPECT_NE(what.find("signal " + std::to_string(SIGSEGV)), std::string::npos) << what;
      EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    }
  }
  {
    ReaderOverride reader(dir.file("no_such_reader"));
    try {
      volume_to_soup(good, "", 0.0, false);
      ADD_FAILURE() << "a missing reader went unnoticed";
    } catch (const ResourceError& e) {
      EXPECT_NE(std::string(e.what()).find("VDB_SHELL_VDB_READER"), std::string::npos) << e.what();
    }
  }
  EXPECT_FALSE(volume_to_soup(good, "", 0.0, false).soup.polygons.empty());
}

TEST(FieldsVdb, NarrowBandLevelSetGetsInteriorFilled) {
  const test::CommandResult which = test::run_command("command -v vdb_tool");
  if (which.exit_code != 0) GTEST_SKIP() << "vdb_tool (libopenvdb-tools) not installed";
  test::TempDir dir;
  const std::string path = dir.file("sphere.vdb");
  const test::CommandResult r = test::run_command(
      "vdb_tool -sphere voxel=0.015625 radius=0.5 width=3 name=surface -write '" + path + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  FieldOptions options;
  const auto fields = fields_from_level_set(path, "", sphere_mesh(), options);
  EXPECT_FALSE(fields->stats().notices.empty());
  const double h = fields->voxel_size();
  EXPECT_NEAR(h, 0.015625, 1e-9);
  auto probe = fields->probe();
  // First-order fast sweeping: within a few voxels at the centre, exact near the surface.
  EXPECT_NEAR(probe->phi({0, 0, 0}), -kRadius, 3.0 * h);
  EXPECT_NEAR(probe->phi({0.45, 0, 0}), -0.05, 0.5 * h);
  EXPECT_GT(probe->flux({0, 0, 0}), 0.5);
}

}  // namespace
}  // namespace vdb_shell
