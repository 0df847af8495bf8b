// vdb_shell.h — the whole pipeline as one call: a closed triangle surface (or a level set in a
// .vdb file) in, a volumetric shell of tetrahedra out (docs/library.md).
//
//   LoadedSurface s = vdb_shell::load_surface("bunny.obj");   // read + validate
//   ShellResult r = vdb_shell::build_shell(s, options);       // fields, traces, the valid shell
//   vdb_shell::write_shell("bunny.vtu", r);                   // any format the CLI writes
//
// Stages, in order: fields (the filled signed distance field and the flux, OpenVDB), trace (every
// surface vertex traced inward), inner (thickness limits and welding), validity (the thickest
// valid shell along the traces, with one full independent-style check). Each reports progress
// and checks the cancel flag through RunControl (core/base/run_control.h).
//
// Units and frame: everything in the input's world units and frame. Sign: the SDF is negative
// inside. Tets are positively oriented (tet_volume > 0); the first points of the shell are the
// surface's vertices, unchanged, followed by the inner vertices.
//
// Errors (core/base/errors.h): InputError for a surface or options that cannot be used (the message
// names the source, the first offending element and the fix); ResourceError for memory budgets
// (every stage estimates its peak before it allocates and refuses one above
// ShellOptions::fields.max_memory_gb, naming the stage: core/base/memory_budget.h) and files;
// InternalError if a shell broke an invariant (a bug: please report the input); CancelledError when
// RunControl::cancel was set. A failed call writes nothing and changes no argument. The call keeps
// no global state: several may run at once on different threads.
#pragma once

#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/assemble/quality.h"
#include "core/base/errors.h"
#include "core/base/run_control.h"
#include "core/base/surface_mesh.h"
#include "core/base/tet_mesh.h"
#include "core/inner/inner.h"
#include "core/read/load_surface.h"
#include "core/trace/trace.h"
#include "core/validity/optimize.h"
#include "core/validity/search.h"
#include "core/validity/shell_checks.h"
#include "vdb_ops/fields.h"
#include "vdb_ops/repair.h"

namespace vdb_shell {

/// Every option of a run; each field's default is the CLI's (docs/usage.md has units and the
/// paper's symbols).
struct ShellOptions {
  FieldOptions fields;         ///< --resolution, --voxel-size, --max-memory
  TraceOptions trace;          ///< --planar-angle, --step, --critical, --point-size, ...
  ThicknessOptions thickness;  ///< --max-thickness, --thickness-edge-factor
  ValidityOptions validity;    ///< --min-quality
  OptimizeOptions optimize;    ///< --optimize / --no-optimize
  /// A .vdb file whose level set is the distance field, instead of building one (--level-set).
  std::string level_set;
  /// Grid of `level_set` (or of build_shell_from_level_set()'s file) to use (--grid); empty:
  /// "surface" if it is a level set, else the first float level set.
  std::string grid_name;
  /// build_shell_from_level_set(): 0 keeps voxel-sized quads, up to 1 merges flat regions into
  /// fewer faces (--adaptivity).
  double adaptivity = 0.0;
  /// Rebuild the input watertight through a volume before shelling it (--repair,
  /// load_repaired_surface(), vdb_ops/repair.h): its voxel size (--repair-voxel-size; 0: the
  /// fields' voxel size) and the closing, in voxels (--repair-closing).
  bool repair = false;
  double repair_voxel_size = 0.0;
  double repair_closing = 2.0;
  /// Stop after the traces: the result has the fields' figures and the traces, no shell (what
  /// `--grids` without `-o` needs).
  bool traces_only = false;
  /// Keep the fields in ShellResult::fields (for write_fields(); they hold most of the memory).
  bool keep_fields = false;
  /// Worker threads of this call (-j; its own TBB arena, other calls are unaffected); 0: all
  /// cores. The result does not depend on it.
  int threads = 0;
};

/// \throw InputError naming the option (by its CLI name) for values outside their ranges:
///        resolution, negative sizes or limits, min_quality outside [0, 0.5], adaptivity
///        outside [0, 1], unknown integrator values. build_shell() calls it first.
void check_options(const ShellOptions& options);

/// Where the input came from and what validation did to it.
struct InputReport {
  std::string source;    ///< file path, or the name given to build_shell()
  SurfaceStats stats;    ///< vertices, faces, components, genus, volume (after validation)
  bool flipped = false;  ///< the input was oriented inward and was flipped
  /// Components flipped alone: some of several faced into the solid (`flipped` when all did).
  std::size_t flipped_components = 0;
};

/// What the validity search did (docs/validity.md).
struct ValidityReport {
  int rounds = 0;
  int checks_run = 0;
  std::size_t moved_back_vertices = 0;
  double moved_back_mean_fraction = 0;
  std::size_t unwelded_vertices = 0;
  std::size_t folded_vertices = 0;  ///< vertices split into sectors (docs/validity.md)
  std::size_t sectors = 0;          ///< sectors of the folded vertices
  std::size_t gap_tets = 0;         ///< tets filling the gaps between sectors
  /// flat tets (zero volume) keeping the input's zero-area faces on the outer boundary, the
  /// shell's last tets (LoadedSurface::zero_area)
  std::size_t flat_tets = 0;
  std::size_t on_surface_vertices = 0;  ///< vertices kept on the surface (no split found)
  std::size_t following_vertices = 0;   ///< vertices next to an edge following its ends
  std::size_t cap_faces = 0;
  std::size_t floor_drops = 0;
  bool floor_valid = true;
  double seconds = 0;
};

/// What --optimize did (core/validity/optimize.h): the quality before it; ShellResult::quality
/// is after.
struct OptimizeSummary {
  OptimizeReport report;
  double min_quality_before = 0;
  double p5_quality_before = 0;
  double min_dihedral_deg_before = 0;
  double coverage_before = 0;
};

/// Counts of the assembled shell (its tets and points: ShellResult::mesh).
struct ShellCounts {
  std::size_t dropped_degenerate_tets = 0;     ///< tets with a repeated vertex after welding
  std::size_t collapsed_prisms = 0;            ///< prisms whose inner vertices are one point
  std::size_t welded_vertices = 0;             ///< surface vertices sharing an inner vertex
  std::size_t thickness_limited_vertices = 0;  ///< vertices a thickness limit shortened
};

/// The memory estimates of a run, bytes (core/base/memory_budget.h): each stage's estimated peak
/// — what it allocates, what earlier stages still hold and the program itself — which the stage
/// compared with the budget (--max-memory) before it allocated. 0: the stage did not run.
struct MemoryEstimates {
  std::size_t budget = 0;        ///< ShellOptions::fields.max_memory_gb in bytes
  std::size_t surface = 0;       ///< the program, the caller's surface and the run's copy of it
  std::size_t fields = 0;        ///< plan_fields()'s estimate (FieldStats::estimated_bytes)
  std::size_t trace = 0;         ///< the traces (estimate_traces()), with the fields held
  std::size_t inner = 0;         ///< the inner vertices, with the traces held
  std::size_t validity = 0;      ///< the validity search and the assembled shell, traces held
  std::size_t write_shell = 0;   ///< write_shell() of this result (the result held)
  std::size_t write_fields = 0;  ///< write_fields() of this result (0 without keep_fields)
  std::size_t write_html = 0;    ///< report_html() / write_html() of this result (0: no shell)
};

/// Seconds per stage (wall time of this call; reading and writing files are the caller's).
struct StageTimings {
  double fields = 0;
  double trace = 0;
  double inner = 0;     ///< thickness limits and welding
  double validity = 0;  ///< the validity search, the final check and the quality summary
  double check = 0;     ///< of which: the final full check
  double total = 0;
};

/// Everything a run produced.
struct ShellResult {
  ShellOptions options;  ///< the options of the run
  InputReport input;
  /// The shell: points (surface vertices first, then inner vertices, then with --layers the
  /// layer points), positive tets, and per tet `source_triangle`, `layer` (1 at the outer
  /// surface) and `quality` (volume-length ratio), per point `inner` (1 for inner vertices and
  /// layer points), `thickness` (world units: an inner vertex's distance to the farthest surface
  /// vertex it belongs to, a layer point's to its own, 0 on the surface) and `surface_vertex`.
  /// Empty with traces_only.
  TetMesh mesh;
  /// The inner side as a surface (outward from the shell, i.e. facing the interior): one
  /// triangle per input triangle, a vertex kept on the surface being its own inner vertex.
  SurfaceMesh inner_surface;
  /// The input surface after validation (the outer boundary of the shell).
  SurfaceMesh surface;
  TraceResult traces;                    ///< every vertex's trace, with stop reasons
  FieldStats field_stats;                ///< voxel size, strategy, active voxels, seconds
  std::shared_ptr<const Fields> fields;  ///< only with ShellOptions::keep_fields
  ShellCounts counts;
  ShellCheckResult checks;  ///< the final full check (valid())
  ValidityReport validity;
  QualitySummary quality;  ///< histogram, min/median/mean Q, coverage, volume
  OptimizeSummary optimize;
  StageTimings timings;
  MemoryEstimates memory;  ///< every stage's estimated peak, checked against --max-memory
  /// What --repair did (set by the caller that repaired the input: load_repaired_surface()).
  std::optional<RepairReport> repair;
  /// Every notice of the run, one sentence each: validation's (flipped, triangulated, dropped
  /// vertices) first, then the fields' (interior filled by fast sweeping, ...).
  std::vector<std::string> notices;
};

/// Builds the shell of a validated surface (load_surface(), make_surface()).
/// \throw InputError (bad options), ResourceError, InternalError (a shell that could not be made
///        valid: a bug), CancelledError — see the file comment.
ShellResult build_shell(const LoadedSurface& surface, const ShellOptions& options,
                        const RunControl& control = {});

/// Validates `mesh` as make_surface() does (closed, 2-manifold, not crossing itself, finite,
/// indices in range; messages name `source`) and builds its shell. Vertices no triangle uses are
/// dropped (a notice says so), so the shell's first points are the used vertices in their order.
ShellResult build_shell(const SurfaceMesh& mesh, const ShellOptions& options,
                        const RunControl& control = {}, const std::string& source = "surface mesh");

/// The zero crossing of a .vdb level set (options.grid_name, options.adaptivity) as a validated
/// surface: the surface a level set input is shelled on. With options.repair the grid may be any
/// float volume — a level set of either sign, a fog volume (meshed at 0.5), a grid of no class
/// (volume_to_soup()) — and its surface is repaired as load_repaired_surface() does; `repair`
/// (if given) gets what the repair did and which grid, class and value were meshed.
/// \throw InputError naming the file, the grid and the fix (a level set positive inside, a grid
///        that is not a level set, a surface that is not closed: each suggests --repair).
LoadedSurface load_level_set_surface(const std::string& vdb_path, const ShellOptions& options,
                                     RepairReport* repair = nullptr);

/// `soup` (any polygons: holes, seams, overlaps, self-intersections) rebuilt as a closed,
/// 2-manifold surface through a volume (repair_surface(), options.repair_voxel_size or the
/// fields' voxel size, options.repair_closing) and validated; `report` says what the repair did.
/// The shell's outer boundary is this surface, not the input's polygons.
/// \throw InputError for bad options or an input with nothing to repair (repair.h);
///        InternalError if the rebuilt surface fails validation (a bug: please report).
LoadedSurface load_repaired_surface(const PolygonSoup& soup, const std::string& source,
                                    const ShellOptions& options, RepairReport& report);

/// Meshes the level set of `vdb_path` (load_level_set_surface()) and shells it, using the same
/// level set as the distance field (options.level_set must be empty). With options.repair, the
/// volume's repaired surface is shelled in fields of its own (result.repair says how).
ShellResult build_shell_from_level_set(const std::string& vdb_path, const ShellOptions& options,
                                       const RunControl& control = {});

/// Output file names a report mentions (empty: not written).
struct ReportFiles {
  std::string shell;  ///< the tet mesh file
};

/// The JSON report of a run (docs/usage.md lists every key), pretty-printed with two spaces.
/// `read_seconds` and `write_seconds` are the caller's file times (timings_s.read, .write);
/// timings_s.total is the run's total plus both.
std::string report_json(const ShellResult& result, const ReportFiles& files = {},
                        double read_seconds = 0, double write_seconds = 0);

/// The HTML report of a run (docs/report.md): one self-contained page — the input, cut-away
/// pictures of the shell, cross-sections, thickness and worst-tet pictures, the traces, the
/// quality and dihedral-angle histograms and the run's figures (report_json() among them).
/// Rendered in software, deterministic: the same result gives the same bytes. A traces_only
/// result gets the input and the traces only.
/// \throw ResourceError (before any work) if the result held and the page's own memory are
///        estimated above result.options.fields.max_memory_gb (MemoryEstimates::write_html).
std::string report_html(const ShellResult& result, const ReportFiles& files = {},
                        double read_seconds = 0, double write_seconds = 0);

/// Writes report_html() to `path`, atomically.
void write_html(const std::string& path, const ShellResult& result, const ReportFiles& files = {},
                double read_seconds = 0, double write_seconds = 0);

/// A 200 x 160 cut-away picture of the shell (PNG bytes) for html_index(); empty for a result
/// without tets.
std::string html_thumbnail(const ShellResult& result);

/// One input of a batch's index page.
struct HtmlIndexRow {
  std::string input;      ///< the input file
  std::string page;       ///< its report_html() page, relative to the index (empty: failed)
  std::string thumbnail;  ///< html_thumbnail() of its result (may be empty)
  std::string error;      ///< why it failed (empty: it succeeded)
  std::size_t tets = 0;
  double coverage = 0, min_quality = 0, median_quality = 0, seconds = 0;
};

/// The index page of a batch: one row per input (thumbnail, tets, coverage, quality, time,
/// status) linking each input's page.
std::string html_index(const std::vector<HtmlIndexRow>& rows);

/// Writes the shell to `path`, format from its extension (.vtu .vtk .msh .mesh .ele; .msh as
/// Gmsh `msh_version` 41 or 22), atomically (core/write/shell_writers.h).
/// \throw InputError for an unknown extension; ResourceError if the file cannot be written, or
///        (before anything is written) if the result held and the writer's own memory are
///        estimated above result.options.fields.max_memory_gb (MemoryEstimates::write_shell).
void write_shell(const std::string& path, const ShellResult& result, int msh_version = 41);

/// Writes the inner surface (.obj .ply .off), atomically.
void write_inner_surface(const std::string& path, const ShellResult& result);

/// Writes the traces as VTK polylines (.vtk), atomically.
void write_traces(const std::string& path, const ShellResult& result);

/// Writes the fields and the traces to a .vdb file (write_grids()).
/// \throw InputError if the result holds no fields (run with ShellOptions::keep_fields);
///        ResourceError as write_shell() (MemoryEstimates::write_fields: the traces grid).
void write_fields(const std::string& path, const ShellResult& result);

}  // namespace vdb_shell
