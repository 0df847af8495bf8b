// trace.h — vertex classification and path tracing (paper §2, Fig. 6; the trace stage of
// docs/architecture.md).
//
// Every surface vertex p is traced inward, q <- q - step * g with g = grad(phi)(q) normalised
// only when |g| > 1 (eq. 1, 2, 4, 5), or with a higher-order integrator of the same field; where
// |g| is smaller than `min_step` (beyond the paper, whose steps shrink with |g|: along a medial
// ridge, where |g| ~ 0.1, traces would crawl at a tenth of a step), g is lengthened to it, and
// where such a step passes a turn of g the paper's step is taken instead, so that traces still
// settle on critical points and follow ridges.
// A trace stops at
//   * a critical point: |g|^2 < c |g(p)|^2 (eq. 4), or g reversing direction (the point was
//     passed);
//   * the medial surface, for planar vertices only: flux(q) > rho (eq. 8), at the sample where
//     the flux peaks (the flux rises over ~2 voxels before the surface; its peak is on it);
//   * a safety cap on the number of steps.
// Merges (criterion 1) are then resolved order-independently (merges.h): each trace ends at its
// first sample (by arc length) that lies within the point size of a sample of another trace,
// where traces that *started* within the point size of each other, or that run within
// `merge_angle` of the same direction, never merge (they are neighbours running side by side, not
// a junction), and a trace does not merge into the last two point sizes of another (traces
// arriving together at a critical point end there and are welded, they do not stop short of it).
// Non-planar traces are resolved first; planar traces then merge with the (already ended)
// non-planar ones and with each other (paper Fig. 3). Every loop is parallel and each trace
// writes only its own slot: the result is identical for any thread count.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "core/base/run_control.h"
#include "core/base/surface_mesh.h"
#include "core/trace/field_sampler.h"

namespace vdb_shell {

enum class StopReason : std::uint8_t { kCritical = 0, kMerge = 1, kFlux = 2, kCap = 3 };
const char* to_string(StopReason r);

enum class Integrator : std::uint8_t { kEuler, kRk2, kRk4 };
const char* to_string(Integrator i);
/// Parses "euler", "rk2", "rk4"; throws InputError otherwise.
Integrator parse_integrator(const std::string& name);

/// What the user asked for (0 / negative = the documented default derived from the voxel size).
struct TraceOptions {
  double step = 0.0;            ///< world units; 0: half the voxel size (eq. 2)
  double critical = 1e-3;       ///< c of eq. 4 (dimensionless)
  double point_size = 0.0;      ///< world units; 0: one voxel diagonal (sqrt(3) voxels)
  double flux_threshold = 0.1;  ///< rho of eq. 8, on the average outward flux in [-1, 1]
  double planar_angle = 5.0;    ///< degrees; a vertex is planar when all incident face
                                ///< normals lie within this angle of each other
  double merge_angle = 60.0;    ///< degrees; traces meeting at a smaller angle do not merge
  Integrator integrator = Integrator::kRk2;
  double min_step = 0.25;  ///< the shortest step, as a fraction of `step`, in [0, 1] (paper: 0)
  int max_steps = 0;       ///< 0: 4 * (bbox diagonal / step) + 16
};

/// Step, point size and cap after defaults are applied — one pure function computes them.
struct TraceParameters {
  double step = 0;        ///< world units
  double point_size = 0;  ///< world units
  int max_steps = 0;
  double cos_planar = 1;  ///< cosine of planar_angle
  double cos_merge = 1;   ///< cosine of merge_angle
};
/// \throw InputError for non-positive or non-finite values the user gave explicitly.
TraceParameters derive_trace_parameters(const TraceOptions& options, double voxel_size,
                                        const BBox& bounds);

/// 1 for planar vertices, 0 for non-planar (sharp edges, corners, tips, curved regions).
std::vector<std::uint8_t> classify_vertices(const SurfaceMesh& mesh, double planar_angle_deg);

/// All traces, one per surface vertex, as compressed rows of samples.
struct TraceResult {
  std::vector<std::uint32_t> offsets;     ///< trace v's samples are [offsets[v], offsets[v+1])
  std::vector<Vec3d> samples;             ///< sample 0 of each trace is the surface vertex
  std::vector<double> arc_length;         ///< per sample, world units (eq. 5)
  std::vector<std::uint32_t> end;         ///< per trace: index of its end sample within the trace
  std::vector<StopReason> stop;           ///< per trace
  std::vector<std::uint8_t> planar;       ///< per trace
  std::vector<std::int64_t> merged_with;  ///< per trace: the other vertex, or -1

  TraceParameters parameters;
  std::array<std::size_t, 4> stop_count{};  ///< traces per StopReason (see stops())
  double seconds_tracing = 0;
  double seconds_merging = 0;

  std::size_t num_traces() const { return end.size(); }
  std::size_t num_samples(std::size_t v) const { return offsets[v + 1] - offsets[v]; }
  const Vec3d& sample(std::size_t v, std::size_t i) const { return samples[offsets[v] + i]; }
  const Vec3d& end_point(std::size_t v) const { return sample(v, end[v]); }
  double end_arc(std::size_t v) const { return arc_length[offsets[v] + end[v]]; }
  /// How many traces stopped for `reason`.
  std::size_t stops(StopReason reason) const {
    return stop_count[static_cast<std::size_t>(reason)];
  }
};

/// Peak bytes per trace sample while trace_paths() or retrace_split() runs: the traced rows (a
/// position and an arc length, 32 bytes, each row at its size) and their packed copy in the
/// TraceResult (32); retrace_split() also holds the traces it starts from (32). The merge grid
/// built after the rows are freed takes less: 28 bytes per sample and ~13 for its groups and cells
/// (measured 38-45 on fine meshes at 128 and 512). With rows that grew by doubling, 77-90 bytes per
/// sample were measured at the peak of the trace stage (fandisk, fertility, spot, sphere, torus,
/// box at resolutions 64 to 512): an upper bound of today's.
inline constexpr std::size_t kTraceBytesPerSample = 96;
/// Peak bytes per trace besides its samples: its row, the packed per-trace arrays, the
/// classification's face normals (transient) and the merge phase's lists.
inline constexpr std::size_t kTraceBytesPerTrace = 384;
/// Vertices estimate_traces() traces ahead (all of them when there are fewer).
inline constexpr std::size_t kPilotTraces = 256;
/// Factor on the pilot traces' mean samples per trace (a mean over 256 of thousands of traces).
inline constexpr double kPilotSafety = 1.25;

/// What trace_paths() will allocate, estimated before it runs.
struct TraceEstimate {
  std::size_t traces = 0;        ///< surface vertices
  std::size_t pilot_traces = 0;  ///< vertices traced for the estimate
  /// Samples per trace: the pilot traces' mean times kPilotSafety, at most max_steps + 1.
  double samples_per_trace = 0;
  /// Peak bytes of trace_paths(): traces * (samples_per_trace * kTraceBytesPerSample +
  /// kTraceBytesPerTrace).
  std::size_t bytes = 0;
};

/// Estimates the peak memory of trace_paths(mesh, fields, options) before it runs. How many
/// samples a trace takes depends on how it creeps towards the medial surface, where the gradient
/// shrinks (measured: 2 to 3.5 times its depth in steps), so it is measured: kPilotTraces
/// vertices spread evenly over the vertex indices are traced first, exactly as trace_paths()
/// traces them (merges only end traces earlier; their samples are kept). Allocates the pilot
/// traces and 4 bytes per vertex. Parameters as trace_paths().
/// 	hrow InputError as derive_trace_parameters().
TraceEstimate estimate_traces(const SurfaceMesh& mesh, const FieldSampler& fields,
                              const TraceOptions& options);

/// Bytes the vectors of `traces` hold.
std::size_t memory_bytes(const TraceResult& traces);

/// Traces every vertex of `mesh` through `fields` and resolves merges. Reports the fraction of
/// traces done to `monitor` (tracing is 80% of the stage, merging the rest) and checks it.
TraceResult trace_paths(const SurfaceMesh& mesh, const FieldSampler& fields,
                        const TraceOptions& options, const StageMonitor& monitor = StageMonitor());

/// The traces of a surface made from the traced one by splitting vertices (sectors.h): point u
/// takes trace source[u] of `traces` when first_direction[u] is zero; otherwise it gets a trace
/// of its own from its position, one straight step along first_direction[u] (a unit vector),
/// then through `fields` as trace_paths() traces (planar when u's faces in `surface` are), with
/// no merges. Parameters are those of `traces`, stop counts those of the result.
TraceResult retrace_split(const TraceResult& traces, const SurfaceMesh& surface,
                          const std::vector<std::uint32_t>& source,
                          const std::vector<Vec3d>& first_direction, const FieldSampler& fields,
                          const TraceOptions& options);

}  // namespace vdb_shell
