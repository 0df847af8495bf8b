// cli.cpp — the vdb_shell command: option registry, validation of the whole command line before
// anything runs, the pipeline as a short sequence of stage calls, and the mapping of errors to
// exit codes. The only place (with main.cpp) that talks to the terminal.
#include "cli/cli.h"

#include <CLI/CLI.hpp>

#include <cstdio>
#include <iostream>
#include <new>
#include <string>
#include <vector>

#include "core/errors.h"
#include "core/validate.h"

#ifndef VDB_SHELL_VERSION
#define VDB_SHELL_VERSION "unknown"
#endif

namespace vdb_shell {
namespace {

/// What the user said on the command line (defaults are the documented ones).
struct CliOptions {
  std::string input;
  bool quiet = false;
  bool verbose = false;
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

int run(const CliOptions& opt, std::ostream& out, std::ostream& err) {
  const LoadedSurface surface = load_surface(opt.input);
  if (!opt.quiet)
    for (const std::string& n : surface.notices) err << "vdb_shell: note: " << n << "\n";
  print_summary(out, opt.input, surface);
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
  app.get_formatter()->column_width(34);

  CliOptions opt;
  app.add_option("INPUT", opt.input, "Surface mesh file (.obj .off .ply .stl)")
      ->required()
      ->group("Input");
  app.set_version_flag("--version", std::string("vdb_shell ") + VDB_SHELL_VERSION);
  app.add_flag("-q,--quiet", opt.quiet, "Print only errors")->group("Output");
  app.add_flag("-v,--verbose", opt.verbose, "Print more detail")->group("Output");

  try {
    app.parse(argc, argv);
    if (opt.quiet && opt.verbose)
      throw CLI::ValidationError("--quiet and --verbose", "choose one of them");
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e, out, err);
    return code == 0 ? kExitOk : kExitBadInput;
  }

  try {
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
