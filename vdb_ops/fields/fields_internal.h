// fields_internal.h — what the parts of the field build (vdb_ops/fields/*.cpp) share: OpenVDB
// type names, the grid frame and index-space mesh, the memory model, Fields::Impl, and each part's
// entry point. Internal to vdb_ops/ (includes OpenVDB; never installed).
//
// The build of build_fields() (fields.h), in order:
//   plan.cpp        plan_fields(): voxel size, frame, memory estimate; shared helpers
//   seed_band.cpp   mesh_to_band(): the signed band within kSeedBandVoxels of the surface, with
//                   each voxel's closest triangle
//   wavefront.cpp   fill_by_wavefront(): closest triangles into the interior and the exterior band
//   refine.cpp      the refinement passes near medial surfaces
//   derived.cpp     finish_fields(): the flux (and gradient) grids, the Fields object
//   build.cpp       build_fields(), fields_from_level_set(), the Fields accessors
//   probe.cpp       Fields::probe(): trilinear sampling for the tracer
//   vdb_io.cpp      .vdb reading and writing, volume_to_soup()
// Space: "index space" is OpenVDB's voxel index space (voxel centres at integer coordinates);
// lengths are world units unless a name says voxels.
#pragma once

#include <openvdb/openvdb.h>

#include <array>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "core/base/run_control.h"
#include "core/base/surface_mesh.h"
#include "vdb_ops/fields.h"

namespace vdb_shell {

using openvdb::Coord;
using openvdb::FloatGrid;
using openvdb::FloatTree;
using openvdb::Vec3SGrid;
using FloatLeaf = FloatTree::LeafNodeType;
using Vec3SLeaf = Vec3SGrid::TreeType::LeafNodeType;

namespace fields_detail {

inline constexpr double kGiB = 1024.0 * 1024.0 * 1024.0;
/// Voxels along a leaf node's side.
inline constexpr int kLeafDim = int(FloatLeaf::DIM);  // 8
/// Voxels of padding around the bounding box in the plan (band + flux stencil).
inline constexpr int kPadVoxels = 6;
/// Flux is stored for voxels with phi below this many voxel sizes (inside, plus one voxel out).
inline constexpr double kFluxPhiLimitVoxels = 1.0;
/// Largest index coordinate allowed (leaves room for OpenVDB's int32 coordinates).
inline constexpr double kMaxIndexCoord = 1 << 28;
/// Width of the band meshToVolume computes for the wavefront's seeds, voxels: at most 2, where
/// OpenVDB stops at its voxelization (which reaches ~2 voxels) and does not widen the band.
inline constexpr float kSeedBandVoxels = 2.0f;

// Memory model (bytes), calibrated on tests/bench measurements (peak RSS at 128..1024).
/// Peak bytes per interior voxel while the SDF is built (distance + closest-polygon trees).
double build_bytes_per_voxel(SdfMethod m);
/// Bytes per leaf touched by the surface band during the build (float, int32 and mask leaves).
inline constexpr double kBandLeafBytes = 6.0 * 1024.0;
/// Bytes of a stored gradient voxel (Vec3s plus leaf slack).
inline constexpr double kGradientBytesPerVoxel = 13.0;
/// Fixed overhead (library, mesh copies), bytes.
inline constexpr double kFixedBytes = 64.0 * 1024.0 * 1024.0;

/// openvdb::initialize(), once per process.
void init_openvdb();
/// 17 significant digits (reads back bit for bit), for messages and metadata.
std::string format_double(double v);
/// "1.23 GiB".
std::string format_gb(double bytes);
/// The name FieldStats::strategy reports for a method.
const char* method_name(SdfMethod m);

/// 3x3 matrix in row-major doubles; m[r][c].
using Mat3 = std::array<std::array<double, 3>, 3>;

/// Gradient map of a linear transform: grad_world = G * grad_index, G = J^{-T} where
/// J[r][c] = d world_r / d index_c. Also checks that the voxels are cubes (J a similarity).
struct GradientMap {
  Mat3 g{};
  double voxel_size = 0.0;
  bool cubic = false;
};
GradientMap gradient_map(const openvdb::math::Transform& xform);
/// m * v.
openvdb::Vec3d apply_map(const Mat3& m, const openvdb::Vec3d& v);

/// The grid frame of a build: cubic voxels of `voxel_size` with voxel (0, 0, 0) at `origin`, a
/// multiple of the voxel size below the bounding box (kPadVoxels of padding).
struct GridFrame {
  double voxel_size = 0.0;
  openvdb::Vec3d origin;  ///< world centre of voxel (0,0,0)
};
GridFrame frame_of(const BBox& box, double h);
openvdb::math::Transform::Ptr transform_of(const GridFrame& f);

/// A mesh in index space (float, as OpenVDB's mesh adapters take it).
struct IndexMesh {
  std::vector<openvdb::Vec3s> points;  ///< index space
  std::vector<openvdb::Vec3I> triangles;
};
IndexMesh to_index_space(const SurfaceMesh& mesh, const openvdb::math::Transform& xform);

/// OpenVDB meshToVolume: a narrow band of `ex` voxels outside and `in` voxels inside (in =
/// FLT_MAX fills the interior with distances to a nearby triangle). `index_grid`, if given,
/// receives each voxel's triangle; `flags` are meshToVolume's conversion flags.
FloatGrid::Ptr mesh_to_volume(const IndexMesh& m, const openvdb::math::Transform& xform, float ex,
                              float in, openvdb::Int32Grid* index_grid = nullptr, int flags = 0);

/// The seed band: meshToVolume(m, xform, ex, in, DISABLE_RENORMALIZATION, index_grid), with its
/// voxelization by bit rows where band_voxels_apply(); the same result either way. Widths in
/// voxels, at most 2. `flood_filled`, if given, receives the number of triangles voxelized by a
/// flood fill (0 when meshToVolume did everything).
FloatGrid::Ptr mesh_to_band(const IndexMesh& m, const openvdb::math::Transform& xform, float ex,
                            float in, openvdb::Int32Grid& index_grid,
                            std::size_t* flood_filled = nullptr);

/// Fills the interior of `sdf` (the seed band with its closest-triangle grid `index_grid`) and
/// its exterior up to `exterior_voxels` with distances to the closest triangles (wavefront.cpp),
/// then refines the voxels near medial surfaces. Reports to `monitor` (fractions 0.25..0.75).
void fill_by_wavefront(FloatGrid& sdf, const openvdb::Int32Grid& index_grid, const IndexMesh& m,
                       float exterior_voxels, const StageMonitor& monitor);

/// One Jacobi pass of closest-triangle propagation after meshToVolume's own interior
/// (SdfMethod::kMeshToVolumeInterior): every active voxel also measures the triangles its 26
/// neighbours found closest and keeps the smallest distance.
void refine_by_neighbours_jacobi(FloatGrid& sdf, const openvdb::Int32Grid& index_grid,
                                 const IndexMesh& m);

/// Upper bound of the interior depth of a level set, voxels: half the smallest side of the
/// active bounding box, plus a margin.
int interior_depth_bound(const FloatGrid& grid);

/// Derives the flux (and, with options.store_gradient, the gradient) of `sdf`, names and
/// classes the grids, fills the counts, timings (from `t0`) and parameters of `stats`, and
/// returns the Fields. Reports to `monitor` (fractions 0.75..1).
std::unique_ptr<Fields> finish_fields(FloatGrid::Ptr sdf, const FieldOptions& options,
                                      FieldStats stats, std::chrono::steady_clock::time_point t0,
                                      const StageMonitor& monitor);

/// \throw InputError naming `path` if it is missing or not a regular file.
void require_readable(const std::string& path);

/// Picks the one grid to read from the metadata of a file's grids (returns its name).
using GridSelector = std::function<std::string(const openvdb::GridPtrVec& metas)>;

/// The grids of the .vdb file `path` — all of them, or the one `select` names from their
/// metadata — read by OpenVDB in the program vdb_shell_vdb_reader (vdb_reader_main()), one run
/// of it per call, and handed back as OpenVDB's writer re-wrote them. OpenVDB 10's reader trusts
/// the sizes stored in a file (a corrupt one overflows its buffers: the .vdb fuzz target found
/// io::bloscFromStream copying a stored length into a node's buffer), so this process never
/// parses the file's bytes itself, only what the writer made of the reader's grids. A reader
/// that crashes or throws takes only its own process down. It is a program started afresh, not
/// a fork of this process: a fork's child runs without the parent's other threads, and a lock
/// one of them held (TBB's, the heap's) would hang it.
/// The reader runs on one thread and may map 64 times the file's size (at least 128 MiB): one
/// asking for more is reading sizes a corrupt file claims.
/// \throw InputError naming the file (what the reader or `select` said, or how it failed);
///        ResourceError if the reader cannot be found or started.
openvdb::GridPtrVecPtr read_vdb_isolated(const std::string& path, const GridSelector& select);

/// main() of vdb_shell_vdb_reader (vdb_reader_main.cpp), which read_vdb_isolated() starts with
/// a socket as its stdin and stdout: `--all FILE` replies with every grid of FILE; `--select FILE`
/// with their metadata, then reads a grid's name (its size in 8 bytes, then the name) and replies
/// with that grid. A reply is a status byte (0: grids as OpenVDB's writer wrote them; 2: the
/// error message, the last reply), the size of what follows (8 bytes) and that. Returns 1 for bad
/// arguments.
int vdb_reader_main(int argc, char** argv);

/// What mesh_volume() made: volumeToMesh's polygons (index lists into soup.points) and the same
/// as polygons facing the other way (out of the region below the iso-value for a level set, out
/// of the one above it for any other class).
struct VolumeMesh {
  std::vector<openvdb::Vec3I> triangles;
  std::vector<openvdb::Vec4I> quads;
  PolygonSoup soup;
};

/// volumeToMesh of `grid` at `isovalue` (its values' units) and `adaptivity`. An adaptive mesh
/// with zero-area triangles, crossing faces or faces folded back across an edge (polygons merged
/// across a thin part or a fold) is meshed again with merging turned off around them (OpenVDB's
/// adaptivity mask: 2, then 4, then 8 voxels around each of their corners), so the rest keeps its
/// large polygons; what is left after three such rounds is the caller's to judge.
VolumeMesh mesh_volume(const FloatGrid& grid, double isovalue, double adaptivity);

/// Which grids read_float_grid() takes.
enum class GridKinds {
  kLevelSet,  ///< float level sets only
  kAnyFloat,  ///< any float grid (a level set of either sign, a fog volume, ...)
};

/// Reads the float grid `grid_name` of `vdb_path` (empty name: 'surface' if it is a float level
/// set, else the first float level set; with kAnyFloat, else the first float fog volume, else
/// the first float grid) and checks its type (and, with kLevelSet, its class: `hint` ends that
/// message). `where` names it for messages.
/// \throw InputError naming the file, the grid and the fix.
FloatGrid::Ptr read_float_grid(const std::string& vdb_path, const std::string& grid_name,
                               GridKinds kinds, std::string& where, const std::string& hint = {});

}  // namespace fields_detail

/// The grids behind a Fields object.
struct Fields::Impl {
  FloatGrid::Ptr sdf;
  FloatGrid::Ptr flux;
  Vec3SGrid::Ptr gradient;  ///< null unless stored
  fields_detail::GradientMap gmap;
  FieldStats stats;
  std::map<std::string, std::string> parameters;
};

/// Access to a Fields object's grids for the parts of the build (Fields::impl() is private).
struct FieldsAccess {
  static const Fields::Impl& impl(const Fields& fields) { return *fields.impl_; }
};

}  // namespace vdb_shell
