// cli.cpp — the vdb_shell command: option registry, validation of the whole command line before
// anything runs, the pipeline as a short sequence of stage calls, and the mapping of errors to
// exit codes. The only place (with main.cpp) that talks to the terminal.
#include "cli/cli.h"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>
#include <tbb/global_control.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <new>
#include <string>
#include <vector>

#include "core/assemble.h"
#include "core/atomic_file.h"
#include "core/errors.h"
#include "core/inner.h"
#include "core/paths_io.h"
#include "core/quality.h"
#include "core/shell_checks.h"
#include "core/trace.h"
#include "core/validate.h"
#include "core/validity.h"
#include "core/writers.h"
#include "vdb_ops/fields.h"
#include "vdb_ops/point_index_vdb.h"

#ifndef VDB_SHELL_VERSION
#define VDB_SHELL_VERSION "unknown"
#endif

namespace vdb_shell {
namespace {

/// What the user said on the command line (defaults are the documented ones).
struct CliOptions {
  std::string input;
  std::string output;
  std::string level_set;
  std::string grid_name;
  std::string grids;
  std::string paths;
  std::string inner;
  std::string report;
  int msh_version = 41;
  int threads = 0;
  std::string integrator = "rk2";
  bool quiet = false;
  bool verbose = false;
  FieldOptions fields;
  TraceOptions trace;
  ThicknessOptions thickness;
};

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

std::string fmt(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

std::string fmt(const Vec3d& v) { return "(" + fmt(v.x) + ", " + fmt(v.y) + ", " + fmt(v.z) + ")"; }

void print_summary(std::ostream& out, const std::string& path, const LoadedSurface& s) {
  const SurfaceStats& st = s.stats;
  out << "input       " << path << " (" << s.polygons_read << " polygons read)\n"
      << "vertices    " << st.vertices << "\n"
      << "faces       " << st.faces << "\n"
      << "edges       " << st.edges << "\n"
      << "components  " << st.components << "\n"
      << "genus       " << st.genus << "\n"
      << "bbox min    " << fmt(st.bbox.lo) << "\n"
      << "bbox max    " << fmt(st.bbox.hi) << "\n"
      << "bbox size   " << fmt(st.bbox.extent()) << "\n"
      << "mean edge   " << fmt(st.mean_edge_length) << "\n"
      << "volume      " << fmt(st.enclosed_volume) << "\n";
}

/// Checks every output path before any work: known extension, existing folder.
void check_outputs(const CliOptions& o) {
  namespace fs = std::filesystem;
  auto folder_exists = [](const std::string& path, const char* option) {
    const fs::path parent = fs::path(path).parent_path();
    if (!parent.empty() && !fs::is_directory(parent))
      throw InputError(std::string(option) + " " + path + ": the folder " + parent.string() +
                       " does not exist; create it first");
  };
  auto ext_is = [](const std::string& path, const char* ext) {
    return fs::path(path).extension() == ext;
  };
  if (!o.output.empty()) {
    tet_format_from_path(o.output, o.msh_version);
    folder_exists(o.output, "-o");
  }
  if (!o.grids.empty()) {
    if (!ext_is(o.grids, ".vdb")) throw InputError("--grids " + o.grids + ": must end in .vdb");
    folder_exists(o.grids, "--grids");
  }
  if (!o.paths.empty()) {
    if (!ext_is(o.paths, ".vtk")) throw InputError("--paths " + o.paths + ": must end in .vtk");
    folder_exists(o.paths, "--paths");
  }
  if (!o.inner.empty()) {
    if (!ext_is(o.inner, ".obj") && !ext_is(o.inner, ".ply") && !ext_is(o.inner, ".off"))
      throw InputError("--inner " + o.inner + ": use .obj, .ply or .off");
    folder_exists(o.inner, "--inner");
  }
  if (!o.report.empty()) folder_exists(o.report, "--report");
  if (o.output.empty() && (!o.paths.empty() || !o.inner.empty() || !o.report.empty()))
    throw InputError("--paths, --inner and --report describe a shell: give -o OUTPUT too");
}

int run(CliOptions opt, std::ostream& out, std::ostream& err) {
  const auto t_total = Clock::now();
  check_outputs(opt);
  opt.trace.integrator = parse_integrator(opt.integrator);

  auto t0 = Clock::now();
  const LoadedSurface surface = load_surface(opt.input);
  const double t_read = seconds_since(t0);
  if (!opt.quiet)
    for (const std::string& n : surface.notices) err << "vdb_shell: note: " << n << "\n";
  if (opt.output.empty() && opt.grids.empty()) {
    print_summary(out, opt.input, surface);
    return kExitOk;
  }
  const SurfaceMesh& mesh = surface.mesh;

  t0 = Clock::now();
  const std::unique_ptr<Fields> fields =
      opt.level_set.empty() ? build_fields(mesh, opt.fields)
                            : fields_from_level_set(opt.level_set, opt.grid_name, mesh, opt.fields);
  const double t_fields = seconds_since(t0);
  if (opt.verbose)
    err << "vdb_shell: fields: voxel " << fmt(fields->voxel_size()) << ", "
        << fields->stats().sdf_active_voxels << " SDF voxels, "
        << fields->stats().flux_active_voxels << " flux voxels, " << fmt(t_fields) << " s\n";

  double t_write = 0;
  if (opt.output.empty()) {  // --grids only
    t0 = Clock::now();
    write_grids(opt.grids, *fields, fields->parameters());
    if (!opt.quiet) err << "vdb_shell: wrote " << opt.grids << "\n";
    return kExitOk;
  }

  t0 = Clock::now();
  const TraceResult traces = trace_paths(mesh, *fields, opt.trace, make_vdb_point_index);
  const double t_trace = seconds_since(t0);

  t0 = Clock::now();
  const InnerVertices inner = place_inner_vertices(mesh, traces, opt.thickness);
  const ValidShell valid = make_valid_shell(mesh, traces, inner);
  const AssembleResult& shell = valid.shell;
  const ShellCheckResult& checks = valid.checks;
  const QualitySummary quality = summarize_quality(mesh, shell.mesh);
  const double t_assemble = seconds_since(t0);
  if (!checks.valid()) {
    std::string problems = describe_problems(checks);
    std::replace(problems.begin(), problems.end(), '\n', ';');
    throw InternalError(opt.input + ": could not make the shell valid after " +
                        std::to_string(valid.rounds) + " rounds (" + problems + ")" +
                        (valid.floor_valid ? "" : "; the thinnest shell is invalid too: " +
                                                      valid.floor_problems) +
                        "; nothing was written — please report this input");
  }

  t0 = Clock::now();
  write_tet_mesh(opt.output, shell.mesh, tet_format_from_path(opt.output, opt.msh_version));
  if (!opt.grids.empty()) write_grids(opt.grids, *fields, fields->parameters());
  if (!opt.paths.empty()) write_paths_vtk(opt.paths, traces);
  if (!opt.inner.empty()) {
    SurfaceMesh inner_surface;
    inner_surface.points = valid.input.inner_points;
    for (const Triangle& t : mesh.triangles)
      inner_surface.triangles.push_back(
          {valid.input.inner_id[t[0]], valid.input.inner_id[t[2]], valid.input.inner_id[t[1]]});
    write_surface(opt.inner, inner_surface);
  }
  t_write = seconds_since(t0);
  const double t_all = seconds_since(t_total);

  nlohmann::ordered_json j;
  j["input"] = {{"file", opt.input},
                {"vertices", surface.stats.vertices},
                {"faces", surface.stats.faces},
                {"components", surface.stats.components},
                {"genus", surface.stats.genus},
                {"enclosed_volume", surface.stats.enclosed_volume},
                {"flipped", surface.flipped}};
  j["fields"] = {{"voxel_size", fields->voxel_size()},
                 {"strategy", fields->stats().strategy},
                 {"sdf_active_voxels", fields->stats().sdf_active_voxels},
                 {"flux_active_voxels", fields->stats().flux_active_voxels}};
  j["trace"] = {{"step", traces.parameters.step},
                {"point_size", traces.parameters.point_size},
                {"integrator", to_string(opt.trace.integrator)},
                {"planar_vertices",
                 std::count(traces.planar.begin(), traces.planar.end(), std::uint8_t{1})},
                {"samples", traces.samples.size()}};
  j["stop_reasons"] = {{"critical", traces.count[0]},
                       {"merge", traces.count[1]},
                       {"flux", traces.count[2]},
                       {"cap", traces.count[3]}};
  j["shell"] = {{"file", opt.output},
                {"tets", shell.mesh.tets.size()},
                {"points", shell.mesh.points.size()},
                {"coverage", quality.coverage},
                {"shell_volume", quality.shell_volume},
                {"inverted_tets", checks.inverted_tets},
                {"zero_volume_tets", checks.zero_volume_tets},
                {"intersecting_tet_pairs", checks.overlapping_pairs},
                {"outside_inner_vertices", checks.outside_inner_vertices},
                {"missing_surface_triangles", checks.missing_triangles},
                {"dropped_degenerate_tets", shell.dropped_degenerate_tets},
                {"collapsed_prisms", shell.collapsed_prisms},
                {"welded_vertices", inner.welded - std::min(inner.welded, valid.unwelded)},
                {"thickness_limited_vertices", inner.limited},
                {"valid", checks.valid()}};
  j["validity"] = {{"rounds", valid.rounds},
                   {"checks", valid.checks_run},
                   {"moved_back_vertices", valid.moved_back},
                   {"moved_back_mean_fraction", valid.moved_back_mean},
                   {"unwelded_vertices", valid.unwelded},
                   {"floor_valid", valid.floor_valid},
                   {"seconds", valid.seconds}};
  j["quality"] = {{"min", quality.min_quality},
                  {"median", quality.median_quality},
                  {"mean", quality.mean_quality},
                  {"min_dihedral_deg", quality.min_dihedral_deg},
                  {"non_positive", quality.non_positive},
                  {"histogram", quality.histogram}};
  j["timings_s"] = {{"read", t_read},     {"fields", t_fields}, {"trace", t_trace},
                    {"assemble", t_assemble}, {"check", checks.seconds},
                    {"write", t_write},   {"total", t_all}};
  if (!opt.report.empty())
    write_file_atomically(opt.report, [&](std::ostream& os) { os << j.dump(2) << "\n"; });

  if (!opt.quiet) {
    err << "vdb_shell: " << opt.output << ": " << shell.mesh.tets.size() << " tets from "
        << mesh.triangles.size() << " faces, coverage " << fmt(quality.coverage)
        << ", quality min " << fmt(quality.min_quality) << " median "
        << fmt(quality.median_quality) << ", stops critical " << traces.count[0] << " merge "
        << traces.count[1] << " flux " << traces.count[2] << " cap " << traces.count[3]
        << ", " << fmt(t_all) << " s\n";
  }
  out << j.dump(2) << "\n";
  return kExitOk;
}

}  // namespace

int run_cli(int argc, const char* const* argv, std::ostream& out, std::ostream& err) {
  CLI::App app{"vdb_shell: turns a closed triangle surface (OBJ, OFF, PLY, STL) into a volumetric\n"
               "shell of tetrahedra by tracing every vertex inward through a signed distance\n"
               "field (\"Volumetric Shells using Path Tracing\"). Without -o it validates the\n"
               "input and prints its summary.",
               "vdb_shell"};
  app.option_defaults()->always_capture_default();
  app.get_formatter()->column_width(40);

  CliOptions opt;
  const char* in = "Input";
  app.add_option("INPUT", opt.input, "Surface mesh file (.obj .off .ply .stl)")
      ->required()
      ->group(in);
  app.add_option("--level-set", opt.level_set,
                 "Use this .vdb level set as the distance field instead of building one")
      ->group(in);
  app.add_option("--grid", opt.grid_name, "Grid of --level-set to use (default: 'surface' or "
                                          "the first level set)")
      ->group(in);

  const char* fg = "Fields";
  app.add_option("-r,--resolution", opt.fields.resolution,
                 "Voxels along the longest bounding-box side")
      ->check(CLI::Range(kMinResolution, 16384))
      ->group(fg);
  app.add_option("--voxel-size", opt.fields.voxel_size,
                 "Voxel size in input units; overrides --resolution (0: use --resolution)")
      ->check(CLI::NonNegativeNumber)
      ->group(fg);
  app.add_option("--max-memory", opt.fields.max_memory_gb,
                 "Refuse field builds estimated above this many GiB")
      ->check(CLI::PositiveNumber)
      ->group(fg);
  app.add_option("--grids", opt.grids,
                 "Write the fields (surface, flux) to this .vdb file")
      ->group(fg);

  const char* tg = "Tracing";
  app.add_option("--planar-angle", opt.trace.planar_angle,
                 "Degrees: a vertex is planar when its face normals lie within this angle")
      ->group(tg);
  app.add_option("--step", opt.trace.step,
                 "Step length in input units (paper: delta epsilon; 0: half a voxel)")
      ->group(tg);
  app.add_option("--critical", opt.trace.critical,
                 "c of eq. 4: stop where |grad phi|^2 < c |grad phi(p)|^2")
      ->group(tg);
  app.add_option("--point-size", opt.trace.point_size,
                 "Merge distance in input units (paper: point size; 0: one voxel diagonal)")
      ->group(tg);
  app.add_option("--flux-threshold", opt.trace.flux_threshold,
                 "rho of eq. 8: planar traces stop where the average outward flux exceeds it")
      ->group(tg);
  app.add_option("--merge-angle", opt.trace.merge_angle,
                 "Degrees: traces meeting at a smaller angle run side by side, not merge")
      ->group(tg);
  app.add_option("--integrator", opt.integrator, "euler (the paper's), rk2 or rk4")
      ->check(CLI::IsMember({"euler", "rk2", "rk4"}))
      ->group(tg);
  app.add_option("--paths", opt.paths, "Write the traces as VTK polylines (.vtk)")->group(tg);

  const char* th = "Thickness";
  app.add_option("--max-thickness", opt.thickness.max_thickness,
                 "Largest thickness in input units, along the trace (0: as thick as possible)")
      ->check(CLI::NonNegativeNumber)
      ->group(th);
  app.add_option("--thickness-edge-factor", opt.thickness.edge_factor,
                 "K: limit each vertex to K x its mean incident edge length (0: no limit)")
      ->check(CLI::NonNegativeNumber)
      ->group(th);

  const char* og = "Output";
  app.add_option("-o,--output", opt.output,
                 "Tet shell: .vtu .vtk .msh .mesh .ele (format from the extension)")
      ->group(og);
  app.add_option("--msh-version", opt.msh_version, "Gmsh format: 41 (4.1) or 22 (2.2)")
      ->check(CLI::IsMember({41, 22}))
      ->group(og);
  app.add_option("--inner", opt.inner, "Write the inner surface (.obj .ply .off)")->group(og);
  app.add_option("--report", opt.report, "Write the JSON report here too")->group(og);
  app.add_flag("-q,--quiet", opt.quiet, "Print only errors")->group(og);
  app.add_flag("-v,--verbose", opt.verbose, "Print more detail")->group(og);

  app.add_option("-j,--threads", opt.threads, "Worker threads (0: all cores)")
      ->check(CLI::NonNegativeNumber)
      ->group("Performance");
  app.set_version_flag("--version", std::string("vdb_shell ") + VDB_SHELL_VERSION);

  try {
    app.parse(argc, argv);
    if (opt.quiet && opt.verbose)
      throw CLI::ValidationError("--quiet and --verbose", "choose one of them");
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e, out, err);
    return code == 0 ? kExitOk : kExitBadInput;
  }

  try {
    std::unique_ptr<tbb::global_control> threads;
    if (opt.threads > 0)
      threads = std::make_unique<tbb::global_control>(
          tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(opt.threads));
    return run(opt, out, err);
  } catch (const InputError& e) {
    err << "vdb_shell: error: " << e.what() << "\n";
    return kExitBadInput;
  } catch (const std::bad_alloc&) {
    err << "vdb_shell: error: out of memory; lower --resolution or --max-memory\n";
    return kExitFailure;
  } catch (const std::exception& e) {
    err << "vdb_shell: error: " << e.what() << "\n";
    return kExitFailure;
  }
}

int run_cli(int argc, const char* const* argv) { return run_cli(argc, argv, std::cout, std::cerr); }

}  // namespace vdb_shell
