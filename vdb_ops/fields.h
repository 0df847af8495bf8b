// fields.h — the distance, gradient and flux fields of a closed surface (pipeline stage 2).
//
// Built over OpenVDB grids, but this header includes no OpenVDB header: the grids live behind
// Fields' pimpl and reach core/ through the FieldSampler interface (core/trace/field_sampler.h).
//
//   surface   FloatGrid, class GRID_LEVEL_SET: signed distance to the mesh, world units, negative
//             inside. The interior is filled (every voxel inside is active, down to the deepest
//             point); outside, a narrow band of kExteriorBandVoxels voxels is active and the
//             background beyond it is +kExteriorBandVoxels * voxel_size (phi is clamped there).
//   gradient  grad(phi) at voxel centres by central differences, world units per world unit
//             (dimensionless). Either stored as a Vec3SGrid (FieldOptions::store_gradient) or
//             computed on the fly from the 32-voxel stencil of the SDF; the probe then interpolates
//             the 8 voxel gradients around a point trilinearly (paper §2.2). Both give the same
//             values up to float rounding.
//   flux      FloatGrid: the average outward flux of grad(phi) through the 26-neighbour cube
//             around each voxel (paper eq. 7 divided by 26, clamped to [-1, 1]); the outward normal
//             at a neighbour `a` is the unit offset (a - centre) / |a - centre|. Stored sparsely:
//             only voxels inside or within one voxel of the surface with |flux| >= flux_min are
//             active; everything else reads 0 (the background).
//
// Space: positions passed to or returned by this API are world coordinates (the input mesh's
// units and frame). Grids built by build_fields() have cubic voxels of edge voxel_size() whose
// centres lie at world points voxel_center(i, j, k) = origin + voxel_size * (i, j, k); the origin
// is a multiple of voxel_size near the mesh's bounding box, so index coordinates stay small and
// float index-space positions keep their precision for meshes far from the world origin.
//
// Determinism: the same mesh and options give bit-identical grids for any TBB thread count (the
// flux and gradient are pure per-voxel functions of the SDF; OpenVDB's mesh conversion reduces
// to per-voxel minima; each iteration of the interior wavefront reads only what the previous one
// wrote, and ties between triangles go to the smaller index).
//
// Errors: InputError for unusable options or files (exit 2), ResourceError when the estimated
// memory exceeds the budget or a file cannot be written (exit 3). Nothing is printed.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "core/base/run_control.h"
#include "core/base/surface_mesh.h"
#include "core/base/vec3.h"
#include "core/read/polygon_soup.h"
#include "core/trace/field_sampler.h"

namespace vdb_shell {

struct TraceResult;  // core/trace/trace.h

/// Smallest accepted resolution (voxels along the longest bounding-box side).
inline constexpr int kMinResolution = 8;
/// Width of the active band outside the surface, voxels (Houdini's default half-width).
inline constexpr double kExteriorBandVoxels = 3.0;

/// How the filled signed distance field is computed from a mesh.
enum class SdfMethod {
  /// The default. OpenVDB meshToVolume's voxelization (the voxels within 2 of the surface) with
  /// its closest-polygon grid (the voxelization itself is ours, with the same result: see
  /// compare_seed_band()), then a closest-triangle wavefront into the interior and out to the
  /// exterior band: every voxel takes the closest of the triangles its 26 neighbours took, voxels
  /// accepted in order of distance (one voxel per iteration); then voxels near medial surfaces
  /// try the triangles of their 5^3 neighbourhood. Exact up to float rounding: the distance to
  /// the closest triangle (tests compare it with kMeshToVolumeInterior; timings and memory in
  /// docs/benchmarks.md).
  kExactInterior,
  /// OpenVDB meshToVolume with an unbounded interior band (its own layer-by-layer closest-polygon
  /// expansion), then one pass in which every voxel also tries the triangles its 26 neighbours
  /// found closest. The same distances as kExactInterior up to a fraction of a voxel, and
  /// slower at high resolutions (docs/benchmarks.md); kept as the reference.
  kMeshToVolumeInterior,
  /// Narrow band (3 voxels each side) followed by first-order fast sweeping into the interior
  /// (tools::dilateSdf). First order: off by a voxel or more deep inside, and slower and larger
  /// than kExactInterior (docs/benchmarks.md); kept for comparison.
  kFastSweeping,
};

/// What the user asked for. Derived values come from plan_fields().
struct FieldOptions {
  /// Voxels along the longest side of the mesh's bounding box (paper: 128). >= kMinResolution.
  int resolution = 128;
  /// Voxel edge length, world units. When > 0 it overrides `resolution`.
  double voxel_size = 0.0;
  /// Memory budget of the run, GiB (2^30 bytes; --max-memory). The build's peak is estimated
  /// before anything is allocated; a larger estimate is refused with ResourceError. The later
  /// stages of build_shell() check their own estimates against the same budget
  /// (core/base/memory_budget.h).
  double max_memory_gb = 8.0;
  /// Smallest |flux| stored in the flux grid (average outward flux, dimensionless). Smaller values
  /// read as 0. Keep it at most half the tracer's medial threshold rho (default rho 0.1).
  double flux_min = 0.05;
  /// Store the gradient as a Vec3SGrid (written to .vdb as `gradient`) instead of computing it
  /// from the SDF's 32-voxel stencil at each query. Trace steps get a little faster, but the
  /// grids take about three times the memory and the build longer (docs/benchmarks.md); hence
  /// off by default.
  bool store_gradient = false;
  /// Interior fill method (see SdfMethod).
  SdfMethod sdf_method = SdfMethod::kExactInterior;
};

/// Derived grid geometry and memory estimate for a mesh and options (pure, cheap).
struct FieldPlan {
  double voxel_size = 0.0;          ///< world units
  Vec3d origin;                     ///< world position of voxel (0, 0, 0)'s centre
  std::array<int, 3> dims{};        ///< voxels along x, y, z covering the bbox plus padding
  int resolution = 0;               ///< voxels along the longest bbox side (as derived)
  double interior_voxels = 0.0;     ///< estimate: enclosed volume / voxel_size^3
  double band_voxels = 0.0;         ///< estimate: surface area / voxel_size^2 * band width
  std::size_t estimated_bytes = 0;  ///< estimated peak memory of the build
};

/// Inclusive index-space box.
struct IndexBox {
  std::array<int, 3> lo{};
  std::array<int, 3> hi{};
};

/// What a field build did and cost.
struct FieldStats {
  std::string strategy;                    ///< e.g. "meshToVolume exact interior"
  std::string source;                      ///< "mesh" or the .vdb path and grid name
  double voxel_size = 0.0;                 ///< world units
  std::array<int, 3> dims{};               ///< extent of the SDF's active voxels, voxels
  std::size_t sdf_active_voxels = 0;       ///< active voxels of `surface`
  std::size_t interior_voxels = 0;         ///< active voxels of `surface` with phi < 0
  std::size_t flux_active_voxels = 0;      ///< active voxels of `flux`
  std::size_t gradient_active_voxels = 0;  ///< active voxels of `gradient` (0 if not stored)
  std::size_t estimated_bytes = 0;         ///< plan_fields() estimate (0 for a level set input)
  std::size_t grid_bytes = 0;              ///< memory held by all grids after the build
  double seconds_sdf = 0.0;                ///< signed distance field (incl. interior fill)
  double seconds_fill = 0.0;         ///< of which: interior fill + refinement (kExactInterior)
  double seconds_refine = 0.0;       ///< of which: refinement pass (kMeshToVolumeInterior)
  double seconds_flux = 0.0;         ///< flux grid
  double seconds_gradient = 0.0;     ///< gradient grid (0 if not stored)
  double seconds_total = 0.0;        ///< whole build
  std::vector<std::string> notices;  ///< one sentence each, for the CLI to print
};

/// The fields of one surface. Immutable after construction; safe to share between threads.
class Fields : public FieldSampler {
 public:
  struct Impl;
  explicit Fields(std::unique_ptr<Impl> impl);
  ~Fields() override;
  Fields(const Fields&) = delete;
  Fields& operator=(const Fields&) = delete;

  /// A new probe (trilinear phi, gradient and flux) for the calling thread.
  std::unique_ptr<FieldProbe> probe() const override;
  /// Voxel edge length, world units.
  double voxel_size() const override;

  /// Counts, memory and timings of the build.
  const FieldStats& stats() const;
  /// World position of the centre of voxel (i, j, k).
  Vec3d voxel_center(int i, int j, int k) const;
  /// Index-space bounding box of the SDF's active voxels.
  IndexBox active_index_box() const;
  /// Signed distance stored at voxel (i, j, k), world units (the background where inactive).
  double phi_at_voxel(int i, int j, int k) const;
  /// Flux stored at voxel (i, j, k) (0 where inactive).
  double flux_at_voxel(int i, int j, int k) const;
  /// True when the gradient is stored as a grid (written to .vdb as `gradient`).
  bool has_gradient_grid() const;
  /// The build parameters, as written into the .vdb metadata (name -> value as text).
  const std::map<std::string, std::string>& parameters() const;

 private:
  friend struct FieldsAccess;  // the parts of the build (vdb_ops/fields/fields_internal.h)
  std::unique_ptr<Impl> impl_;
};

/// The smallest voxel size OpenVDB's linear maps accept, world units (1.44e-5: a voxel volume
/// of 3e-15, math/Maps.h). build_shell() builds the fields of a surface whose voxels would be
/// smaller at a power of two times its size.
double min_voxel_size();

/// Derives the voxel size, grid extent and memory estimate of build_fields(mesh, options).
/// \throw InputError if the mesh is empty, the options are invalid (resolution < kMinResolution,
///        voxel_size giving fewer than kMinResolution voxels along the longest side, NaN or
///        negative values, flux_min outside [0, 1]), the voxel size is below min_voxel_size(), or
///        index coordinates would overflow.
/// \throw ResourceError if the estimate exceeds max_memory_gb or 90% of the physical memory.
FieldPlan plan_fields(const SurfaceMesh& mesh, const FieldOptions& options);

/// Builds the filled SDF, the flux grid and (optionally) the gradient grid of a closed,
/// outward-oriented mesh (as load_surface() returns it).
/// Reports the stage's progress to `monitor` (the seed band, the interior fill by depth, the
/// flux by leaves) and checks it at every parallel step.
/// \throw InputError, ResourceError as plan_fields(); ResourceError on std::bad_alloc;
///        CancelledError from `monitor`.
std::unique_ptr<Fields> build_fields(const SurfaceMesh& mesh, const FieldOptions& options,
                                     const StageMonitor& monitor = StageMonitor());

/// Uses the level set `grid_name` of the .vdb file `vdb_path` as the SDF instead of building one
/// (empty name: the FloatGrid named "surface" if it is a level set, else the first FloatGrid
/// level set in the file). A narrow-band level set gets its interior filled by fast sweeping
/// (a notice says so). options.resolution and options.voxel_size are ignored (the grid's voxel
/// size rules); flux_min, store_gradient and max_memory_gb apply.
/// \throw InputError if the file is missing or unreadable, the grid is absent, not a FloatGrid,
///        not a level set (the message suggests setting the grid class), has non-cubic voxels or
///        a non-linear transform, or its active region does not contain every mesh vertex.
std::unique_ptr<Fields> fields_from_level_set(const std::string& vdb_path,
                                              const std::string& grid_name, const SurfaceMesh& mesh,
                                              const FieldOptions& options,
                                              const StageMonitor& monitor = StageMonitor());

/// Writes `surface` (GRID_LEVEL_SET), `flux`, if stored `gradient`, and, if `traces` is given,
/// `traces` (OpenVDB points, one per trace sample up to each end sample, with the `surface`
/// grid's transform; see vdb_ops/trace_points.h) to the .vdb file `path`, all in one atomic write
/// (temporary file + rename). Every grid carries fields.parameters() and `metadata` (string
/// values) as metadata; the file carries them too. The bytes depend only on the content: the
/// header's UUID, random in OpenVDB, is derived from the rest of the file.
/// \throw ResourceError naming `path` if the file cannot be written.
void write_grids(const std::string& path, const Fields& fields,
                 const std::map<std::string, std::string>& metadata,
                 const TraceResult* traces = nullptr);

/// Peak bytes write_grids() allocates besides what it is given, per byte of the grids
/// (FieldStats::grid_bytes): OpenVDB's writer buffers each grid while it serializes it (measured
/// 0.5-1.0 times the grids' memory on fandisk, fertility, box, torus, bowl, flap).
inline constexpr double kGridWriteFactor = 1.5;

/// Estimated peak bytes write_grids(path, fields, metadata, traces) allocates: the grids'
/// buffers (kGridWriteFactor) and the `traces` points grid (estimate_trace_points_bytes(),
/// vdb_ops/trace_points.h).
std::size_t estimate_write_grids_bytes(const Fields& fields, const TraceResult* traces);

/// A grid of a .vdb file as the OpenVDB reader sees it (for tests, the CLI and round trips).
struct VdbGridInfo {
  std::string name;
  std::string value_type;  ///< "float", "vec3s", ...
  std::string grid_class;  ///< "level set", "fog volume", "unknown", ...
  std::size_t active_voxels = 0;
  double voxel_size = 0.0;                      ///< world units (x axis)
  std::map<std::string, std::string> metadata;  ///< every grid metadata item, as text
  std::uint64_t checksum = 0;  ///< FNV-1a over (coord, value bits) of every active voxel
};

/// The surface of a .vdb grid (volume_to_soup()).
struct VolumeSurface {
  PolygonSoup soup;              ///< quads and triangles facing outward, world units
  std::string where;             ///< "grid 'NAME' of 'FILE'", for messages
  std::string grid_class;        ///< "level set", "fog volume", "unknown", ...
  double isovalue = 0.0;         ///< the value meshed
  bool positive_inside = false;  ///< the solid is where the values exceed `isovalue`
};

/// The surface of the grid `grid_name` of `vdb_path` as polygons (OpenVDB volumeToMesh).
/// `adaptivity` in [0, 1]: 0 keeps every voxel-sized quad, larger values merge flat regions
/// into fewer polygons; where merged polygons would cross or fold, they are meshed again without
/// merging around the defect. Pass the soup through make_surface() (load_surface.h).
/// Without `any_volume` (a .vdb input as it is): a float level set (empty name: 'surface', else
/// the first), negative inside, meshed at its zero crossing. With `any_volume` (--repair): any
/// float grid (empty name: as before, else the first fog volume, else the first float grid); a
/// fog volume, or a grid of no class holding densities (background 0, values in [0, 1]), is
/// meshed at 0.5, anything else at 0; the polygons face away from whichever side encloses
/// the solid (a level set positive inside is accepted).
/// \throw InputError for a missing file, a grid of the wrong type or class, a level set positive
///        inside without `any_volume`, or no surface.
VolumeSurface volume_to_soup(const std::string& vdb_path, const std::string& grid_name,
                             double adaptivity, bool any_volume);

/// Reads every grid of `path` with the OpenVDB API.
/// \throw InputError if the file is missing or not a .vdb file.
std::vector<VdbGridInfo> read_vdb_grid_infos(const std::string& path);

/// The same description of the in-memory grids of `fields` (as write_grids() would name them,
/// without the extra metadata).
std::vector<VdbGridInfo> grid_infos(const Fields& fields);

}  // namespace vdb_shell
