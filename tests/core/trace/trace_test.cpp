// trace_test.cpp — classification, tracing and merge resolution (core/trace/trace.h) on exact
// analytic fields (tests/analytic_field.h), without OpenVDB.
#include <gtest/gtest.h>

#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>

#include "assets/shapes.h"
#include "core/base/errors.h"
#include "core/trace/trace.h"
#include "tests/analytic_field.h"

namespace vdb_shell {
namespace {

SurfaceMesh scaled(SurfaceMesh m, const Vec3d& s) {
  for (Vec3d& p : m.points) p = {p.x * s.x, p.y * s.y, p.z * s.z};
  return m;
}

TEST(Classify, BoxCornersAndEdgesAreNonPlanarFaceCentresPlanar) {
  const SurfaceMesh box = make_shape("box", 1);  // 2x2 quads per side: 26 vertices
  const auto planar = classify_vertices(box, 5.0);
  int n_planar = 0;
  for (std::size_t v = 0; v < box.points.size(); ++v) {
    const Vec3d& p = box.points[v];
    const int on_faces = (std::fabs(std::fabs(p.x) - 0.5) < 1e-12) +
                         (std::fabs(std::fabs(p.y) - 0.5) < 1e-12) +
                         (std::fabs(std::fabs(p.z) - 0.5) < 1e-12);
    EXPECT_EQ(planar[v], on_faces == 1 ? 1 : 0) << "vertex " << v;
    n_planar += planar[v];
  }
  EXPECT_EQ(n_planar, 6);
}

TEST(Classify, CoarseSphereIsNonPlanarEverywhere) {
  // 760 faces: neighbouring normals differ by ~18 degrees, above the 5 degree default.
  const SurfaceMesh sphere = make_shape("sphere", 1);
  const auto planar = classify_vertices(sphere, 5.0);
  EXPECT_EQ(std::count(planar.begin(), planar.end(), 1), 0);
  const auto loose = classify_vertices(sphere, 60.0);
  EXPECT_EQ(std::count(loose.begin(), loose.end(), 0), 0);
}

TEST(Trace, SphereTracesEndAtTheCentreWithoutOvershoot) {
  const double voxel = 1.0 / 128.0;
  const SurfaceMesh sphere = make_shape("sphere", 1);
  const auto field = test::sphere_field(0.5, voxel);
  for (Integrator integ : {Integrator::kEuler, Integrator::kRk2, Integrator::kRk4}) {
    TraceOptions opt;
    opt.integrator = integ;
    const TraceResult r = trace_paths(sphere, *field, opt);
    EXPECT_EQ(r.stops(StopReason::kCap), 0u);
    for (std::size_t v = 0; v < r.num_traces(); ++v) {
      EXPECT_LT(norm(r.end_point(v)), 2.0 * voxel) << to_string(integ) << " vertex " << v;
      // No sample ever passes the centre by more than a step.
      for (std::size_t i = 0; i <= r.end[v]; ++i)
        EXPECT_GT(dot(r.sample(v, i), r.sample(v, 0)), -r.parameters.step * 0.5);
    }
  }
}

TEST(Trace, CubeLikeThePaperEndsAtTheCentre) {
  const double voxel = 1.0 / 64.0;
  const SurfaceMesh box = make_shape("box", 1);
  const auto field = test::box_field({0.5, 0.5, 0.5}, voxel);
  const TraceResult r = trace_paths(box, *field, TraceOptions{});
  EXPECT_EQ(r.stops(StopReason::kCap), 0u);
  for (std::size_t v = 0; v < r.num_traces(); ++v)
    EXPECT_LT(norm(r.end_point(v)), 1.5 * voxel)
        << "vertex " << v << " stop " << to_string(r.stop[v]);
}

TEST(Trace, BeamFaceTracesStopAtTheMedialSurface) {
  const double voxel = 2.0 / 128.0;
  const SurfaceMesh beam = scaled(make_shape("box", 2), {4.0, 1.0, 1.0});  // 2 x 1 x 1... halves
  const auto field = test::box_field({2.0, 0.5, 0.5}, voxel);
  const TraceResult r = trace_paths(beam, *field, TraceOptions{});
  int checked = 0;
  for (std::size_t v = 0; v < r.num_traces(); ++v) {
    const Vec3d& p = beam.points[v];
    if (!r.planar[v] || std::fabs(p.x) > 1.0) continue;  // mid-section face vertices only
    const Vec3d& q = r.end_point(v);
    const double to_medial = std::fabs(std::fabs(q.y) - std::fabs(q.z)) / std::sqrt(2.0);
    EXPECT_LT(to_medial, 1.5 * voxel) << "vertex " << v << " " << to_string(r.stop[v]);
    EXPECT_LT(field->probe()->phi(q), 0.0);
    ++checked;
  }
  EXPECT_GT(checked, 8);
}

TEST(Trace, FineMeshStillGivesThickTraces) {
  // Edges (1/40) shorter than the point size (sqrt(3)/32): neighbours start side by side.
  const double voxel = 1.0 / 32.0;
  const SurfaceMesh box = make_shape("box", 20);
  const auto field = test::box_field({0.5, 0.5, 0.5}, voxel);
  const TraceResult r = trace_paths(box, *field, TraceOptions{});
  std::vector<double> depth;
  const auto probe = field->probe();
  for (std::size_t v = 0; v < r.num_traces(); ++v) depth.push_back(-probe->phi(r.end_point(v)));
  std::nth_element(depth.begin(), depth.begin() + depth.size() / 2, depth.end());
  // A vertex at distance d from the nearest edge can reach depth ~d; the median is ~0.15.
  EXPECT_GT(depth[depth.size() / 2], 0.1);
  EXPECT_EQ(r.stops(StopReason::kCap), 0u);
}

TEST(Trace, SameResultForAnyThreadCount) {
  const SurfaceMesh shape = make_shape("box", 6);
  const auto field = test::box_field({0.5, 0.5, 0.5}, 1.0 / 48.0);
  auto run = [&](int threads) {
    tbb::task_arena arena(threads);
    TraceResult r;
    arena.execute([&] { r = trace_paths(shape, *field, TraceOptions{}); });
    return r;
  };
  const TraceResult a = run(1), b = run(2), c = run(8);
  for (const TraceResult* o : {&b, &c}) {
    EXPECT_EQ(a.samples.size(), o->samples.size());
    EXPECT_TRUE(std::equal(a.samples.begin(), a.samples.end(), o->samples.begin()));
    EXPECT_EQ(a.end, o->end);
    EXPECT_EQ(a.merged_with, o->merged_with);
  }
}

TEST(Trace, MinStepKeepsStepsLongWhereTheGradientIsShort) {
  // A cube's corners and edges reach its medial surface, where the central differences of |phi|
  // cancel across the ridge: the paper's steps (min_step 0) shrink there with |grad phi|.
  const double voxel = 1.0 / 64.0;
  const SurfaceMesh box = make_shape("box", 4);
  const auto field = test::box_field({0.5, 0.5, 0.5}, voxel);
  const auto steps_under = [](const TraceResult& r, double fraction) {
    std::size_t n = 0;
    for (std::size_t v = 0; v < r.num_traces(); ++v)
      for (std::size_t i = 0; i < r.end[v]; ++i)
        n += distance(r.sample(v, i), r.sample(v, i + 1)) < fraction * r.parameters.step;
    return n;
  };
  TraceOptions paper;
  paper.min_step = 0.0;
  TraceOptions floor;
  floor.min_step = 0.5;
  const TraceResult a = trace_paths(box, *field, paper);
  const TraceResult b = trace_paths(box, *field, floor);
  // Shorter steps remain only where a lengthened step passed a turn of the gradient and the
  // paper's step was taken instead: near the centre (502 and 230 steps under a quarter).
  EXPECT_GT(steps_under(a, 0.25), 400u);
  EXPECT_LT(steps_under(b, 0.25), steps_under(a, 0.25) / 2);
  EXPECT_LT(b.samples.size(), a.samples.size());
  // Both settle on the centre, the cube's one critical point, as closely: the paper's steps
  // shrink into it (0.023 voxels at most), and so do the steps taken where a lengthened one
  // passed it (0.031; ending where the lengthened steps stopped, 0.125).
  for (const TraceResult* r : {&a, &b}) {
    EXPECT_EQ(r->stops(StopReason::kCap), 0u);
    std::size_t at_centre = 0;
    for (std::size_t v = 0; v < r->num_traces(); ++v)
      if (r->stop[v] == StopReason::kCritical) {
        EXPECT_LT(norm(r->end_point(v)), 0.05 * voxel) << "vertex " << v;
        ++at_centre;
      }
    EXPECT_GT(at_centre, 90u);
  }
}

TEST(TraceEstimate, APilotOfEveryVertexCountsTheSamplesExactly) {
  // 26 vertices: all are pilots, traced as trace_paths() traces them.
  const SurfaceMesh box = make_shape("box", 1);
  const auto field = test::box_field({0.5, 0.5, 0.5}, 1.0 / 64.0);
  const TraceEstimate e = estimate_traces(box, *field, TraceOptions{});
  const TraceResult r = trace_paths(box, *field, TraceOptions{});
  EXPECT_EQ(e.traces, box.points.size());
  EXPECT_EQ(e.pilot_traces, box.points.size());
  const double mean = double(r.samples.size()) / double(r.num_traces());
  EXPECT_DOUBLE_EQ(e.samples_per_trace, kPilotSafety * mean);
  EXPECT_EQ(e.bytes, static_cast<std::size_t>(double(box.points.size()) *
                                              (e.samples_per_trace * kTraceBytesPerSample +
                                               double(kTraceBytesPerTrace))));
}

TEST(TraceEstimate, BoundsWhatTheTracesHoldWithinTwice) {
  struct Case {
    SurfaceMesh mesh;
    std::unique_ptr<test::AnalyticField> field;
  };
  std::vector<Case> cases;
  cases.push_back({make_shape("box", 12), test::box_field({0.5, 0.5, 0.5}, 1.0 / 64.0)});
  cases.push_back({make_shape("sphere", 3), test::sphere_field(0.5, 1.0 / 64.0)});
  cases.push_back({scaled(make_shape("box", 8), {2.0, 1.0, 0.5}),
                   test::box_field({1.0, 0.5, 0.25}, 1.0 / 32.0)});
  for (const Case& c : cases) {
    const TraceEstimate e = estimate_traces(c.mesh, *c.field, TraceOptions{});
    const TraceResult r = trace_paths(c.mesh, *c.field, TraceOptions{});
    EXPECT_EQ(e.pilot_traces, std::min(c.mesh.points.size(), kPilotTraces));
    const double mean = double(r.samples.size()) / double(r.num_traces());
    EXPECT_GE(e.samples_per_trace, mean) << c.mesh.points.size() << " vertices";
    EXPECT_LE(e.samples_per_trace, 2.0 * mean) << c.mesh.points.size() << " vertices";
    EXPECT_GE(e.bytes, memory_bytes(r));  // and the rows beside them at the peak
  }
}

TEST(Trace, OptionsAreValidated) {
  const BBox unit{{0, 0, 0}, {1, 1, 1}};
  TraceOptions bad;
  bad.step = -1;
  EXPECT_THROW(derive_trace_parameters(bad, 0.01, unit), InputError);
  bad = {};
  bad.flux_threshold = 2;
  EXPECT_THROW(derive_trace_parameters(bad, 0.01, unit), InputError);
  for (const double min_step : {-0.1, 1.5, std::nan("")}) {
    bad = {};
    bad.min_step = min_step;
    EXPECT_THROW(derive_trace_parameters(bad, 0.01, unit), InputError) << min_step;
  }
  const TraceParameters p = derive_trace_parameters(TraceOptions{}, 0.01, unit);
  EXPECT_DOUBLE_EQ(p.step, 0.005);
  EXPECT_DOUBLE_EQ(p.point_size, 0.01 * std::sqrt(3.0));
  EXPECT_THROW(parse_integrator("midpoint"), InputError);
}

}  // namespace
}  // namespace vdb_shell
