// trace.cpp — classification, path tracing and order-independent merge resolution; see trace.h.
#include "core/trace/trace.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "core/base/errors.h"
#include "core/base/memory_budget.h"
#include "core/base/parallel.h"
#include "core/base/timer.h"
#include "core/trace/merges.h"

namespace vdb_shell {
namespace {

/// grad(phi) normalised only when longer than one (paper: counters numerical diffusion).
Vec3d clamp_unit(const Vec3d& g) {
  const double n2 = norm2(g);
  return n2 > 1.0 ? g / std::sqrt(n2) : g;
}

/// One step of the chosen integrator from q (gradient g at q already sampled); returns the
/// displacement (to be subtracted).
Vec3d step_direction(FieldProbe& probe, const Vec3d& q, const Vec3d& g, double h,
                     Integrator integrator) {
  const Vec3d k1 = clamp_unit(g);
  switch (integrator) {
    case Integrator::kEuler:
      return k1;
    case Integrator::kRk2:
      return clamp_unit(probe.gradient(q - k1 * (0.5 * h)));
    case Integrator::kRk4: {
      const Vec3d k2 = clamp_unit(probe.gradient(q - k1 * (0.5 * h)));
      const Vec3d k3 = clamp_unit(probe.gradient(q - k2 * (0.5 * h)));
      const Vec3d k4 = clamp_unit(probe.gradient(q - k3 * h));
      return (k1 + 2.0 * k2 + 2.0 * k3 + k4) / 6.0;
    }
  }
  return k1;
}

struct OneTrace {
  std::vector<Vec3d> samples;
  std::vector<double> arc;
  StopReason stop = StopReason::kCap;
};

/// The rows of `rows` as r's compressed traces, each ending at its last sample, unmerged.
void pack_traces(const std::vector<OneTrace>& rows, TraceResult& r) {
  const std::size_t n = rows.size();
  r.offsets.assign(n + 1, 0);
  for (std::size_t v = 0; v < n; ++v)
    r.offsets[v + 1] = r.offsets[v] + static_cast<std::uint32_t>(rows[v].samples.size());
  r.samples.resize(r.offsets[n]);
  r.arc_length.resize(r.offsets[n]);
  r.end.resize(n);
  r.stop.resize(n);
  r.merged_with.assign(n, -1);
  for_each_index(n, [&](std::size_t v) {
    std::copy(rows[v].samples.begin(), rows[v].samples.end(), r.samples.begin() + r.offsets[v]);
    std::copy(rows[v].arc.begin(), rows[v].arc.end(), r.arc_length.begin() + r.offsets[v]);
    r.end[v] = static_cast<std::uint32_t>(rows[v].samples.size() - 1);
    r.stop[v] = rows[v].stop;
  });
}

void trace_one(FieldProbe& probe, const Vec3d& p, bool planar, const TraceOptions& opt,
               const TraceParameters& par, OneTrace& t) {
  t.samples.assign(1, p);
  t.arc.assign(1, 0.0);
  const double g0 = norm2(probe.gradient(p));
  const double critical = opt.critical * (g0 > 0.0 ? g0 : 1.0);
  Vec3d q = p, prev_g;
  Vec3d paper_d;            // the last step's direction before min_step lengthened it
  bool lengthened = false;  // whether min_step lengthened the last step
  double prev_flux = -1.0;
  const auto step_to = [&](const Vec3d& next) {
    t.arc.push_back(t.arc.back() + distance(next, q));
    t.samples.push_back(next);
    q = next;
  };
  const auto drop_last = [&] {
    t.samples.pop_back();
    t.arc.pop_back();
  };
  for (int i = 0;; ++i) {
    const Vec3d g = probe.gradient(q);
    if (norm2(g) < critical) {
      t.stop = StopReason::kCritical;
      return;
    }
    if (i > 0 && dot(g, prev_g) < 0.0) {
      if (lengthened) {
        // The lengthened step passed where the gradient turns (a critical point, or across a
        // ridge the trace was following): the paper's step instead, so that traces settle on
        // critical points and follow ridges as the paper's do.
        drop_last();
        q = t.samples.back();
        step_to(q - paper_d * par.step);
        lengthened = false;
        continue;
      }
      // The critical point was passed: end at the deeper of the last two samples.
      if (probe.phi(q) > probe.phi(t.samples[t.samples.size() - 2])) drop_last();
      t.stop = StopReason::kCritical;
      return;
    }
    if (planar) {
      // Stop on the medial surface itself: at the peak of the flux once it exceeds rho.
      const double f = probe.flux(q);
      if (prev_flux > opt.flux_threshold && f <= prev_flux) {
        drop_last();
        t.stop = StopReason::kFlux;
        return;
      }
      prev_flux = f;
    }
    if (i >= par.max_steps) {
      t.stop = StopReason::kCap;
      return;
    }
    paper_d = step_direction(probe, q, g, par.step, opt.integrator);
    const double d2 = norm2(paper_d);
    lengthened = d2 > 0.0 && d2 < opt.min_step * opt.min_step;
    prev_g = g;
    step_to(q - (lengthened ? paper_d * (opt.min_step / std::sqrt(d2)) : paper_d) * par.step);
  }
}

/// Whether a vertex with these unit face normals is planar: every two within the angle whose
/// cosine is `cos_max`.
bool planar_fan(const std::vector<Vec3d>& normals, double cos_max) {
  for (std::size_t a = 0; a < normals.size(); ++a)
    for (std::size_t b = a + 1; b < normals.size(); ++b)
      if (dot(normals[a], normals[b]) < cos_max) return false;
  return true;
}

}  // namespace

const char* to_string(StopReason r) {
  switch (r) {
    case StopReason::kCritical:
      return "critical";
    case StopReason::kMerge:
      return "merge";
    case StopReason::kFlux:
      return "flux";
    case StopReason::kCap:
      return "cap";
  }
  return "?";
}

const char* to_string(Integrator i) {
  switch (i) {
    case Integrator::kEuler:
      return "euler";
    case Integrator::kRk2:
      return "rk2";
    case Integrator::kRk4:
      return "rk4";
  }
  return "?";
}

Integrator parse_integrator(const std::string& name) {
  if (name == "euler") return Integrator::kEuler;
  if (name == "rk2") return Integrator::kRk2;
  if (name == "rk4") return Integrator::kRk4;
  throw InputError("unknown integrator '" + name + "'; use euler, rk2 or rk4");
}

TraceParameters derive_trace_parameters(const TraceOptions& o, double voxel_size,
                                        const BBox& bounds) {
  auto check = [](double v, const char* what) {
    if (!std::isfinite(v) || v < 0.0)
      throw InputError(std::string(what) + " must be a finite, non-negative number (got " +
                       std::to_string(v) + "); 0 selects the default");
  };
  check(o.step, "--step");
  check(o.point_size, "--point-size");
  check(o.critical, "--critical");
  if (!(voxel_size > 0.0) || !std::isfinite(voxel_size))
    throw InputError("the voxel size must be positive");
  if (!(o.planar_angle >= 0.0 && o.planar_angle <= 180.0))
    throw InputError("--planar-angle must lie in [0, 180] degrees");
  if (!(o.merge_angle >= 0.0 && o.merge_angle <= 180.0))
    throw InputError("--merge-angle must lie in [0, 180] degrees");
  if (!(o.flux_threshold > -1.0 && o.flux_threshold < 1.0))
    throw InputError("--flux-threshold must lie in (-1, 1) (average outward flux)");
  if (!(o.min_step >= 0.0 && o.min_step <= 1.0))
    throw InputError("--min-step must lie in [0, 1] (a fraction of the step; 0: the paper's)");
  TraceParameters p;
  p.step = o.step > 0.0 ? o.step : 0.5 * voxel_size;
  p.point_size = o.point_size > 0.0 ? o.point_size : std::sqrt(3.0) * voxel_size;
  const double diag = bounds.empty() ? 0.0 : bounds.diagonal();
  p.max_steps =
      o.max_steps > 0 ? o.max_steps : static_cast<int>(std::min(4.0 * diag / p.step + 16.0, 1e8));
  p.cos_planar = std::cos(o.planar_angle * kPi / 180.0);
  p.cos_merge = std::cos(o.merge_angle * kPi / 180.0);
  return p;
}

std::vector<std::uint8_t> classify_vertices(const SurfaceMesh& mesh, double planar_angle_deg) {
  const double cos_max = std::cos(planar_angle_deg * kPi / 180.0);
  std::vector<std::vector<Vec3d>> normals(mesh.points.size());
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
    const Vec3d n = normalized(face_normal_area(mesh, f));
    for (std::uint32_t v : mesh.triangles[f]) normals[v].push_back(n);
  }
  std::vector<std::uint8_t> planar(mesh.points.size(), 1);
  for_each_index(mesh.points.size(),
                 [&](std::size_t v) { planar[v] = planar_fan(normals[v], cos_max); });
  return planar;
}

TraceEstimate estimate_traces(const SurfaceMesh& mesh, const FieldSampler& fields,
                              const TraceOptions& options) {
  TraceEstimate e;
  const std::size_t n = mesh.points.size();
  e.traces = n;
  if (n == 0) return e;
  const TraceParameters par =
      derive_trace_parameters(options, fields.voxel_size(), bounding_box(mesh));
  // Pilot i is vertex (2i + 1) n / (2 pilots): the middle of the i-th of `pilots` equal runs.
  const std::size_t pilots = std::min(n, kPilotTraces);
  std::vector<std::uint32_t> pilot(pilots), slot(n, UINT32_MAX);
  for (std::size_t i = 0; i < pilots; ++i) {
    pilot[i] = static_cast<std::uint32_t>((2 * i + 1) * n / (2 * pilots));
    slot[pilot[i]] = static_cast<std::uint32_t>(i);
  }
  std::vector<std::vector<Vec3d>> normals(pilots);  // as classify_vertices(), for the pilots
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f)
    for (std::uint32_t v : mesh.triangles[f])
      if (slot[v] != UINT32_MAX) normals[slot[v]].push_back(normalized(face_normal_area(mesh, f)));
  std::vector<std::size_t> samples(pilots, 0);
  for_each_chunk(pilots, [&](std::size_t begin, std::size_t end) {
    const std::unique_ptr<FieldProbe> probe = fields.probe();
    OneTrace t;
    for (std::size_t i = begin; i < end; ++i) {
      trace_one(*probe, mesh.points[pilot[i]], planar_fan(normals[i], par.cos_planar), options, par,
                t);
      samples[i] = t.samples.size();
    }
  });
  double sum = 0;
  for (const std::size_t s : samples) sum += double(s);  // in index order: deterministic
  e.pilot_traces = pilots;
  e.samples_per_trace = std::min(kPilotSafety * sum / double(pilots), double(par.max_steps) + 1.0);
  const double bytes = double(n) * (e.samples_per_trace * double(kTraceBytesPerSample) +
                                    double(kTraceBytesPerTrace));
  e.bytes = bytes >= 1e18 ? std::size_t(1e18) : static_cast<std::size_t>(bytes);
  return e;
}

std::size_t memory_bytes(const TraceResult& t) {
  return bytes_of(t.offsets) + bytes_of(t.samples) + bytes_of(t.arc_length) + bytes_of(t.end) +
         bytes_of(t.stop) + bytes_of(t.planar) + bytes_of(t.merged_with);
}

TraceResult retrace_split(const TraceResult& traces, const SurfaceMesh& surface,
                          const std::vector<std::uint32_t>& source,
                          const std::vector<Vec3d>& first_direction, const FieldSampler& fields,
                          const TraceOptions& options) {
  const std::size_t n = surface.points.size();
  TraceResult r;
  r.parameters = traces.parameters;
  r.planar = classify_vertices(surface, options.planar_angle);
  std::vector<OneTrace> rows(n);
  const std::unique_ptr<FieldProbe> probe = fields.probe();
  OneTrace scratch;  // as in trace_paths()
  for (std::size_t u = 0; u < n; ++u) {
    OneTrace& t = rows[u];
    if (norm2(first_direction[u]) == 0) {  // the traced surface's own trace
      const auto first = traces.offsets[source[u]], last = traces.offsets[source[u] + 1];
      t.samples.assign(traces.samples.begin() + first, traces.samples.begin() + last);
      t.arc.assign(traces.arc_length.begin() + first, traces.arc_length.begin() + last);
      t.stop = traces.stop[source[u]];
      continue;
    }
    const Vec3d p = surface.points[u];
    trace_one(*probe, p + first_direction[u] * r.parameters.step, r.planar[u] != 0, options,
              r.parameters, scratch);
    t.samples.reserve(scratch.samples.size() + 1);
    t.samples.push_back(p);
    t.samples.insert(t.samples.end(), scratch.samples.begin(), scratch.samples.end());
    t.arc.reserve(scratch.arc.size() + 1);
    t.arc.push_back(0.0);
    for (const double a : scratch.arc) t.arc.push_back(a + r.parameters.step);
    t.stop = scratch.stop;
  }
  pack_traces(rows, r);
  for (std::size_t u = 0; u < n; ++u)
    if (norm2(first_direction[u]) == 0) {  // ended where merges ended it
      r.end[u] = traces.end[source[u]];
      r.merged_with[u] = traces.merged_with[source[u]];
    }
  for (StopReason s : r.stop) ++r.stop_count[static_cast<std::size_t>(s)];
  return r;
}

TraceResult trace_paths(const SurfaceMesh& mesh, const FieldSampler& fields,
                        const TraceOptions& options, const StageMonitor& monitor) {
  TraceResult r;
  r.parameters = derive_trace_parameters(options, fields.voxel_size(), bounding_box(mesh));
  const std::size_t n = mesh.points.size();
  r.planar = classify_vertices(mesh, options.planar_angle);

  auto t0 = std::chrono::steady_clock::now();
  std::vector<OneTrace> traces(n);
  monitor.begin_part(0.0, 0.8, n);
  for_each_chunk(n, [&](std::size_t begin, std::size_t end) {
    const std::unique_ptr<FieldProbe> probe = fields.probe();
    // Traced in one reused row, then copied at their size: rows grown sample by sample would
    // copy each trace several times and hold up to twice its samples.
    OneTrace scratch;
    for (std::size_t v = begin; v < end; ++v) {
      trace_one(*probe, mesh.points[v], r.planar[v] != 0, options, r.parameters, scratch);
      traces[v] = scratch;
      monitor.advance();
    }
  });
  pack_traces(traces, r);
  traces.clear();
  r.seconds_tracing = seconds_since(t0);

  // Merges: non-planar among themselves, then planar against everything (paper Fig. 3).
  t0 = std::chrono::steady_clock::now();
  std::vector<std::uint32_t> non_planar, planar;
  for (std::uint32_t v = 0; v < n; ++v) (r.planar[v] ? planar : non_planar).push_back(v);
  resolve_merges(r, non_planar, non_planar);
  monitor.report(0.9);
  std::vector<std::uint32_t> all(n);
  for (std::uint32_t v = 0; v < n; ++v) all[v] = v;
  resolve_merges(r, planar, all);
  r.seconds_merging = seconds_since(t0);

  for (StopReason s : r.stop) ++r.stop_count[static_cast<std::size_t>(s)];
  return r;
}

}  // namespace vdb_shell
