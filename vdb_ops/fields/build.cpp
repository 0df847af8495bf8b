// build.cpp — building the fields: build_fields() from a mesh (by SdfMethod),
// fields_from_level_set() from a .vdb level set, and the Fields accessors.
#include "vdb_ops/fields/fields_internal.h"

#include <openvdb/tools/FastSweeping.h>
#include <openvdb/tools/Interpolation.h>
#include <openvdb/tools/Prune.h>

#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <new>

#include "core/base/errors.h"
#include "core/base/memory_budget.h"
#include "core/base/run_control.h"
#include "core/base/timer.h"

namespace vdb_shell {

using namespace fields_detail;

namespace {

/// True if some inactive value is negative (the interior is not filled).
bool has_unfilled_interior(const FloatGrid& grid) {
  for (auto it = grid.tree().cbeginValueOff(); it; ++it) {
    if (*it < 0.0f) return true;
  }
  return false;
}

/// Fills the inactive interior of a level set by first-order fast sweeping.
FloatGrid::Ptr fill_interior_by_sweeping(const FloatGrid& grid) {
  FloatGrid::Ptr out = openvdb::tools::dilateSdf(
      grid, interior_depth_bound(grid), openvdb::tools::NN_FACE_EDGE_VERTEX, 1,
      openvdb::tools::FastSweepingDomain::SWEEP_LESS_THAN_ISOVALUE);
  openvdb::tools::pruneInactive(out->tree());
  out->setGridClass(openvdb::GRID_LEVEL_SET);
  return out;
}

}  // namespace

Fields::Fields(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Fields::~Fields() = default;

double Fields::voxel_size() const { return impl_->gmap.voxel_size; }
const FieldStats& Fields::stats() const { return impl_->stats; }
bool Fields::has_gradient_grid() const { return impl_->gradient != nullptr; }
const std::map<std::string, std::string>& Fields::parameters() const { return impl_->parameters; }

Vec3d Fields::voxel_center(int i, int j, int k) const {
  const openvdb::Vec3d w = impl_->sdf->transform().indexToWorld(openvdb::Vec3d(i, j, k));
  return {w[0], w[1], w[2]};
}

IndexBox Fields::active_index_box() const {
  const openvdb::CoordBBox b = impl_->sdf->evalActiveVoxelBoundingBox();
  return {{b.min()[0], b.min()[1], b.min()[2]}, {b.max()[0], b.max()[1], b.max()[2]}};
}

double Fields::phi_at_voxel(int i, int j, int k) const {
  return impl_->sdf->tree().getValue(Coord(i, j, k));
}

double Fields::flux_at_voxel(int i, int j, int k) const {
  return impl_->flux->tree().getValue(Coord(i, j, k));
}

std::unique_ptr<Fields> build_fields(const SurfaceMesh& mesh, const FieldOptions& options,
                                     const StageMonitor& monitor) {
  init_openvdb();
  const FieldPlan plan = plan_fields(mesh, options);
  const auto t0 = std::chrono::steady_clock::now();
  try {
    const GridFrame frame = frame_of(bounding_box(mesh), plan.voxel_size);
    const openvdb::math::Transform::Ptr xform = transform_of(frame);
    FieldStats stats;
    stats.strategy = method_name(options.sdf_method);
    stats.source = "mesh";
    stats.estimated_bytes = plan.estimated_bytes;
    FloatGrid::Ptr sdf;
    {
      const IndexMesh im = to_index_space(mesh, *xform);
      if (options.sdf_method == SdfMethod::kExactInterior) {
        // OpenVDB's renormalization (which smooths bumps where a mesh intersects itself) is
        // skipped: it costs ~20% of the band, and without it every band voxel holds the exact
        // distance to its own closest polygon, as the wavefront's voxels do.
        openvdb::Int32Grid::Ptr index_grid = openvdb::Int32Grid::create(-1);
        sdf = mesh_to_band(im, *xform, kSeedBandVoxels, kSeedBandVoxels, *index_grid);
        monitor.report(0.25);
        const auto t1 = std::chrono::steady_clock::now();
        fill_by_wavefront(*sdf, *index_grid, im, float(kExteriorBandVoxels), monitor);
        stats.seconds_fill = seconds_since(t1);
      } else if (options.sdf_method == SdfMethod::kMeshToVolumeInterior) {
        openvdb::Int32Grid::Ptr index_grid = openvdb::Int32Grid::create(-1);
        sdf = mesh_to_volume(im, *xform, float(kExteriorBandVoxels),
                             std::numeric_limits<float>::max(), index_grid.get());
        monitor.report(0.5);
        const auto t1 = std::chrono::steady_clock::now();
        refine_by_neighbours_jacobi(*sdf, *index_grid, im);
        stats.seconds_refine = seconds_since(t1);
      } else {
        FloatGrid::Ptr band =
            mesh_to_volume(im, *xform, float(kExteriorBandVoxels), float(kExteriorBandVoxels));
        monitor.report(0.25);
        sdf = fill_interior_by_sweeping(*band);
      }
    }
    monitor.report(0.75);
    stats.seconds_sdf = seconds_since(t0);
    auto fields = finish_fields(std::move(sdf), options, std::move(stats), t0, monitor);
    return fields;
  } catch (const std::bad_alloc&) {
    throw ResourceError("out of memory while building the fields at resolution " +
                        std::to_string(plan.resolution) + " (estimated " +
                        format_gb(double(plan.estimated_bytes)) + "); lower --resolution");
  }
}

std::unique_ptr<Fields> fields_from_level_set(const std::string& vdb_path,
                                              const std::string& grid_name, const SurfaceMesh& mesh,
                                              const FieldOptions& options,
                                              const StageMonitor& monitor) {
  init_openvdb();
  require_readable(vdb_path);
  if (!(options.flux_min >= 0.0 && options.flux_min <= 1.0)) {
    throw InputError("flux_min must lie in [0, 1]; got " + format_double(options.flux_min));
  }
  const auto t0 = std::chrono::steady_clock::now();
  std::string where;
  FloatGrid::Ptr grid = read_float_grid(vdb_path, grid_name, GridKinds::kLevelSet, where);
  if (!grid->transform().isLinear()) {
    throw InputError(where + " has a non-linear (frustum) transform; resample it to a linear one");
  }
  const GradientMap gmap = gradient_map(grid->transform());
  if (!gmap.cubic) {
    throw InputError(where + " has non-cubic or sheared voxels (voxel size " +
                     format_double(grid->voxelSize()[0]) + ", " +
                     format_double(grid->voxelSize()[1]) + ", " +
                     format_double(grid->voxelSize()[2]) + "); resample it to cubic voxels");
  }
  // Every mesh vertex must lie inside the active region (its 8 surrounding voxels active).
  {
    FloatGrid::ConstAccessor acc = grid->getConstAccessor();
    std::size_t outside = 0, first = 0;
    for (std::size_t v = 0; v < mesh.num_vertices(); ++v) {
      const Vec3d& p = mesh.points[v];
      const openvdb::Vec3d xyz = grid->transform().worldToIndex(openvdb::Vec3d(p.x, p.y, p.z));
      const Coord b(int(std::floor(xyz[0])), int(std::floor(xyz[1])), int(std::floor(xyz[2])));
      bool inside = std::isfinite(xyz[0]) && std::isfinite(xyz[1]) && std::isfinite(xyz[2]);
      for (int i = 0; inside && i < 8; ++i) {
        inside = acc.isValueOn(b.offsetBy(i & 1, (i >> 1) & 1, (i >> 2) & 1));
      }
      if (!inside && outside++ == 0) first = v;
    }
    if (outside > 0) {
      const Vec3d& p = mesh.points[first];
      throw InputError("the active region of " + where + " does not contain the mesh: " +
                       std::to_string(outside) + " of " + std::to_string(mesh.num_vertices()) +
                       " vertices lie outside it, the first is vertex " + std::to_string(first) +
                       " at (" + format_double(p.x) + ", " + format_double(p.y) + ", " +
                       format_double(p.z) +
                       "); pass the level set built from this mesh, or "
                       "drop --level-set to build one");
    }
  }
  // Memory: the filled interior of a narrow band is about as large as the bounding box's
  // interior; estimate it from the mesh like plan_fields() does.
  const double h = gmap.voxel_size;
  const double interior = std::abs(signed_volume(mesh)) / (h * h * h);
  const bool unfilled = has_unfilled_interior(*grid);
  const double bytes =
      kFixedBytes + double(grid->memUsage()) +
      interior * (unfilled ? build_bytes_per_voxel(SdfMethod::kFastSweeping) : 0.0) +
      (options.store_gradient ? interior * kGradientBytesPerVoxel : 0.0);
  check_memory_budget("fields", std::size_t(bytes), budget_bytes(options.max_memory_gb),
                      "the fields of " + where, "raise --max-memory");
  FieldStats stats;
  stats.source = vdb_path + ":" + grid->getName();
  stats.estimated_bytes = std::size_t(bytes);
  try {
    grid->tree().voxelizeActiveTiles();
    if (unfilled) {
      grid = fill_interior_by_sweeping(*grid);
      stats.strategy = "level set from file, interior filled by fast sweeping";
      stats.notices.push_back("the level set " + where +
                              " has an unfilled interior; it was filled by first-order fast "
                              "sweeping, which can be off by a voxel or more deep inside");
    } else {
      stats.strategy = "level set from file (filled interior)";
    }
    stats.seconds_sdf = seconds_since(t0);
    {
      FloatGrid::ConstAccessor acc = grid->getConstAccessor();
      double worst = 0.0;
      for (const Vec3d& p : mesh.points) {
        const openvdb::Vec3d xyz = grid->transform().worldToIndex(openvdb::Vec3d(p.x, p.y, p.z));
        worst = std::max(worst, std::abs(double(openvdb::tools::BoxSampler::sample(acc, xyz))));
      }
      if (worst > h) {
        stats.notices.push_back("the mesh does not lie on the zero level of " + where +
                                ": |phi| reaches " + format_double(worst / h) +
                                " voxels at a vertex");
      }
    }
    monitor.report(0.75);
    return finish_fields(std::move(grid), options, std::move(stats), t0, monitor);
  } catch (const std::bad_alloc&) {
    throw ResourceError("out of memory while preparing the fields of " + where);
  }
}

}  // namespace vdb_shell
