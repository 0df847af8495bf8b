// plan.cpp — the fields' plan: voxel size, grid frame, memory estimate (fields.h,
// plan_fields()), and the small helpers every part of the build shares (fields_internal.h).
#include "vdb_ops/fields/fields_internal.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <mutex>
#include <sstream>

#include "core/base/errors.h"
#include "core/base/memory_budget.h"

namespace vdb_shell {
namespace fields_detail {

void init_openvdb() {
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });
}

std::string format_double(double v) {
  std::ostringstream s;
  s.precision(17);
  s << v;
  return s.str();
}

std::string format_gb(double bytes) {
  std::ostringstream s;
  s.precision(3);
  s << bytes / kGiB << " GiB";
  return s.str();
}

namespace {

/// Physical memory of the machine, bytes (0 if unknown).
double physical_memory_bytes() {
  const long pages = ::sysconf(_SC_PHYS_PAGES);
  const long page = ::sysconf(_SC_PAGE_SIZE);
  return pages > 0 && page > 0 ? double(pages) * double(page) : 0.0;
}

/// Total area of the mesh's triangles, world units squared.
double surface_area(const SurfaceMesh& mesh) {
  double area = 0.0;
  for (std::size_t f = 0; f < mesh.num_faces(); ++f) area += 0.5 * norm(face_normal_area(mesh, f));
  return area;
}

}  // namespace

GradientMap gradient_map(const openvdb::math::Transform& xform) {
  GradientMap out;
  const openvdb::Vec3d o = xform.indexToWorld(openvdb::Vec3d(0.0, 0.0, 0.0));
  Mat3 j{};
  std::array<double, 3> len{};
  for (int c = 0; c < 3; ++c) {
    openvdb::Vec3d e(0.0, 0.0, 0.0);
    e[c] = 1.0;
    const openvdb::Vec3d col = xform.indexToWorld(e) - o;
    for (int r = 0; r < 3; ++r) j[r][c] = col[r];
    len[c] = col.length();
  }
  const double h = len[0];
  out.voxel_size = h;
  double dot_max = 0.0;
  for (int a = 0; a < 3; ++a) {
    for (int b = a + 1; b < 3; ++b) {
      double d = 0.0;
      for (int r = 0; r < 3; ++r) d += j[r][a] * j[r][b];
      dot_max = std::max(dot_max, std::abs(d));
    }
  }
  out.cubic = h > 0.0 && std::abs(len[1] - h) <= 1e-6 * h && std::abs(len[2] - h) <= 1e-6 * h &&
              dot_max <= 1e-6 * h * h;
  // For a similarity J = h R: J^{-T} = R / h = J / h^2.
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) out.g[r][c] = h > 0.0 ? j[r][c] / (h * h) : 0.0;
  return out;
}

openvdb::Vec3d apply_map(const Mat3& m, const openvdb::Vec3d& v) {
  return {m[0][0] * v[0] + m[0][1] * v[1] + m[0][2] * v[2],
          m[1][0] * v[0] + m[1][1] * v[1] + m[1][2] * v[2],
          m[2][0] * v[0] + m[2][1] * v[1] + m[2][2] * v[2]};
}

const char* method_name(SdfMethod m) {
  switch (m) {
    case SdfMethod::kExactInterior:
      return "voxelized band + closest-triangle wavefront";
    case SdfMethod::kMeshToVolumeInterior:
      return "meshToVolume exact interior";
    case SdfMethod::kFastSweeping:
      break;
  }
  return "narrow band + fast sweeping interior";
}

double build_bytes_per_voxel(SdfMethod m) { return m == SdfMethod::kFastSweeping ? 50.0 : 10.0; }

GridFrame frame_of(const BBox& box, double h) {
  GridFrame f;
  f.voxel_size = h;
  for (int a = 0; a < 3; ++a) f.origin[a] = h * (std::floor(box.lo[a] / h) - kPadVoxels);
  return f;
}

openvdb::math::Transform::Ptr transform_of(const GridFrame& f) {
  openvdb::math::Transform::Ptr xform =
      openvdb::math::Transform::createLinearTransform(f.voxel_size);
  xform->postTranslate(f.origin);
  return xform;
}

IndexMesh to_index_space(const SurfaceMesh& mesh, const openvdb::math::Transform& xform) {
  IndexMesh out;
  out.points.reserve(mesh.num_vertices());
  for (const Vec3d& p : mesh.points) {
    out.points.emplace_back(xform.worldToIndex(openvdb::Vec3d(p.x, p.y, p.z)));
  }
  out.triangles.reserve(mesh.num_faces());
  for (const Triangle& t : mesh.triangles) out.triangles.emplace_back(t[0], t[1], t[2]);
  return out;
}

}  // namespace fields_detail

using namespace fields_detail;

double min_voxel_size() {
  // The linear maps refuse a voxel of volume below 3 x 1e-15 ("Non-zero scale values required").
  return 1.0001 * std::cbrt(3.0 * openvdb::math::Tolerance<double>::value());
}

FieldPlan plan_fields(const SurfaceMesh& mesh, const FieldOptions& options) {
  if (mesh.num_faces() == 0 || mesh.num_vertices() < 4) {
    throw InputError("cannot build fields: the surface has no faces");
  }
  if (!(options.flux_min >= 0.0 && options.flux_min <= 1.0)) {
    throw InputError("flux_min must lie in [0, 1] (average outward flux); got " +
                     format_double(options.flux_min));
  }
  if (!(options.max_memory_gb > 0.0) || !std::isfinite(options.max_memory_gb)) {
    throw InputError("--max-memory must be a positive number of GiB; got " +
                     format_double(options.max_memory_gb));
  }
  if (!(options.voxel_size >= 0.0) || !std::isfinite(options.voxel_size)) {
    throw InputError("--voxel-size must be a positive length in the input's units; got " +
                     format_double(options.voxel_size));
  }
  const BBox box = bounding_box(mesh);
  const double side = box.max_side();
  if (!(side > 0.0) || !std::isfinite(side)) {
    throw InputError("cannot build fields: the surface's bounding box is empty or not finite");
  }
  FieldPlan plan;
  if (options.voxel_size > 0.0) {
    plan.voxel_size = options.voxel_size;
    const double res = side / options.voxel_size;
    if (res < kMinResolution) {
      throw InputError("--voxel-size " + format_double(options.voxel_size) + " gives only " +
                       format_double(res) + " voxels along the longest bounding-box side (" +
                       format_double(side) + "); use at most " +
                       format_double(side / kMinResolution));
    }
    plan.resolution = res > 1e9 ? 1000000000 : int(std::ceil(res));
  } else {
    if (options.resolution < kMinResolution) {
      throw InputError("--resolution " + std::to_string(options.resolution) +
                       " is too coarse: use at least " + std::to_string(kMinResolution) +
                       " voxels along the longest side (the paper uses 128)");
    }
    plan.resolution = options.resolution;
    plan.voxel_size = side / options.resolution;
  }
  const double h = plan.voxel_size;
  const double min_voxel = min_voxel_size();
  if (h < min_voxel) {
    const double finest = side / min_voxel;
    throw InputError(
        "voxel size " + format_double(h) + " is below the smallest OpenVDB accepts (" +
        format_double(min_voxel) + " input units) for a surface " + format_double(side) +
        " units across: give its coordinates in a smaller unit (e.g. millimetres instead of "
        "metres)" +
        (finest >= kMinResolution
             ? ", or use at most --resolution " + std::to_string(int(std::floor(finest)))
             : std::string()));
  }
  const GridFrame frame = frame_of(box, h);
  plan.origin = {frame.origin[0], frame.origin[1], frame.origin[2]};
  double voxels = 1.0;
  for (int a = 0; a < 3; ++a) {
    const double n = std::ceil(box.extent()[a] / h) + 2.0 * kPadVoxels + 1.0;
    if (!(n < kMaxIndexCoord) || !(std::abs(box.lo[a] / h) < 1e15)) {
      throw InputError("voxel size " + format_double(h) + " is too small for a surface " +
                       format_double(box.extent()[a]) +
                       " units across: the grid would exceed OpenVDB's index range");
    }
    plan.dims[a] = int(n);
    voxels *= n;
  }
  plan.interior_voxels = std::min(voxels, std::abs(signed_volume(mesh)) / (h * h * h));
  const double band_faces = surface_area(mesh) / (h * h);
  plan.band_voxels = std::min(voxels, band_faces * 2.0 * kExteriorBandVoxels);
  const double band_leaves = std::min(voxels / 512.0, band_faces / 64.0 * 2.0);
  double bytes = kFixedBytes + plan.interior_voxels * build_bytes_per_voxel(options.sdf_method) +
                 band_leaves * kBandLeafBytes;
  if (options.store_gradient) {
    bytes += (plan.interior_voxels + plan.band_voxels) * kGradientBytesPerVoxel;
  }
  plan.estimated_bytes = bytes > 1e18 ? std::size_t(1e18) : std::size_t(bytes);

  const double scale = std::cbrt(options.max_memory_gb * kGiB / bytes);
  check_memory_budget("fields", plan.estimated_bytes, budget_bytes(options.max_memory_gb),
                      "the fields at resolution " + std::to_string(plan.resolution) +
                          " (voxel size " + format_double(h) + ")",
                      "lower --resolution (about " + std::to_string(int(plan.resolution * scale)) +
                          " fits) or raise --max-memory");
  const double physical = physical_memory_bytes();
  if (physical > 0.0 && bytes > 0.9 * physical) {
    throw ResourceError("fields: the fields at resolution " + std::to_string(plan.resolution) +
                        " need about " + format_gb(bytes) + ", more than this machine's " +
                        format_gb(physical) + " of memory; lower --resolution");
  }
  return plan;
}

}  // namespace vdb_shell
