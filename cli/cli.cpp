// cli.cpp — the vdb_shell command: option registry, validation of the whole command line before
// anything runs, the pipeline as a short sequence of stage calls, and the mapping of errors to
// exit codes. The only place (with main.cpp) that talks to the terminal.
#include "cli/cli.h"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <mutex>
#include <new>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <signal.h>
#include <unistd.h>

#include "cli/progress.h"
#include "core/base/file_name.h"
#include "core/base/timer.h"
#include "core/write/atomic_file.h"
#include "core/write/shell_writers.h"
#include "vdb_shell/vdb_shell.h"

#ifndef VDB_SHELL_VERSION
#define VDB_SHELL_VERSION "unknown"
#endif

namespace vdb_shell {
namespace {

/// An allocation the system refused: the stages' estimates were within --max-memory, so the
/// machine (or a ulimit) has less to give than the budget says.
const char* const kOutOfMemory =
    "out of memory: the system refused an allocation; set --max-memory to what this machine "
    "can spare (every stage checks its estimate against it) or lower --resolution";

/// CLI11's NonNegativeNumber and PositiveNumber are ranges up to the largest double, which their
/// messages print in full (309 digits): these say the bound.
CLI::Validator lower_bound_check(bool strict) {
  return CLI::Validator(
      [strict](std::string& text) -> std::string {
        double value = 0;
        if (!CLI::detail::lexical_cast(text, value)) return "Value " + text + " is not a number";
        const bool ok = strict ? value > 0 : value >= 0;
        return ok ? std::string() : "Value " + text + (strict ? " must be > 0" : " must be >= 0");
      },
      strict ? "POSITIVE" : "NONNEGATIVE");
}
const CLI::Validator kNonNegative = lower_bound_check(false);
const CLI::Validator kPositive = lower_bound_check(true);

/// What the user said on the command line (defaults are the documented ones).
struct CliOptions {
  std::vector<std::string> inputs;
  std::string input;  ///< the input being processed (one of `inputs`)
  std::string output;
  std::string format = "vtu";
  std::string grids;
  std::string paths;
  std::string inner;
  std::string report;
  std::string html;
  int msh_version = 41;
  double timeout = 0;  ///< seconds per input, 0: none
  std::string integrator = "rk2";
  bool quiet = false;
  bool verbose = false;
  bool progress = false;
  bool no_progress = false;
  bool err_is_terminal = false;  ///< stderr is a terminal: a progress bar unless --quiet
  // Which options were given explicitly (contradiction checks).
  bool resolution_given = false;
  bool format_given = false;
  bool msh_version_given = false;
  bool grid_given = false;
  bool adaptivity_given = false;
  bool repair_closing_given = false;
  bool repair_voxel_size_given = false;
  std::string repaired;  ///< --repaired: where to write the repaired surface
  ShellOptions shell;    ///< every option of the pipeline (--level-set, --grid, -j among them)

  bool batch() const { return inputs.size() > 1; }
  /// A bar redrawn in place on a terminal, one line per stage with --progress elsewhere.
  ProgressMode progress_mode() const {
    if (quiet || no_progress) return ProgressMode::kNone;
    if (err_is_terminal) return ProgressMode::kBar;
    return progress ? ProgressMode::kLines : ProgressMode::kNone;
  }
};

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

bool is_vdb(const std::string& path) { return lower_extension(path) == ".vdb"; }

/// True if write_surface() can write `path`.
bool surface_extension(const std::string& path) {
  const std::vector<std::string>& known = surface_output_extensions();
  return std::find(known.begin(), known.end(), lower_extension(path)) != known.end();
}

/// Rejects options that contradict each other, saying what to do instead.
void check_contradictions(const CliOptions& o) {
  namespace fs = std::filesystem;
  if (o.quiet && o.progress)
    throw InputError("--quiet and --progress contradict each other: choose one of them");
  if (o.progress && o.no_progress)
    throw InputError("--progress and --no-progress contradict each other: choose one of them");
  if (o.resolution_given && o.shell.fields.voxel_size > 0)
    throw InputError(
        "--voxel-size and --resolution both set the voxel size: give only one of "
        "them");
  const bool vdb_inputs = std::all_of(o.inputs.begin(), o.inputs.end(), is_vdb);
  if (o.grid_given && o.shell.level_set.empty() && !vdb_inputs)
    throw InputError("--grid " + o.shell.grid_name +
                     " names a grid of --level-set or of a .vdb "
                     "INPUT: give --level-set FILE.vdb too, or drop --grid");
  if (!o.shell.level_set.empty() && std::any_of(o.inputs.begin(), o.inputs.end(), is_vdb))
    throw InputError("a .vdb INPUT is its own level set: drop --level-set");
  if (o.adaptivity_given && !o.shell.repair &&
      !std::any_of(o.inputs.begin(), o.inputs.end(), is_vdb))
    throw InputError(
        "--adaptivity applies to meshing a .vdb INPUT or a --repair: drop it for mesh files");
  if (!o.shell.repair &&
      (o.repair_closing_given || o.repair_voxel_size_given || !o.repaired.empty()))
    throw InputError(
        "--repair-closing, --repair-voxel-size and --repaired describe a repair: "
        "add --repair");
  if (o.batch()) {
    if (o.msh_version_given && o.format != "msh")
      throw InputError(
          "--msh-version applies to .msh output only: add --format msh or drop "
          "--msh-version");
    return;
  }
  if (o.format_given) {
    if (o.output.empty())
      throw InputError(
          "--format applies to -o: give -o OUTPUT (its extension chooses the "
          "format with one input)");
    if (fs::path(o.output).extension() != "." + o.format)
      throw InputError("--format " + o.format + " contradicts -o " + o.output +
                       ": with one input the extension of -o chooses the format; drop --format");
  }
  if (o.msh_version_given && fs::path(o.output).extension() != ".msh")
    throw InputError(
        "--msh-version applies to .msh output only: write -o FILE.msh or drop "
        "--msh-version");
}

/// Checks every output path before any work: known extension, existing folder.
void check_outputs(const CliOptions& o) {
  namespace fs = std::filesystem;
  // The folder exists and takes a file (a temporary one, created and removed): found before
  // the work rather than after it.
  auto folder_exists = [](const std::string& path, const char* option) {
    const fs::path parent = fs::path(path).parent_path();
    if (!parent.empty() && !fs::is_directory(parent))
      throw InputError(std::string(option) + " " + path + ": the folder " + parent.string() +
                       " does not exist; create it first");
    AtomicFile probe(path);  // \throw ResourceError naming the path and why
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
    if (!surface_extension(o.inner))
      throw InputError("--inner " + o.inner + ": use .obj, .ply, .off or .stl");
    folder_exists(o.inner, "--inner");
  }
  if (!o.repaired.empty()) {
    if (!surface_extension(o.repaired))
      throw InputError("--repaired " + o.repaired + ": use .obj, .ply, .off or .stl");
    folder_exists(o.repaired, "--repaired");
  }
  if (!o.report.empty()) folder_exists(o.report, "--report");
  if (!o.html.empty()) {
    if (!ext_is(o.html, ".html")) throw InputError("--html " + o.html + ": must end in .html");
    folder_exists(o.html, "--html");
  }
  if (o.output.empty() &&
      (!o.paths.empty() || !o.inner.empty() || !o.report.empty() || !o.html.empty()))
    throw InputError("--paths, --inner, --report and --html describe a shell: give -o OUTPUT too");
}

/// With several inputs, -o (and --report) name folders: created if missing, but a path that
/// exists as a file or ends in a file extension is rejected.
void check_batch(const CliOptions& o) {
  namespace fs = std::filesystem;
  if (o.output.empty())
    throw InputError(
        "several inputs: give -o DIR, the folder that receives one shell per input "
        "(or run vdb_shell once per input to see each summary)");
  if (!o.grids.empty() || !o.paths.empty() || !o.inner.empty() || !o.repaired.empty() ||
      !o.shell.level_set.empty())
    throw InputError(
        "--grids, --paths, --inner, --repaired and --level-set take a single input: run "
        "vdb_shell once per input for them");
  tet_format_from_path("x." + o.format, o.msh_version);
  auto check_dir = [](const std::string& dir, const char* option, const char* example) {
    if (fs::exists(dir) && !fs::is_directory(dir))
      throw InputError(std::string(option) + " " + dir + " is a file: with several inputs " +
                       option + " names a folder (" + example + ")");
    if (!fs::exists(dir) && fs::path(dir).has_extension())
      throw InputError(std::string(option) + " " + dir +
                       " looks like a file name: with several "
                       "inputs " +
                       option + " names a folder, created if missing (" + example + ")");
  };
  check_dir(o.output, "-o", "-o shells/");
  if (!o.report.empty()) check_dir(o.report, "--report", "--report reports/");
  if (!o.html.empty()) check_dir(o.html, "--html", "--html pages/");
  std::vector<std::string> stems;
  for (const std::string& in : o.inputs) stems.push_back(fs::path(in).stem().string());
  std::sort(stems.begin(), stems.end());
  const auto dup = std::adjacent_find(stems.begin(), stems.end());
  if (dup != stems.end())
    throw InputError("two inputs have the name " + *dup + ": their outputs would collide in " +
                     o.output + "; rename one or run them in separate calls");
  if (!o.html.empty() && std::binary_search(stems.begin(), stems.end(), "index"))
    throw InputError("an input named index would overwrite the index page of --html " + o.html +
                     "/index.html; rename it or run it in a separate call");
}

/// What one run of the pipeline produced.
/// Sets its flag (a RunControl's cancel) once `seconds` have passed, from a thread of its own;
/// 0 seconds: never. The destructor stops the thread at once.
class Watchdog {
 public:
  explicit Watchdog(double seconds) {
    if (seconds <= 0) return;
    thread_ = std::thread([this, seconds] {
      std::unique_lock<std::mutex> lock(mutex_);
      if (!wake_.wait_for(lock, std::chrono::duration<double>(seconds), [this] { return done_; }))
        fired_ = true;
    });
  }
  ~Watchdog() {
    if (!thread_.joinable()) return;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      done_ = true;
    }
    wake_.notify_all();
    thread_.join();
  }
  Watchdog(const Watchdog&) = delete;
  Watchdog& operator=(const Watchdog&) = delete;
  const std::atomic<bool>* flag() const { return &fired_; }
  bool fired() const { return fired_; }

 private:
  std::atomic<bool> fired_{false};
  std::mutex mutex_;
  std::condition_variable wake_;
  bool done_ = false;
  std::thread thread_;
};

struct RunOutcome {
  bool shell = false;   ///< false: summary or --grids only, nothing below is set
  std::string report;   ///< the JSON report
  std::string summary;  ///< the one-line summary (without "vdb_shell: ")
  /// tets, coverage, quality, seconds and (in batch mode with --html) the thumbnail: the
  /// batch's stdout line and its index row.
  HtmlIndexRow figures;
};

/// The one-line summary of a shell on stderr.
std::string summary_line(const std::string& output, const ShellResult& r, double seconds) {
  return output + ": " + std::to_string(r.mesh.tets.size()) + " tets from " +
         std::to_string(r.input.stats.faces) + " faces, coverage " + fmt(r.quality.coverage) +
         ", quality min " + fmt(r.quality.min_quality) + " median " +
         fmt(r.quality.median_quality) + ", stops critical " +
         std::to_string(r.traces.stops(StopReason::kCritical)) + " merge " +
         std::to_string(r.traces.stops(StopReason::kMerge)) + " flux " +
         std::to_string(r.traces.stops(StopReason::kFlux)) + " cap " +
         std::to_string(r.traces.stops(StopReason::kCap)) + ", " + fmt(seconds) + " s";
}

/// Runs the whole pipeline on `opt.input` (options already checked). Prints the summary to `out`
/// when there is no output; writes the outputs and the --report file otherwise.
RunOutcome run_pipeline(const CliOptions& opt, std::ostream& out, std::ostream& err,
                        const std::string& progress_prefix, bool thumbnail = false) {
  const auto t_total = Clock::now();
  const bool shell_wanted = !opt.output.empty();
  // Stages: read; with --grids alone also fields, trace, write; with -o all six, and html with
  // --html.
  const int stages = shell_wanted ? (opt.html.empty() ? 6 : 7) : (opt.grids.empty() ? 1 : 4);
  Progress progress(err, opt.progress_mode(), stages, progress_prefix);
  RunOutcome outcome;

  ShellOptions shell = opt.shell;
  shell.traces_only = !shell_wanted;
  shell.keep_fields = !opt.grids.empty();
  progress.start("read");
  // A .vdb input is a level set: its zero crossing is the surface, and it is also the field.
  const bool vdb_input = is_vdb(opt.input);
  RepairReport repair;
  const LoadedSurface surface = [&] {
    if (shell.repair) {
      return vdb_input
                 ? load_level_set_surface(opt.input, shell, &repair)
                 : load_repaired_surface(read_polygon_soup(opt.input), opt.input, shell, repair);
    }
    try {
      return vdb_input ? load_level_set_surface(opt.input, shell) : load_surface(opt.input);
    } catch (const InputError& e) {  // a surface that is not closed or crosses itself
      const std::string what = e.what();
      if (what.find("not a closed 2-manifold triangle surface") == std::string::npos) throw;
      throw InputError(what + " — or rerun with --repair to rebuild it watertight");
    }
  }();
  // A .vdb input is its own field; repaired, its surface gets fields of its own.
  if (vdb_input && !shell.repair) shell.level_set = opt.input;
  const double t_read = progress.stop();
  if (!opt.quiet)
    for (const std::string& n : surface.notices) err << "vdb_shell: note: " << n << "\n";
  if (!shell_wanted && opt.grids.empty()) {
    if (!opt.repaired.empty()) write_surface(opt.repaired, surface.mesh);
    print_summary(out, opt.input, surface);
    return outcome;
  }

  RunControl control;
  control.progress = [&progress](const std::string& stage, double fraction) {
    progress.update(stage, fraction);
  };
  Watchdog watchdog(opt.timeout);
  control.cancel = watchdog.flag();
  ShellResult r = [&] {
    try {
      return build_shell(surface, shell, control);
    } catch (const CancelledError& e) {
      if (!watchdog.fired()) throw;
      std::string stage = e.what();  // "cancelled during the X stage; ..."
      stage = stage.substr(0, stage.find(';'));
      throw ResourceError(opt.input + ": timed out after " + fmt(opt.timeout) + " s (--timeout; " +
                          stage + "); raise --timeout or lower --resolution; nothing was written");
    }
  }();
  if (shell.repair) r.repair = repair;
  if (!opt.quiet)
    for (std::size_t i = surface.notices.size(); i < r.notices.size(); ++i)
      err << "vdb_shell: note: " << r.notices[i] << "\n";
  if (opt.verbose)
    err << "vdb_shell: fields: voxel " << fmt(r.field_stats.voxel_size) << ", "
        << r.field_stats.sdf_active_voxels << " SDF voxels, " << r.field_stats.flux_active_voxels
        << " flux voxels, " << fmt(r.timings.fields) << " s\n";

  if (!shell_wanted) {  // --grids only: the fields and the traces as points
    progress.start("write");
    CommitGroup outputs;
    write_fields(opt.grids, r);
    if (!opt.repaired.empty()) write_surface(opt.repaired, surface.mesh);
    outputs.commit();
    progress.stop();
    if (!opt.quiet) err << "vdb_shell: wrote " << opt.grids << "\n";
    if (opt.verbose) err << "vdb_shell: timings: " << progress.timings() << "\n";
    return outcome;
  }

  // Every output of the run appears together, or none does (a failing one removes the others).
  CommitGroup outputs;
  progress.start("write");
  write_shell(opt.output, r, opt.msh_version);
  if (!opt.grids.empty()) write_fields(opt.grids, r);
  if (!opt.paths.empty()) write_traces(opt.paths, r);
  if (!opt.inner.empty()) write_inner_surface(opt.inner, r);
  if (!opt.repaired.empty()) write_surface(opt.repaired, surface.mesh);
  const double t_write = progress.stop();
  const double t_all = seconds_since(t_total);

  ReportFiles files;
  files.shell = opt.output;
  outcome.report = report_json(r, files, t_read, t_write);
  if (!opt.report.empty())
    write_file_atomically(opt.report, [&](std::ostream& os) { os << outcome.report; });
  if (!opt.html.empty()) {
    progress.start("html");
    write_html(opt.html, r, files, t_read, t_write);
    if (thumbnail) outcome.figures.thumbnail = html_thumbnail(r);
    progress.stop();
  }
  outputs.commit();
  if (opt.verbose) err << "vdb_shell: timings: " << progress.timings() << "\n";

  outcome.shell = true;
  outcome.figures.tets = r.mesh.tets.size();
  outcome.figures.coverage = r.quality.coverage;
  outcome.figures.min_quality = r.quality.min_quality;
  outcome.figures.median_quality = r.quality.median_quality;
  outcome.figures.seconds = t_all;
  outcome.summary = summary_line(opt.output, r, t_all);
  return outcome;
}

/// One input, -o a file: the JSON report on stdout, the summary line on stderr.
int run_single(CliOptions opt, std::ostream& out, std::ostream& err) {
  opt.input = opt.inputs.front();
  check_outputs(opt);
  const RunOutcome r = run_pipeline(opt, out, err, "");
  if (!r.shell || opt.quiet) return kExitOk;
  err << "vdb_shell: " << r.summary << "\n";
  out << r.report;
  return kExitOk;
}

/// Several inputs, -o a folder: one tab-separated report line per input on stdout,
///   INPUT \t ok \t TETS \t COVERAGE \t SECONDS \t OUTPUT     or     INPUT \t error \t MESSAGE
/// Every input is processed; the exit code is 0, or 2 if every failure was bad input, else 3.
int run_batch(const CliOptions& opt, std::ostream& out, std::ostream& err) {
  namespace fs = std::filesystem;
  check_batch(opt);
  try {
    fs::create_directories(opt.output);
    if (!opt.report.empty()) fs::create_directories(opt.report);
    if (!opt.html.empty()) fs::create_directories(opt.html);
  } catch (const fs::filesystem_error& e) {
    throw ResourceError(std::string("cannot create the output folder: ") + e.what());
  }
  int failures = 0, bad_input = 0;
  std::vector<HtmlIndexRow> index;
  for (const std::string& input : opt.inputs) {
    CliOptions one = opt;
    one.input = input;
    const std::string stem = fs::path(input).stem().string();
    one.output = (fs::path(opt.output) / (stem + "." + opt.format)).string();
    if (!opt.report.empty()) one.report = (fs::path(opt.report) / (stem + ".json")).string();
    if (!opt.html.empty()) one.html = (fs::path(opt.html) / (stem + ".html")).string();
    std::string error;
    bool is_bad_input = false;
    try {
      RunOutcome r = run_pipeline(one, out, err, "[" + stem + "] ", !opt.html.empty());
      HtmlIndexRow& row = r.figures;
      out << input << "\tok\t" << row.tets << "\t" << fmt(row.coverage) << "\t"
          << fmt_seconds(row.seconds) << "\t" << one.output << "\n"
          << std::flush;
      row.input = input;
      row.page = stem + ".html";
      index.push_back(std::move(row));
      continue;
    } catch (const InputError& e) {
      error = e.what();
      is_bad_input = true;
    } catch (const std::bad_alloc&) {
      error = kOutOfMemory;
    } catch (const std::exception& e) {
      error = e.what();
    }
    ++failures;
    if (is_bad_input) ++bad_input;
    std::replace(error.begin(), error.end(), '\n', ' ');
    std::replace(error.begin(), error.end(), '\t', ' ');
    err << "vdb_shell: error: " << (error.rfind(input, 0) == 0 ? "" : input + ": ") << error
        << "\n";
    out << input << "\terror\t" << error << "\n" << std::flush;
    HtmlIndexRow row;
    row.input = input;
    row.error = error;
    index.push_back(std::move(row));
  }
  if (!opt.html.empty()) {
    const std::string page = html_index(index);
    write_file_atomically((fs::path(opt.html) / "index.html").string(),
                          [&](std::ostream& os) { os << page; });
  }
  if (failures == 0) return kExitOk;
  return failures == bad_input ? kExitBadInput : kExitFailure;
}

int run(CliOptions opt, std::ostream& out, std::ostream& err) {
  check_contradictions(opt);
  opt.shell.trace.integrator = parse_integrator(opt.integrator);
  return opt.batch() ? run_batch(opt, out, err) : run_single(opt, out, err);
}

/// The option registry: every option with its default, group and help text (--help prints them
/// from here; docs/usage.md lists them with units).
void register_options(CLI::App& app, CliOptions& opt) {
  const char* in = "Input";
  app.add_option("INPUT", opt.inputs,
                 "Surface mesh file(s) (.obj .off .ply .stl), or a level set (.vdb) meshed at "
                 "its zero crossing; with several, -o names a folder")
      ->default_str("")
      ->required()
      ->group(in);
  app.add_option("--level-set", opt.shell.level_set,
                 "Use this .vdb level set as the distance field instead of building one")
      ->group(in);
  app.add_option("--grid", opt.shell.grid_name,
                 "Grid of --level-set or of a .vdb INPUT to use "
                 "(default: 'surface', else the first level set)")
      ->group(in);
  app.add_option("--adaptivity", opt.shell.adaptivity,
                 "Meshing a .vdb INPUT: 0 keeps voxel-sized quads, up to 1 merges flat regions "
                 "into fewer faces")
      ->check(CLI::Range(0.0, 1.0))
      ->group(in);
  app.add_flag("--repair", opt.shell.repair,
               "Rebuild the input watertight through a volume first (holes, seams, overlaps, "
               "self-intersections); the shell's outer boundary is then the repaired surface")
      ->group(in);
  app.add_option("--repair-closing", opt.shell.repair_closing,
                 "--repair: close holes and gaps up to about twice this many voxels across")
      ->check(CLI::Range(1.0, 1e6))
      ->group(in);
  app.add_option("--repair-voxel-size", opt.shell.repair_voxel_size,
                 "--repair: the repair volume's voxel size, input units (0: the fields' voxel "
                 "size)")
      ->check(kNonNegative)
      ->group(in);
  app.add_option("--repaired", opt.repaired,
                 "--repair: write the repaired surface (.obj .ply .off .stl)")
      ->group(in);

  const char* fg = "Fields";
  app.add_option("-r,--resolution", opt.shell.fields.resolution,
                 "Voxels along the longest bounding-box side")
      ->check(CLI::Range(kMinResolution, 16384))
      ->group(fg);
  app.add_option("--voxel-size", opt.shell.fields.voxel_size,
                 "Voxel size in input units; overrides --resolution (0: use --resolution)")
      ->check(kNonNegative)
      ->group(fg);
  app.add_option(
         "--max-memory", opt.shell.fields.max_memory_gb,
         "Memory budget, GiB: every stage estimates its peak first and refuses to start above it")
      ->check(kPositive)
      ->group(fg);
  app.add_option("--grids", opt.grids,
                 "Write the fields (surface, flux) and the traces (points) to this .vdb file")
      ->group(fg);

  const char* tg = "Tracing";
  app.add_option("--planar-angle", opt.shell.trace.planar_angle,
                 "Degrees: a vertex is planar when its face normals lie within this angle")
      ->group(tg);
  app.add_option("--step", opt.shell.trace.step,
                 "Step length in input units (paper: delta epsilon; 0: half a voxel)")
      ->group(tg);
  app.add_option("--critical", opt.shell.trace.critical,
                 "c of eq. 4: stop where |grad phi|^2 < c |grad phi(p)|^2")
      ->group(tg);
  app.add_option("--point-size", opt.shell.trace.point_size,
                 "Merge distance in input units (paper: point size; 0: one voxel diagonal)")
      ->group(tg);
  app.add_option("--flux-threshold", opt.shell.trace.flux_threshold,
                 "rho of eq. 8: planar traces stop where the average outward flux exceeds it")
      ->group(tg);
  app.add_option("--merge-angle", opt.shell.trace.merge_angle,
                 "Degrees: traces meeting at a smaller angle run side by side, not merge")
      ->group(tg);
  app.add_option("--integrator", opt.integrator, "euler (the paper's), rk2 or rk4")
      ->check(CLI::IsMember({"euler", "rk2", "rk4"}))
      ->group(tg);
  app.add_option("--min-step", opt.shell.trace.min_step,
                 "Shortest step where |grad phi| < 1 shortens it, a fraction of --step (paper: 0)")
      ->check(CLI::Range(0.0, 1.0))
      ->group(tg);
  app.add_option("--paths", opt.paths, "Write the traces as VTK polylines (.vtk)")->group(tg);

  const char* th = "Thickness";
  app.add_option("--max-thickness", opt.shell.thickness.max_thickness,
                 "Largest thickness in input units, along the trace (0: as thick as possible)")
      ->check(kNonNegative)
      ->group(th);
  app.add_option("--thickness-edge-factor", opt.shell.thickness.edge_factor,
                 "K: limit each vertex to K x its mean incident edge length (0: no limit)")
      ->check(kNonNegative)
      ->group(th);
  app.add_option("--min-quality", opt.shell.validity.min_quality,
                 "Step inner vertices back from tets of a lower volume-length quality, where they "
                 "can move (less on sliver faces; 0: only from inverted ones)")
      ->check(CLI::Range(0.0, 0.5))
      ->group(th);
  app.add_option("--layers", opt.shell.validity.layers,
                 "K: stack K prisms along each prism's straight side edges, 3K tets (the tets "
                 "are K times less elongated)")
      ->check(CLI::Range(1, kMaxLayers))
      ->group(th);
  app.add_option("--layer-ratio", opt.shell.validity.layer_ratio,
                 "Each layer this many times as thick as the one outside it (geometric growth "
                 "from the surface)")
      ->check(CLI::Range(0.1, 10.0))
      ->group(th);
  CLI::Option* optimize =
      app.add_flag("--optimize", opt.shell.optimize.enabled,
                   "After the validity search, move inner vertices (never outward, within the "
                   "thickness limits) and cut prisms' side quads the other way to raise the worst "
                   "tets' quality and smallest dihedral angle (the default)")
          ->group(th);
  app.add_option("--max-coverage-loss", opt.shell.optimize.max_coverage_loss,
                 "Coverage the optimisation's moves may cost in all, as a fraction of the "
                 "enclosed volume (more lets them raise the worst tets further)")
      ->check(CLI::Range(0.0, 0.1))
      ->group(th);
  app.add_flag_callback(
         "--no-optimize", [&opt] { opt.shell.optimize.enabled = false; },
         "Do not optimise: the shell as the validity search leaves it")
      ->excludes(optimize)
      ->group(th);

  const char* og = "Output";
  app.add_option("-o,--output", opt.output,
                 "Tet shell: .vtu .vtk .msh .mesh .ele (format from the extension)")
      ->group(og);
  app.add_option("--format", opt.format,
                 "Shell format with several inputs: vtu vtk msh mesh ele (one input: the "
                 "extension of -o)")
      ->check(CLI::IsMember({"vtu", "vtk", "msh", "mesh", "ele"}))
      ->group(og);
  app.add_option("--msh-version", opt.msh_version, "Gmsh format: 4.1 or 2.2 (also as 41, 22)")
      ->transform(CLI::Validator(
          [](std::string& value) {
            if (value == "4.1" || value == "41") value = "41";
            if (value == "2.2" || value == "22") value = "22";
            return value == "41" || value == "22"
                       ? std::string()
                       : "must be 4.1 or 2.2 (the Gmsh format version), not " + value;
          },
          ""))
      ->type_name("4.1|2.2")
      ->default_str("4.1")
      ->group(og);
  app.add_option("--inner", opt.inner, "Write the inner surface (.obj .ply .off .stl)")->group(og);
  app.add_option("--report", opt.report,
                 "Write the JSON report here too (several inputs: a folder, one <stem>.json each)")
      ->group(og);
  app.add_option("--html", opt.html,
                 "Write a self-contained HTML page with pictures of the shell, its quality and "
                 "the run's figures (several inputs: a folder, one <stem>.html each and "
                 "index.html)")
      ->type_name("FILE.html")
      ->group(og);
  app.add_flag("-q,--quiet", opt.quiet, "Print only errors")->group(og);
  app.add_flag("-v,--verbose", opt.verbose, "Print more detail and per-stage timings")->group(og);
  app.add_flag("--progress", opt.progress,
               "Print each stage and its seconds on stderr (on a terminal: a progress bar, the "
               "default)")
      ->group(og);
  app.add_flag("--no-progress", opt.no_progress, "No progress output, even on a terminal")
      ->group(og);

  app.add_option("-j,--threads", opt.shell.threads, "Worker threads (0: all cores)")
      ->check(kNonNegative)
      ->group("Performance");
  app.add_option("--timeout", opt.timeout,
                 "Give up on an input after this many seconds: exit 3, nothing written (0: none)")
      ->check(kNonNegative)
      ->group("Performance");
}

int run_cli_impl(int argc, const char* const* argv, std::ostream& out, std::ostream& err,
                 bool err_is_terminal) {
  CLI::App app{
      "vdb_shell: turns a closed triangle surface (OBJ, OFF, PLY, STL) into a volumetric\n"
      "shell of tetrahedra by tracing every vertex inward through a signed distance\n"
      "field (\"Volumetric Shells using Path Tracing\"). Without -o it validates the\n"
      "input and prints its summary.",
      "vdb_shell"};
  app.option_defaults()->always_capture_default();
  app.get_formatter()->column_width(40);

  CliOptions opt;
  opt.err_is_terminal = err_is_terminal;
  register_options(app, opt);
  app.set_version_flag("--version", std::string("vdb_shell ") + VDB_SHELL_VERSION);

  try {
    app.parse(argc, argv);
    if (opt.quiet && opt.verbose)
      throw CLI::ValidationError("--quiet and --verbose", "choose one of them");
    opt.resolution_given = app.count("--resolution") > 0;
    opt.format_given = app.count("--format") > 0;
    opt.msh_version_given = app.count("--msh-version") > 0;
    opt.grid_given = app.count("--grid") > 0;
    opt.adaptivity_given = app.count("--adaptivity") > 0;
    opt.repair_closing_given = app.count("--repair-closing") > 0;
    opt.repair_voxel_size_given = app.count("--repair-voxel-size") > 0;
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == static_cast<int>(CLI::ExitCodes::Success))
      return app.exit(e, out, err) == 0 ? kExitOk : kExitBadInput;  // --help, --version
    // One line, as every other bad input.
    std::string what = e.what();
    std::replace(what.begin(), what.end(), '\n', ' ');
    err << "vdb_shell: error: " << what << " (vdb_shell --help lists the options)\n";
    return kExitBadInput;
  }

  try {
    return run(opt, out, err);
  } catch (const InputError& e) {
    err << "vdb_shell: error: " << e.what() << "\n";
    return kExitBadInput;
  } catch (const std::bad_alloc&) {
    err << "vdb_shell: error: " << kOutOfMemory << "\n";
    return kExitFailure;
  } catch (const std::exception& e) {
    err << "vdb_shell: error: " << e.what() << "\n";
    return kExitFailure;
  }
}

extern "C" void remove_temp_files_and_reraise(int sig) {
  remove_pending_temp_files();
  std::signal(sig, SIG_DFL);
  std::raise(sig);
}

}  // namespace

int run_cli(int argc, const char* const* argv, std::ostream& out, std::ostream& err) {
  return run_cli_impl(argc, argv, out, err, false);
}

int run_cli(int argc, const char* const* argv) {
  return run_cli_impl(argc, argv, std::cout, std::cerr, isatty(STDERR_FILENO) == 1);
}

void install_signal_cleanup() {
  struct sigaction action {};
  action.sa_handler = remove_temp_files_and_reraise;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESETHAND;
  for (const int sig : {SIGINT, SIGTERM}) {
    struct sigaction previous {};
    // A signal the parent made us ignore (nohup, `cmd &` in a script for SIGINT) stays ignored.
    if (sigaction(sig, nullptr, &previous) == 0 && previous.sa_handler == SIG_IGN) continue;
    sigaction(sig, &action, nullptr);
  }
}

}  // namespace vdb_shell
