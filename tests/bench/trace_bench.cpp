// trace_bench.cpp — path tracing and merge resolution (core/trace/trace.h) on OpenVDB fields:
// traces per second and total trace time with 1 and 2 threads, beside the field build time of the
// same run; with --straightness, how straight each integrator keeps traces that are straight in
// the exact field.
//
// Not part of the test run. Usage:
//   vdb_shell_bench_traces [--no-large] [--min-step F ...] [MESH[@RESOLUTION] ...]
//   vdb_shell_bench_traces --straightness
// Without MESH: the Table 1 shapes (assets/shapes.h, detail 1) at 128^3, then at 512^3
// ../shared/meshes/fandisk.obj and make_shape("box", 46) (101,568 faces); --no-large skips the
// two 512^3 runs. Each mesh's fields are built once (all threads); each thread count then traces
// it once with the default options (RK2), or once per --min-step given (TraceOptions::min_step,
// the shortest step as a fraction of the step; 0: the paper's). "trace" is the integration,
// "merge" the merge resolution; traces/s = traces / (trace + merge). The 2-thread result is
// checked byte for byte against the 1-thread one. Prints Markdown.
//
// --straightness: the box (2x2 per face: every vertex on an axis of symmetry, so its trace runs
// straight to the centre) and the cylinder at detail 2 (cap centres down the axis, side vertices
// at mid-height straight to the axis), each axis-aligned and rotated by 20 degrees about x then
// 30 about z (so the grid shares none of their symmetries), at 128^3: the largest distance of any
// sample from its trace's straight line, in voxels, for Euler, RK2 and RK4 at the default step
// (half a voxel) and at 2 voxels. tests/vdb_ops/trace_vdb_test.cpp bounds the same figures.
#include <tbb/global_control.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "assets/shapes.h"
#include "core/base/vec3.h"
#include "core/read/load_surface.h"
#include "core/trace/trace.h"
#include "tests/straight_traces.h"
#include "vdb_ops/fields.h"

namespace vdb_shell {
namespace {

struct Job {
  std::string label;
  SurfaceMesh mesh;
  int resolution = 128;
};

template <class T>
bool same_bytes(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0;
}

bool identical(const TraceResult& a, const TraceResult& b) {
  return same_bytes(a.offsets, b.offsets) && same_bytes(a.samples, b.samples) &&
         same_bytes(a.end, b.end) && same_bytes(a.stop, b.stop) &&
         same_bytes(a.merged_with, b.merged_with);
}

TraceResult trace_with_threads(const Job& job, const Fields& fields, const TraceOptions& options,
                               int threads) {
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism,
                            static_cast<std::size_t>(threads));
  return trace_paths(job.mesh, fields, options);
}

void run(const Job& job, const std::vector<double>& min_steps) {
  FieldOptions options;
  options.resolution = job.resolution;
  options.max_memory_gb = 16.0;
  const auto t0 = std::chrono::steady_clock::now();
  const std::unique_ptr<Fields> fields = build_fields(job.mesh, options);
  const double field_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  for (const double min_step : min_steps) {
    TraceOptions trace;
    trace.min_step = min_step;
    const TraceResult one = trace_with_threads(job, *fields, trace, 1);
    const TraceResult two = trace_with_threads(job, *fields, trace, 2);
    const double total1 = one.seconds_tracing + one.seconds_merging;
    for (const TraceResult* r : {&one, &two}) {
      const int threads = r == &one ? 1 : 2;
      const double total = r->seconds_tracing + r->seconds_merging;
      char speed_up[32];
      std::snprintf(speed_up, sizeof speed_up, "%.2f", total > 0 ? total1 / total : 0.0);
      std::printf(
          "| %s | %zu | %d | %.2f | %g | %d | %.3f | %.3f | %.3f | %.0f | %s | %zu/%zu/%zu/%zu "
          "| %.1f | %s |\n",
          job.label.c_str(), job.mesh.triangles.size(), job.resolution, field_seconds, min_step,
          threads, r->seconds_tracing, r->seconds_merging, total,
          total > 0 ? static_cast<double>(r->num_traces()) / total : 0.0, speed_up,
          r->stops(StopReason::kCritical), r->stops(StopReason::kMerge),
          r->stops(StopReason::kFlux), r->stops(StopReason::kCap),
          static_cast<double>(r->samples.size()) / static_cast<double>(r->num_traces()),
          threads == 1 ? "" : (identical(one, two) ? "yes" : "NO"));
      std::fflush(stdout);
    }
  }
}

using test::largest_deviation;
using test::rotated;
using test::StraightTrace;

void run_straightness() {
  const std::vector<test::StraightCase> cases = test::straight_trace_cases();
  std::printf(
      "| shape | straight traces | step, voxels | Euler | RK2 | RK4 |\n"
      "|---|---|---|---|---|---|\n");
  for (const test::StraightCase& c : cases) {
    FieldOptions options;
    options.resolution = 128;
    const std::unique_ptr<Fields> fields = build_fields(c.mesh, options);
    const double voxel = fields->voxel_size();
    for (const double step_voxels : {0.5, 2.0}) {
      std::printf("| %s | %zu | %g |", c.name.c_str(), c.straight.size(), step_voxels);
      for (const Integrator integ : {Integrator::kEuler, Integrator::kRk2, Integrator::kRk4}) {
        TraceOptions trace;
        trace.integrator = integ;
        trace.step = step_voxels * voxel;
        const TraceResult r = trace_paths(c.mesh, *fields, trace);
        std::printf(" %.3f |", largest_deviation(r, c.straight, voxel));
      }
      std::printf("\n");
      std::fflush(stdout);
    }
  }
}

}  // namespace
}  // namespace vdb_shell

int main(int argc, char** argv) {
  using namespace vdb_shell;
  try {
    bool large = true;
    std::vector<Job> jobs;
    std::vector<double> min_steps;
    for (int a = 1; a < argc; ++a) {
      std::string arg = argv[a];
      if (arg == "--no-large") {
        large = false;
        continue;
      }
      if (arg == "--min-step" && a + 1 < argc) {
        min_steps.push_back(std::atof(argv[++a]));
        continue;
      }
      if (arg == "--straightness") {
        run_straightness();
        return 0;
      }
      int res = 128;
      const auto at = arg.rfind('@');
      if (at != std::string::npos) {
        res = std::atoi(arg.c_str() + at + 1);
        arg = arg.substr(0, at);
      }
      SurfaceMesh mesh = std::filesystem::exists(arg) ? load_surface(arg).mesh : make_shape(arg);
      jobs.push_back({std::filesystem::path(arg).filename().string(), std::move(mesh), res});
    }
    if (jobs.empty()) {
      for (const char* name : {"box", "cylinder", "pointy", "horn", "tube", "sphere", "funnel",
                               "propeller", "star", "bowl", "torus"})
        jobs.push_back({name, make_shape(name), 128});
      if (large) {
        const std::string fandisk = std::string(VDB_SHELL_SHARED_MESHES) + "/fandisk.obj";
        if (std::filesystem::exists(fandisk))
          jobs.push_back({"fandisk", load_surface(fandisk).mesh, 512});
        else
          std::fprintf(stderr, "skipping fandisk: %s not found\n", fandisk.c_str());
        jobs.push_back({"box (detail 46)", make_shape("box", 46), 512});
      }
    }
    std::printf(
        "| mesh | faces | resolution | fields, s (all threads) | min step | threads | trace, s "
        "| merge, s | total, s | traces/s | speed-up | stops crit/merge/flux/cap "
        "| samples/trace | same as 1 thread |\n"
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    if (min_steps.empty()) min_steps.push_back(TraceOptions{}.min_step);
    for (const Job& job : jobs) run(job, min_steps);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "vdb_shell_bench_traces: %s\n", e.what());
    return 1;
  }
  return 0;
}
