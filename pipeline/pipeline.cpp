// pipeline.cpp — build_shell(): the stage sequence, the decisions between stages (the stored
// flux's threshold, the diagnosis of a shell that could not be made valid), the inner surface
// and the JSON report. The only place the pipeline is written down; the CLI, the Python module,
// the tests and the benchmarks call it.
#include "vdb_shell/vdb_shell.h"

#include "pipeline/html_report.h"

#include <tbb/task_arena.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>
#include <utility>

#include "core/base/memory_budget.h"
#include "core/base/timer.h"
#include "core/inner/sectors.h"
#include "core/validity/sector_shell.h"
#include "core/write/shell_writers.h"
#include "core/write/trace_writer.h"
#include "vdb_ops/trace_points.h"

namespace vdb_shell {
namespace {

void require(bool ok, const std::string& option, double value, const std::string& rule) {
  if (ok) return;
  std::ostringstream message;
  message << option << " " << value << ": " << rule;
  throw InputError(message.str());
}

/// `value` as messages print numbers (6 significant digits).
std::string text(double value) {
  std::ostringstream out;
  out << value;
  return out.str();
}

/// Runs `body` in a TBB arena of `threads` workers (0: the default arena, all cores).
template <class Body>
auto in_arena(int threads, const Body& body) {
  if (threads <= 0) return body();
  tbb::task_arena arena(threads);
  return arena.execute(body);
}

/// The message of a shell the search could not make valid. make_surface() refused every surface
/// that is not closed, 2-manifold and free of crossings, and for those a valid shell exists: a
/// failure is a bug.
[[noreturn]] void throw_invalid(const LoadedSurface& surface, const SectorSplit& split,
                                const ValidShell& valid) {
  const auto one_line = [](std::string text) {  // describe_problems(): one line per problem
    while (!text.empty() && text.back() == '\n') text.pop_back();
    std::replace(text.begin(), text.end(), '\n', ';');
    return text;
  };
  std::ostringstream message;
  message << surface.source << ": could not make the shell valid after " << valid.rounds
          << " rounds (" << one_line(describe_problems(valid.checks)) << ")";
  if (!valid.floor_valid)
    message << "; the thinnest shell is invalid too: " << one_line(valid.floor_problems);
  if (!split.empty()) {
    const std::uint32_t v = split.folded.front();
    const Vec3d& p = surface.mesh.points[v];
    message << "; " << split.folded.size() << " folded surface vertices split into "
            << split.sectors << " sectors (first: vertex " << v << " at (" << p.x << ", " << p.y
            << ", " << p.z << "))";
  }
  if (!valid.on_surface.empty()) {
    const std::uint32_t u = valid.on_surface.front(), v = split.empty() ? u : split.vertex[u];
    const Vec3d& p = surface.mesh.points[v];
    message << "; " << valid.on_surface.size()
            << " surface vertices kept on the surface (first: vertex " << v << " at (" << p.x
            << ", " << p.y << ", " << p.z << "))";
  }
  message << "; nothing was written — please report this input";
  throw InternalError(message.str());
}

/// A given level set (--level-set, a .vdb input) must be negative inside, as OpenVDB's level
/// sets are: phi a quarter voxel inside the centroids of up to 64 faces spread over the surface.
/// \throw InputError when most of them are positive (a grid of the other sign convention).
void check_level_set_sign(const LoadedSurface& surface, const FieldSampler& fields,
                          const std::string& level_set) {
  const SurfaceMesh& mesh = surface.mesh;
  const std::size_t faces = mesh.triangles.size(), samples = std::min<std::size_t>(faces, 64);
  const std::unique_ptr<FieldProbe> probe = fields.probe();
  std::size_t positive = 0;
  for (std::size_t i = 0; i < samples; ++i) {
    const std::size_t f = i * faces / samples;
    const Triangle& t = mesh.triangles[f];
    const Vec3d centroid = (mesh.points[t[0]] + mesh.points[t[1]] + mesh.points[t[2]]) / 3.0;
    const Vec3d inside =
        centroid - normalized(face_normal_area(mesh, f)) * (0.25 * fields.voxel_size());
    positive += probe->phi(inside) > 0;
  }
  if (2 * positive <= samples) return;
  throw InputError(level_set +
                   ": the level set is positive inside the surface (phi > 0 just "
                   "inside " +
                   std::to_string(positive) + " of " + std::to_string(samples) + " faces of " +
                   surface.source +
                   "); vdb_shell needs OpenVDB's convention, negative inside: negate the grid");
}

// Memory held between stages, bytes (the buffers of each container: core/base/memory_budget.h).

std::size_t memory_bytes(const SurfaceMesh& m) {
  return bytes_of(m.points) + bytes_of(m.triangles);
}

std::size_t memory_bytes(const TetMesh& m) {
  return bytes_of(m.points) + bytes_of(m.tets) + bytes_of(m.quality) + bytes_of(m.source_triangle) +
         bytes_of(m.inner) + bytes_of(m.thickness) + bytes_of(m.surface_vertex);
}

std::size_t memory_bytes(const SectorSplit& s) {
  return memory_bytes(s.surface) + bytes_of(s.vertex) + bytes_of(s.direction) +
         bytes_of(s.constraints) + bytes_of(s.folded) + bytes_of(s.unsplit) +
         bytes_of(s.boundaries);
}

std::size_t memory_bytes(const InnerVertices& in) {
  return bytes_of(in.input.inner_points) + bytes_of(in.input.inner_id) +
         bytes_of(in.input.cap_faces) + bytes_of(in.input.cap_points) + bytes_of(in.arc) +
         bytes_of(in.limit) + bytes_of(in.constraints);
}

/// The fields a result holds, bytes (0 unless kept).
std::size_t fields_bytes(const ShellResult& r) { return r.fields ? r.field_stats.grid_bytes : 0; }

/// What a finished result holds while it is written, bytes: the result (shell, inner surface,
/// surface, traces, kept fields) and the caller's surface (as large as the result's copy).
std::size_t result_bytes(const ShellResult& r) {
  return 2 * memory_bytes(r.surface) + memory_bytes(r.mesh) + memory_bytes(r.inner_surface) +
         memory_bytes(r.traces) + fields_bytes(r);
}

/// MemoryEstimates::write_shell, ::write_html and ::write_fields of a result.
std::size_t write_shell_estimate(const ShellResult& r) {
  return kProgramBytes + result_bytes(r) + estimate_write_bytes(r.mesh);
}
std::size_t write_html_estimate(const ShellResult& r) {
  return r.mesh.tets.empty()
             ? 0
             : kProgramBytes + result_bytes(r) + estimate_html_bytes(r.surface, r.mesh);
}
std::size_t write_fields_estimate(const ShellResult& r) {
  return r.fields
             ? kProgramBytes + result_bytes(r) + estimate_write_grids_bytes(*r.fields, &r.traces)
             : 0;
}

std::string count(std::size_t n, const char* what) { return std::to_string(n) + " " + what; }

/// The inner side as a surface; a vertex kept on the surface is its own inner vertex.
SurfaceMesh inner_surface_of(const SurfaceMesh& mesh, const ShellInput& input) {
  SurfaceMesh inner;
  inner.points = input.inner_points;
  std::vector<std::uint32_t> id = input.inner_id;
  for (std::uint32_t v = 0; v < id.size(); ++v)
    if (id[v] == kOnSurface) {
      id[v] = static_cast<std::uint32_t>(inner.points.size());
      inner.points.push_back(mesh.points[v]);
    }
  inner.triangles.reserve(mesh.triangles.size());
  for (const Triangle& t : mesh.triangles)
    inner.triangles.push_back({id[t[0]], id[t[2]], id[t[1]]});
  return inner;
}

/// OpenVDB's linear maps refuse voxels under min_voxel_size() (1.44e-5 units: a surface under
/// ~2e-3 units across at 128^3), and volumes and squared lengths of voxels over 2^32 units
/// (a surface 1e100 units across) overflow. Such a surface is shelled at 2^k times its size, k
/// making the voxel size 1/128 to 1/64, and the results are scaled back: multiplying by a power of
/// two is exact both ways, so the shell is exactly the scaled surface's shell, scaled. 0 for voxels
/// in between (the output is then the unscaled run's, to the byte).
int field_scale_exponent(double voxel_size) {
  if (!(voxel_size > 0) || (voxel_size >= 2 * min_voxel_size() && voxel_size <= 0x1p32)) return 0;
  return -std::ilogb(voxel_size) - 7;
}

/// The voxel size of the fields build_fields() would build for `mesh`, world units.
double planned_voxel_size(const SurfaceMesh& mesh, const FieldOptions& options) {
  return options.voxel_size > 0 ? options.voxel_size
                                : bounding_box(mesh).max_side() / options.resolution;
}

/// `options` with every length scaled by 2^k (the dimensionless ones as they are; a negative
/// weld tolerance, "the default", stays negative).
ShellOptions scaled_options(ShellOptions o, int k) {
  for (double* length :
       {&o.fields.voxel_size, &o.trace.step, &o.trace.point_size, &o.thickness.max_thickness,
        &o.thickness.weld_tolerance, &o.repair_voxel_size})
    *length = std::ldexp(*length, k);
  return o;
}

/// Scales every length a result holds by 2^k: the shell, the inner surface, the traces, the
/// voxel size and the volumes. The surface and the options are the caller's to set.
void scale_result(ShellResult& r, int k) {
  scale_by_power_of_two(r.mesh.points, k);
  for (double& t : r.mesh.thickness) t = std::ldexp(t, k);
  scale_by_power_of_two(r.inner_surface.points, k);
  scale_by_power_of_two(r.traces.samples, k);
  for (double& a : r.traces.arc_length) a = std::ldexp(a, k);
  for (double* length :
       {&r.traces.parameters.step, &r.traces.parameters.point_size, &r.field_stats.voxel_size})
    *length = std::ldexp(*length, k);
  r.quality.shell_volume = std::ldexp(r.quality.shell_volume, 3 * k);
  r.quality.enclosed_volume = std::ldexp(r.quality.enclosed_volume, 3 * k);
}

ShellResult run(const LoadedSurface& surface, const ShellOptions& options,
                const RunControl& control) {
  const auto t_total = Clock::now();
  // The shell is built on the input with its zero-area faces flipped away (if any), and joined
  // to the input itself at the end.
  const SurfaceMesh flipped =
      surface.zero_area.empty() ? SurfaceMesh{} : flipped_surface(surface.mesh, surface.zero_area);
  const SurfaceMesh& mesh = surface.zero_area.empty() ? surface.mesh : flipped;
  ShellResult r;
  MemoryEstimates& memory = r.memory;
  const std::size_t budget = memory.budget = budget_bytes(options.fields.max_memory_gb);
  // Every estimate counts the program and the surface twice: the caller's and the result's copy.
  const std::size_t surfaces = kProgramBytes + 2 * memory_bytes(mesh);
  memory.surface = surfaces;
  check_memory_budget("surface", memory.surface, budget,
                      "the program and the surface (" + count(mesh.points.size(), "vertices") +
                          ", " + count(mesh.triangles.size(), "faces") + ", with the run's copy)",
                      "give a surface with fewer faces or raise --max-memory");
  r.options = options;
  r.input = {surface.source, surface.stats, surface.flipped, surface.flipped_components};
  r.surface = surface.mesh;
  r.notices = surface.notices;

  std::shared_ptr<const Fields> fields;
  SectorSplit split;
  TraceResult split_traces;
  {
    const auto t0 = Clock::now();
    StageMonitor monitor(control, "fields");
    ActiveStage active(monitor);
    // The flux grid stores |flux| >= flux_min only: keep it at most rho / 2 (fields.h) so a
    // smaller flux threshold still sees every value it asks about.
    FieldOptions field_options = options.fields;
    field_options.flux_min =
        std::clamp(0.5 * options.trace.flux_threshold, 1e-3, field_options.flux_min);
    fields = options.level_set.empty() ? build_fields(mesh, field_options, monitor)
                                       : fields_from_level_set(options.level_set, options.grid_name,
                                                               mesh, field_options, monitor);
    if (!options.level_set.empty()) check_level_set_sign(surface, *fields, options.level_set);
    monitor.finish();
    r.timings.fields = seconds_since(t0);
  }
  r.field_stats = fields->stats();
  memory.fields = r.field_stats.estimated_bytes;
  const std::size_t grids = r.field_stats.grid_bytes;
  r.notices.insert(r.notices.end(), r.field_stats.notices.begin(), r.field_stats.notices.end());
  if (options.keep_fields) r.fields = fields;

  {
    const auto t0 = Clock::now();
    StageMonitor monitor(control, "trace");
    ActiveStage active(monitor);
    // Folded vertices: their fans split into sectors, each traced from the vertex along its
    // own inward direction (core/inner/sectors.h).
    if (!options.traces_only) split = split_folded_vertices(mesh);
    // The traces of the split surface (retrace_split()) peak at the same bytes per sample as
    // trace_paths(), for as many traces as the split surface has points.
    const TraceEstimate estimate = estimate_traces(mesh, *fields, options.trace);
    const double traces = double(split.empty() ? mesh.points.size() : split.surface.points.size());
    memory.trace = surfaces + grids + memory_bytes(split) +
                   static_cast<std::size_t>(double(estimate.bytes) * traces /
                                            double(std::max<std::size_t>(estimate.traces, 1)));
    check_memory_budget("trace", memory.trace, budget,
                        "the traces (" + count(std::size_t(traces), "traces") + " x about " +
                            std::to_string(std::llround(estimate.samples_per_trace)) +
                            " samples, from " + std::to_string(estimate.pilot_traces) +
                            " traced ahead), with " + format_gib(double(grids)) + " of fields held",
                        "lower --resolution or raise --step, or raise --max-memory");
    r.traces = trace_paths(mesh, *fields, options.trace, monitor);
    if (!split.empty())
      split_traces = retrace_split(r.traces, split.surface, split.vertex, split.direction, *fields,
                                   options.trace);
    monitor.finish();
    r.timings.trace = seconds_since(t0);
  }
  if (!options.keep_fields) fields.reset();  // the fields are not needed past the traces
  if (options.traces_only) {
    memory.write_fields = write_fields_estimate(r);
    r.timings.total = seconds_since(t_total);
    return r;
  }

  // The shell is built on the split surface (the input where nothing is folded).
  const SurfaceMesh& work = split.empty() ? mesh : split.surface;
  const TraceResult& work_traces = split.empty() ? r.traces : split_traces;
  // Held from here on: the traces (and the split surface's), the fields only when kept.
  const std::size_t traces_held =
      memory_bytes(r.traces) + memory_bytes(split_traces) + memory_bytes(split);
  const std::size_t held = surfaces + fields_bytes(r) + traces_held;
  const std::string with_traces = ", with " + format_gib(double(traces_held)) + " of traces held";
  InnerVertices inner;
  {
    const auto t0 = Clock::now();
    StageMonitor monitor(control, "inner");
    memory.inner = held + estimate_inner_bytes(work);
    check_memory_budget(
        "inner", memory.inner, budget,
        "the inner vertices of " + count(work.points.size(), "traces") + with_traces,
        "lower --resolution or raise --step (shorter traces), or raise --max-memory");
    inner = place_inner_vertices(work, work_traces, options.thickness, split.vertex);
    inner.constraints = split.constraints;
    monitor.finish();
    r.timings.inner = seconds_since(t0);
  }
  {
    const auto t0 = Clock::now();
    StageMonitor monitor(control, "validity");
    ActiveStage active(monitor);
    const int layers = options.validity.layers;
    const std::size_t search = estimate_validity_bytes(work, layers);
    memory.validity = held + memory_bytes(inner) + search;
    check_memory_budget(
        "validity", memory.validity, budget,
        "the validity search and the shell (" + count(work.triangles.size(), "prisms") +
            ", up to " + count(3 * std::size_t(layers) * work.triangles.size(), "tets") + ")" +
            with_traces,
        search >= traces_held
            ? "give a surface with fewer faces, or raise --max-memory"
            : "lower --resolution or raise --step (shorter traces), or give a surface with fewer "
              "faces, or raise --max-memory");
    const auto optimize = [&](ValidShell& valid, ShellChecker& checker) {
      if (!options.optimize.enabled) return;
      const QualitySummary before = summarize_quality(work, valid.shell.mesh);
      r.optimize.min_quality_before = before.min_quality;
      r.optimize.p5_quality_before = before.p5_quality;
      r.optimize.min_dihedral_deg_before = before.min_dihedral_deg;
      r.optimize.coverage_before = before.coverage;
      r.optimize.report = optimize_shell(work, inner.limit, valid, options.optimize, checker);
    };
    ValidShell valid =
        make_valid_shell(work, work_traces, inner, options.validity, monitor, optimize);
    if (valid.checks.valid() && !split.empty()) {
      const SectorShell sectors = join_sectors(mesh, split, valid, options.validity.min_quality);
      r.validity.gap_tets = sectors.gap_tets;
    }
    if (valid.checks.valid() && !surface.zero_area.empty())
      join_zero_area_faces(surface.mesh, surface.zero_area, r.validity.gap_tets, valid);
    r.validity.flat_tets = surface.zero_area.tets.size();
    QualityOptions flat;
    flat.flat_tets = r.validity.flat_tets;
    r.quality = summarize_quality(surface.mesh, valid.shell.mesh, flat);
    r.timings.validity = seconds_since(t0);
    if (!valid.checks.valid()) throw_invalid(surface, split, valid);
    monitor.finish();
    r.timings.check = valid.checks.seconds;

    const AssembleResult& shell = valid.shell;
    r.counts.dropped_degenerate_tets = shell.dropped_degenerate_tets;
    r.counts.collapsed_prisms = shell.collapsed_prisms;
    r.counts.welded_vertices = inner.welded - std::min(inner.welded, valid.unwelded);
    r.counts.thickness_limited_vertices = inner.limited;
    r.validity.rounds = valid.rounds;
    r.validity.checks_run = valid.checks_run;
    r.validity.moved_back_vertices = valid.moved_back;
    r.validity.moved_back_mean_fraction = valid.moved_back_mean;
    r.validity.unwelded_vertices = valid.unwelded;
    r.validity.folded_vertices = split.folded.size();
    r.validity.sectors = split.sectors;
    r.validity.on_surface_vertices = valid.on_surface.size();
    r.validity.cap_faces = valid.cap_faces;
    r.validity.following_vertices = valid.followers;
    r.validity.floor_drops = valid.floor_drops;
    r.validity.floor_valid = valid.floor_valid;
    r.validity.seconds = valid.seconds;
    r.checks = std::move(valid.checks);
    r.inner_surface = inner_surface_of(work, valid.input);
    r.mesh = std::move(valid.shell.mesh);
  }
  memory.write_shell = write_shell_estimate(r);
  memory.write_fields = write_fields_estimate(r);
  memory.write_html = write_html_estimate(r);
  r.timings.total = seconds_since(t_total);
  return r;
}

}  // namespace

void check_options(const ShellOptions& o) {
  const FieldOptions& f = o.fields;
  if (f.voxel_size <= 0)
    require(f.resolution >= kMinResolution && f.resolution <= 16384, "--resolution", f.resolution,
            "must be in [" + std::to_string(kMinResolution) + ", 16384]");
  require(std::isfinite(f.voxel_size) && f.voxel_size >= 0, "--voxel-size", f.voxel_size,
          "must be a length >= 0 (0: use --resolution)");
  require(std::isfinite(f.max_memory_gb) && f.max_memory_gb > 0, "--max-memory", f.max_memory_gb,
          "must be a positive number of GiB");
  const ThicknessOptions& t = o.thickness;
  require(std::isfinite(t.max_thickness) && t.max_thickness >= 0, "--max-thickness",
          t.max_thickness, "must be >= 0 (0: as thick as possible)");
  require(std::isfinite(t.edge_factor) && t.edge_factor >= 0, "--thickness-edge-factor",
          t.edge_factor, "must be >= 0 (0: no limit)");
  require(o.validity.min_quality >= 0 && o.validity.min_quality <= 0.5, "--min-quality",
          o.validity.min_quality, "must be in [0, 0.5]");
  require(o.validity.layers >= 1 && o.validity.layers <= kMaxLayers, "--layers", o.validity.layers,
          "must be in [1, " + std::to_string(kMaxLayers) + "]");
  require(std::isfinite(o.validity.layer_ratio) && o.validity.layer_ratio >= 0.1 &&
              o.validity.layer_ratio <= 10,
          "--layer-ratio", o.validity.layer_ratio, "must be in [0.1, 10]");
  require(o.optimize.max_coverage_loss >= 0 && o.optimize.max_coverage_loss <= 0.1,
          "--max-coverage-loss", o.optimize.max_coverage_loss, "must be in [0, 0.1]");
  require(o.trace.min_step >= 0 && o.trace.min_step <= 1, "--min-step", o.trace.min_step,
          "must be in [0, 1] (a fraction of the step; 0: the paper's)");
  require(o.adaptivity >= 0 && o.adaptivity <= 1, "--adaptivity", o.adaptivity,
          "must be in [0, 1]");
  require(o.threads >= 0, "--threads", o.threads, "must be >= 0 (0: all cores)");
  require(std::isfinite(o.repair_voxel_size) && o.repair_voxel_size >= 0, "--repair-voxel-size",
          o.repair_voxel_size, "must be a length >= 0 (0: the fields' voxel size)");
  require(std::isfinite(o.repair_closing) && o.repair_closing >= 1, "--repair-closing",
          o.repair_closing, "must be at least 1 voxel");
}

LoadedSurface load_repaired_surface(const PolygonSoup& soup, const std::string& source,
                                    const ShellOptions& options, RepairReport& report) {
  check_options(options);
  RepairOptions repair;
  repair.closing = options.repair_closing;
  repair.adaptivity = options.adaptivity;
  repair.max_memory_gb = options.fields.max_memory_gb;
  repair.voxel_size =
      options.repair_voxel_size > 0 ? options.repair_voxel_size : options.fields.voxel_size;
  if (repair.voxel_size <= 0) {  // the fields' voxel size: the longest side / --resolution
    BBox box;
    for (const Vec3d& p : soup.points)
      if (is_finite(p)) box.expand(p);
    repair.voxel_size = box.empty() ? 0.0 : box.max_side() / options.fields.resolution;
  }
  if (!(repair.voxel_size > 0))
    throw InputError(source + ": nothing to repair: its points span no length");
  // A surface that validates as it is needs no rebuilding: kept, exactly (validation's own
  // fixes, e.g. an inward surface flipped, still apply).
  const auto t0 = Clock::now();
  try {
    LoadedSurface kept = make_surface(soup, source);
    report = RepairReport{};
    report.kept = true;
    report.voxel_size = repair.voxel_size;
    report.closing = repair.closing;
    report.input_faces = soup.polygons.size();
    report.faces = kept.mesh.triangles.size();
    report.seconds = seconds_since(t0);
    kept.notices.insert(kept.notices.begin(),
                        std::string(kept.notices.empty() ? "the input is already"
                                                         : "the input, mended as the notes below "
                                                           "say, is") +
                            " closed, 2-manifold and not crossing itself: --repair kept it as it "
                            "is");
    return kept;
  } catch (const InputError&) {  // something to repair
  }
  // The repair's volume has the voxels of the fields: built at 2^k times the size when they are
  // too small for OpenVDB (field_scale_exponent()), scaled back exactly.
  const int k = field_scale_exponent(repair.voxel_size);
  PolygonSoup rebuilt;
  if (k == 0) {
    rebuilt = repair_surface(soup, repair, source, report);
  } else {
    PolygonSoup scaled = soup;
    scale_by_power_of_two(scaled.points, k);
    repair.voxel_size = std::ldexp(repair.voxel_size, k);
    rebuilt = repair_surface(scaled, repair, source, report);
    scale_by_power_of_two(rebuilt.points, -k);
    for (double* length : {&report.voxel_size, &report.distance_max, &report.distance_mean,
                           &report.input_distance_max, &report.input_distance_mean,
                           &report.solid_input_distance_max})
      *length = std::ldexp(*length, -k);
  }
  try {
    LoadedSurface surface = make_surface(rebuilt, source + " (repaired)");
    surface.notices.insert(
        surface.notices.begin(),
        "the input was rebuilt watertight (--repair): " + std::to_string(report.input_faces) +
            " polygons -> " + std::to_string(surface.mesh.triangles.size()) + " triangles");
    return surface;
  } catch (const InputError& e) {
    throw InternalError(std::string("the repaired surface is not valid (please report): ") +
                        e.what());
  }
}

ShellResult build_shell(const LoadedSurface& surface, const ShellOptions& options,
                        const RunControl& control) {
  check_options(options);
  if (surface.mesh.triangles.empty())
    throw InputError(surface.source + ": the surface has no triangles; give a closed surface");
  const double h = planned_voxel_size(surface.mesh, options.fields);
  const int k = options.level_set.empty() ? field_scale_exponent(h) : 0;
  if (k == 0) return in_arena(options.threads, [&] { return run(surface, options, control); });
  const char* why =
      k > 0 ? " is below the smallest OpenVDB accepts (" : " is above the largest kept (";
  const std::string limit = text(k > 0 ? min_voxel_size() : 0x1p32) + " units)";
  if (options.keep_fields)
    throw InputError(surface.source + ": its voxel size " + text(h) + why + limit +
                     ": to keep or write the fields, give its coordinates in a " +
                     (k > 0 ? "smaller unit (e.g. millimetres instead of metres)" : "larger unit"));
  LoadedSurface scaled = surface;
  scale_by_power_of_two(scaled.mesh.points, k);
  ShellResult r =
      in_arena(options.threads, [&] { return run(scaled, scaled_options(options, k), control); });
  scale_result(r, -k);
  r.options = options;
  r.input = {surface.source, surface.stats, surface.flipped, surface.flipped_components};
  r.surface = surface.mesh;
  r.notices.push_back("the voxel size " + text(h) + why + limit + ": the shell was built at 2^" +
                      std::to_string(k) + " times the surface's size and scaled back exactly");
  return r;
}

ShellResult build_shell(const SurfaceMesh& mesh, const ShellOptions& options,
                        const RunControl& control, const std::string& source) {
  return build_shell(make_surface(polygon_soup_of(mesh), source), options, control);
}

LoadedSurface load_level_set_surface(const std::string& vdb_path, const ShellOptions& options,
                                     RepairReport* repair) {
  // volume_to_soup() checks the adaptivity.
  const VolumeSurface volume =
      volume_to_soup(vdb_path, options.grid_name, options.adaptivity, options.repair);
  if (!options.repair) return make_surface(volume.soup, vdb_path);
  RepairReport report;
  LoadedSurface surface = load_repaired_surface(volume.soup, vdb_path, options, report);
  report.grid = volume.where;
  report.grid_class = volume.grid_class;
  report.isovalue = volume.isovalue;
  report.positive_inside = volume.positive_inside;
  if (volume.grid_class != "level set" || volume.positive_inside) {
    std::ostringstream notice;
    notice << volume.where << " (class '" << volume.grid_class << "') was meshed at "
           << volume.isovalue << ", its solid where the values are "
           << (volume.positive_inside ? "larger" : "smaller");
    surface.notices.insert(surface.notices.begin(), notice.str());
  }
  if (repair) *repair = report;
  return surface;
}

ShellResult build_shell_from_level_set(const std::string& vdb_path, const ShellOptions& options,
                                       const RunControl& control) {
  if (!options.level_set.empty())
    throw InputError(
        "a .vdb input is its own level set: leave ShellOptions::level_set empty "
        "(--level-set)");
  if (options.repair) {  // the fields are the repaired surface's own, as for a mesh file
    RepairReport repair;
    ShellResult r =
        build_shell(load_level_set_surface(vdb_path, options, &repair), options, control);
    r.repair = repair;
    return r;
  }
  ShellOptions with_level_set = options;
  with_level_set.level_set = vdb_path;
  return build_shell(load_level_set_surface(vdb_path, options), with_level_set, control);
}

std::string report_json(const ShellResult& r, const ReportFiles& files, double read_seconds,
                        double write_seconds) {
  nlohmann::ordered_json j;
  const SurfaceStats& in = r.input.stats;
  const FieldStats& fs = r.field_stats;
  j["input"] = {{"file", r.input.source},     {"vertices", in.vertices},
                {"faces", in.faces},          {"components", in.components},
                {"genus", in.genus},          {"enclosed_volume", in.enclosed_volume},
                {"flipped", r.input.flipped}, {"flipped_components", r.input.flipped_components}};
  j["fields"] = {{"voxel_size", fs.voxel_size},
                 {"strategy", fs.strategy},
                 {"sdf_active_voxels", fs.sdf_active_voxels},
                 {"flux_active_voxels", fs.flux_active_voxels},
                 {"seconds",
                  {{"sdf", fs.seconds_sdf},
                   {"interior", fs.seconds_fill + fs.seconds_refine},
                   {"flux", fs.seconds_flux},
                   {"gradient", fs.seconds_gradient}}}};
  const TraceResult& traces = r.traces;
  j["trace"] = {
      {"step", traces.parameters.step},
      {"point_size", traces.parameters.point_size},
      {"integrator", to_string(r.options.trace.integrator)},
      {"min_step", r.options.trace.min_step},
      {"planar_vertices", std::count(traces.planar.begin(), traces.planar.end(), std::uint8_t{1})},
      {"samples", traces.samples.size()}};
  j["stop_reasons"] = {{"critical", traces.stops(StopReason::kCritical)},
                       {"merge", traces.stops(StopReason::kMerge)},
                       {"flux", traces.stops(StopReason::kFlux)},
                       {"cap", traces.stops(StopReason::kCap)}};
  if (!r.options.traces_only) {
    const ShellCheckResult& checks = r.checks;
    const ShellCounts& c = r.counts;
    j["shell"] = {{"file", files.shell},
                  {"layers", r.options.validity.layers},
                  {"layer_ratio", r.options.validity.layer_ratio},
                  {"tets", r.mesh.tets.size()},
                  {"points", r.mesh.points.size()},
                  {"coverage", r.quality.coverage},
                  {"shell_volume", r.quality.shell_volume},
                  {"inverted_tets", checks.inverted_tets},
                  {"zero_volume_tets", checks.zero_volume_tets},
                  {"intersecting_tet_pairs", checks.overlapping_pairs},
                  {"outside_inner_vertices", checks.outside_inner_vertices},
                  {"missing_surface_triangles", checks.missing_triangles},
                  {"dropped_degenerate_tets", c.dropped_degenerate_tets},
                  {"collapsed_prisms", c.collapsed_prisms},
                  {"welded_vertices", c.welded_vertices},
                  {"thickness_limited_vertices", c.thickness_limited_vertices},
                  {"valid", checks.valid()}};
    const ValidityReport& v = r.validity;
    j["validity"] = {{"rounds", v.rounds},
                     {"checks", v.checks_run},
                     {"moved_back_vertices", v.moved_back_vertices},
                     {"moved_back_mean_fraction", v.moved_back_mean_fraction},
                     {"unwelded_vertices", v.unwelded_vertices},
                     {"folded_vertices", v.folded_vertices},
                     {"sectors", v.sectors},
                     {"gap_tets", v.gap_tets},
                     {"flat_tets", v.flat_tets},
                     {"on_surface_vertices", v.on_surface_vertices},
                     {"following_vertices", v.following_vertices},
                     {"cap_faces", v.cap_faces},
                     {"floor_drops", v.floor_drops},
                     {"floor_valid", v.floor_valid},
                     {"seconds", v.seconds}};
    const QualitySummary& q = r.quality;
    j["quality"] = {{"min", q.min_quality},
                    {"p5", q.p5_quality},
                    {"median", q.median_quality},
                    {"mean", q.mean_quality},
                    {"min_dihedral_deg", q.min_dihedral_deg},
                    {"non_positive", q.non_positive},
                    {"histogram", q.histogram}};
    const OptimizeSummary& o = r.optimize;
    j["optimize"] = {{"enabled", r.options.optimize.enabled},
                     {"max_coverage_loss", r.options.optimize.max_coverage_loss},
                     {"sweeps", o.report.sweeps},
                     {"checks", o.report.checks},
                     {"moved_vertices", o.report.moved_vertices},
                     {"reverted_moves", o.report.reverted},
                     {"recut_quads", o.report.recut_quads},
                     {"reverted_cuts", o.report.reverted_cuts},
                     {"min_quality_before", o.min_quality_before},
                     {"p5_before", o.p5_quality_before},
                     {"min_dihedral_deg_before", o.min_dihedral_deg_before},
                     {"coverage_before", o.coverage_before},
                     {"seconds", o.report.seconds}};
  }
  if (r.repair) {
    const RepairReport& p = *r.repair;
    j["repair"] = {{"method", p.kept ? "kept" : "closing"},
                   {"voxel_size", p.voxel_size},
                   {"closing", p.closing},
                   {"input_faces", p.input_faces},
                   {"faces", p.faces},
                   {"components", r.input.stats.components},
                   {"holes_closed", p.holes_closed},
                   {"dropped_parts", p.dropped_parts},
                   {"collapsed_edges", p.collapsed_edges},
                   {"distance_max", p.distance_max},
                   {"distance_mean", p.distance_mean},
                   {"input_distance_max", p.input_distance_max},
                   {"input_distance_mean", p.input_distance_mean},
                   {"solid_input_distance_max", p.solid_input_distance_max},
                   {"solid_input_points", p.solid_input_points},
                   {"seconds", p.seconds}};
    if (!p.grid.empty())
      j["repair"]["volume"] = {{"grid", p.grid},
                               {"class", p.grid_class},
                               {"isovalue", p.isovalue},
                               {"positive_inside", p.positive_inside}};
  }
  const MemoryEstimates& m = r.memory;
  const auto gib = [](std::size_t bytes) { return double(bytes) / kBytesPerGiB; };
  j["memory_gb"] = {{"budget", gib(m.budget)},
                    {"surface", gib(m.surface)},
                    {"fields", gib(m.fields)},
                    {"trace", gib(m.trace)},
                    {"inner", gib(m.inner)},
                    {"validity", gib(m.validity)},
                    {"write_shell", gib(m.write_shell)},
                    {"write_fields", gib(m.write_fields)},
                    {"write_html", gib(m.write_html)}};
  const StageTimings& t = r.timings;
  j["timings_s"] = {{"read", read_seconds},
                    {"fields", t.fields},
                    {"trace", t.trace},
                    {"assemble", t.inner + t.validity},
                    {"check", t.check},
                    {"write", write_seconds},
                    {"total", read_seconds + t.total + write_seconds}};
  return j.dump(2) + "\n";
}

void write_shell(const std::string& path, const ShellResult& result, int msh_version) {
  if (result.options.traces_only)
    throw InputError(path + ": the run stopped after the traces (traces_only): no shell to write");
  check_memory_budget("write", write_shell_estimate(result),
                      budget_bytes(result.options.fields.max_memory_gb),
                      "writing the shell (" + count(result.mesh.tets.size(), "tets") + ", " +
                          count(result.mesh.points.size(), "points") + "), with " +
                          format_gib(double(result_bytes(result))) + " of results held",
                      "lower --resolution or raise --step, or raise --max-memory");
  write_tet_mesh(path, result.mesh, tet_format_from_path(path, msh_version));
}

void write_inner_surface(const std::string& path, const ShellResult& result) {
  if (result.options.traces_only)
    throw InputError(path + ": the run stopped after the traces (traces_only): no inner surface");
  write_surface(path, result.inner_surface);
}

void write_traces(const std::string& path, const ShellResult& result) {
  write_paths_vtk(path, result.traces);
}

void write_fields(const std::string& path, const ShellResult& result) {
  if (!result.fields)
    throw InputError(path +
                     ": the result holds no fields; build it with "
                     "ShellOptions::keep_fields");
  check_memory_budget(
      "write", write_fields_estimate(result), budget_bytes(result.options.fields.max_memory_gb),
      "writing the grids and the traces grid (" +
          count(trace_point_count(result.traces), "points") + ") of " + path + ", with " +
          format_gib(double(result_bytes(result))) + " of fields and results held",
      "lower --resolution or raise --step, or raise --max-memory");
  write_grids(path, *result.fields, result.fields->parameters(), &result.traces);
}

}  // namespace vdb_shell
