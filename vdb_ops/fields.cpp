// fields.cpp — see fields.h. The only translation unit that includes OpenVDB's tools.
//
// Layout: options and plan; the SDF methods (the seed band's voxelization and the
// closest-triangle wavefront, meshToVolume interior, fast sweeping); the per-leaf gradient/flux
// pass; the probe;
// .vdb reading and writing. Parallel loops run over leaf nodes in the tree's own (fixed) order and
// write one output slot per leaf, merged serially in that order, so results do not depend on the
// thread count.
#include "vdb_ops/fields.h"

#include <openvdb/openvdb.h>
#include <openvdb/io/File.h>
#include <openvdb/io/Stream.h>
#include <openvdb/tools/ChangeBackground.h>
#include <openvdb/tools/FastSweeping.h>
#include <openvdb/tools/Interpolation.h>
#include <openvdb/tools/MeshToVolume.h>
#include <openvdb/tools/Prune.h>
#include <openvdb/tools/VolumeToMesh.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cstdlib>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <deque>

#include <sys/mman.h>
#include <filesystem>
#include <limits>
#include <mutex>
#include <new>
#include <set>
#include <sstream>
#include <tuple>
#include <unordered_map>

#include "core/write/atomic_file.h"
#include "core/base/errors.h"
#include "core/base/timer.h"
// After the OpenVDB headers: declares make_trace_points_grid() (vdb_ops/trace_points.h).
#include "vdb_ops/trace_points.h"

namespace vdb_shell {

using openvdb::Coord;
using openvdb::FloatGrid;
using openvdb::FloatTree;
using openvdb::Vec3SGrid;
using FloatLeaf = FloatTree::LeafNodeType;
using Vec3SLeaf = Vec3SGrid::TreeType::LeafNodeType;

namespace {

constexpr double kGiB = 1024.0 * 1024.0 * 1024.0;
/// Voxels of padding around the bounding box in the plan (band + flux stencil).
constexpr int kPadVoxels = 6;
/// Flux is stored for voxels with phi below this many voxel sizes (inside, plus one voxel out).
constexpr double kFluxPhiLimitVoxels = 1.0;
/// Largest index coordinate we allow (leaves room for OpenVDB's int32 coordinates).
constexpr double kMaxIndexCoord = 1 << 28;

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

/// Physical memory of the machine, bytes (0 if unknown).
double physical_memory_bytes() {
  const long pages = ::sysconf(_SC_PHYS_PAGES);
  const long page = ::sysconf(_SC_PAGE_SIZE);
  return pages > 0 && page > 0 ? double(pages) * double(page) : 0.0;
}

double surface_area(const SurfaceMesh& mesh) {
  double area = 0.0;
  for (std::size_t f = 0; f < mesh.num_faces(); ++f) area += 0.5 * norm(face_normal_area(mesh, f));
  return area;
}

/// 3x3 matrix in row-major doubles; m[r][c].
using Mat3 = std::array<std::array<double, 3>, 3>;

/// Gradient map of a linear transform: grad_world = G * grad_index, G = J^{-T} where
/// J[r][c] = d world_r / d index_c. Also checks that the voxels are cubes (J a similarity).
struct GradientMap {
  Mat3 g{};
  double voxel_size = 0.0;
  bool cubic = false;
};

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
    case SdfMethod::kExactInterior: return "voxelized band + closest-triangle wavefront";
    case SdfMethod::kMeshToVolumeInterior: return "meshToVolume exact interior";
    case SdfMethod::kFastSweeping: break;
  }
  return "narrow band + fast sweeping interior";
}

// ---------------------------------------------------------------------------------------------
// Memory model (bytes), calibrated on tests/bench measurements (peak RSS at 128..1024).

/// Peak bytes per interior voxel while the SDF is built (distance + closest-polygon trees).
double build_bytes_per_voxel(SdfMethod m) { return m == SdfMethod::kFastSweeping ? 50.0 : 10.0; }
/// Bytes per leaf touched by the surface band during the build (float, int32 and mask leaves).
constexpr double kBandLeafBytes = 6.0 * 1024.0;
/// Bytes of a stored gradient voxel (Vec3s plus leaf slack).
constexpr double kGradientBytesPerVoxel = 13.0;
/// Fixed overhead (library, mesh copies), bytes.
constexpr double kFixedBytes = 64.0 * 1024.0 * 1024.0;

}  // namespace

// ---------------------------------------------------------------------------------------------
// Fields

struct Fields::Impl {
  FloatGrid::Ptr sdf;
  FloatGrid::Ptr flux;
  Vec3SGrid::Ptr gradient;  ///< null unless stored
  GradientMap gmap;
  FieldStats stats;
  std::map<std::string, std::string> parameters;
};

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

// ---------------------------------------------------------------------------------------------
// Plan

namespace {

struct GridFrame {
  double voxel_size = 0.0;
  openvdb::Vec3d origin;  ///< world centre of voxel (0,0,0)
};

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

}  // namespace

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

  const double budget = options.max_memory_gb * kGiB;
  if (bytes > budget) {
    const double scale = std::cbrt(budget / bytes);
    throw ResourceError("the fields at resolution " + std::to_string(plan.resolution) +
                        " (voxel size " + format_double(h) + ") need about " + format_gb(bytes) +
                        ", more than --max-memory " + format_double(options.max_memory_gb) +
                        " GiB; lower --resolution (about " +
                        std::to_string(int(plan.resolution * scale)) +
                        " fits) or raise --max-memory");
  }
  const double physical = physical_memory_bytes();
  if (physical > 0.0 && bytes > 0.9 * physical) {
    throw ResourceError("the fields at resolution " + std::to_string(plan.resolution) +
                        " need about " + format_gb(bytes) + ", more than this machine's " +
                        format_gb(physical) + " of memory; lower --resolution");
  }
  return plan;
}

// ---------------------------------------------------------------------------------------------
// Signed distance field

namespace {

struct IndexMesh {
  std::vector<openvdb::Vec3s> points;  ///< index space
  std::vector<openvdb::Vec3I> triangles;
};

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

/// Narrow band of `ex` voxels outside and `in` voxels inside (in = FLT_MAX fills the interior
/// with distances to a nearby triangle). `index_grid`, if given, receives each voxel's triangle.
FloatGrid::Ptr mesh_to_volume(const IndexMesh& m, const openvdb::math::Transform& xform, float ex,
                              float in, openvdb::Int32Grid* index_grid = nullptr, int flags = 0) {
  openvdb::tools::QuadAndTriangleDataAdapter<openvdb::Vec3s, openvdb::Vec3I> adapter(m.points,
                                                                                     m.triangles);
  openvdb::util::NullInterrupter interrupter;
  return openvdb::tools::meshToVolume<FloatGrid>(interrupter, adapter, xform, ex, in, flags,
                                                 index_grid);
}

// ---------------------------------------------------------------------------------------------
// The seed band: meshToVolume's narrow band, with a faster voxelization.
//
// meshToVolume starts by voxelizing (OpenVDB 10, tools/MeshToVolume.h, VoxelizePolygons): each
// triangle flood-fills from the voxel floor(a) through the voxels it intersects (squared distance
// to the voxel centre <= 0.75), measuring every voxel it reaches with
// closestPointOnTriangleToPoint; each voxel keeps the smallest squared distance and, among equal
// ones, the smallest triangle index. Tree accesses per voxel make this ~60% of the band's time
// (fandisk 512^3: 0.25 of 0.41 s).
// The voxels a triangle reaches are the 3^3 neighbourhoods of floor(a) and of the voxels it
// intersects, since those are 26-connected (the voxel centre nearest to any point of the triangle
// is within sqrt(0.75) of it, and moves to a neighbour as the point moves). band_voxels() finds
// them with 64-bit rows over the triangle's bounding box, measures them with the same OpenVDB
// function, and keeps the same minimum: its distance and index trees are meshToVolume's, voxel
// for voxel. (Only a rounding split of the intersecting voxels at exactly sqrt(0.75) could
// differ: then it also measures the voxels the flood fill would not reach.) mesh_to_band() then
// runs meshToVolume's remaining steps unchanged, in its order.

using Int32Leaf = openvdb::Int32Tree::LeafNodeType;

/// One voxelization leaf: squared distances (active where measured) and triangle indices, with
/// their buffers (LeafBuffer::data() is a call per voxel otherwise).
struct BandLeaf {
  std::unique_ptr<FloatLeaf> dist;
  std::unique_ptr<Int32Leaf> index;
  float* d2 = nullptr;
  std::int32_t* id = nullptr;
};

/// Leaf coordinates (origin / 8) packed into 63 bits; |voxel coordinates| < 2^23.
std::uint64_t band_leaf_key(const Coord& c) {
  auto part = [](int v) { return std::uint64_t(std::uint32_t((v >> 3) + (1 << 20)) & 0x1fffffu); };
  return part(c[0]) << 42 | part(c[1]) << 21 | part(c[2]);
}

/// One thread's voxelization: its leaves, and scratch space for one triangle at a time.
struct BandVoxels {
  std::unordered_map<std::uint64_t, std::size_t> slot;  ///< leaf key -> index in `leaves`
  std::deque<std::pair<std::uint64_t, BandLeaf>> leaves;  ///< a deque: kept by address
  std::vector<BandLeaf*> box_leaves;   ///< the leaves over the triangle's box (null: not yet)
  std::vector<std::uint64_t> bits;     ///< bit rows (fast path) or visited marks (flood fill)
  std::vector<float> measured;         ///< squared distances measured near the plane
  std::vector<Coord> stack;
  std::size_t flood_filled = 0;  ///< triangles voxelized by the flood fill

  BandLeaf& leaf_at(const Coord& ijk) {
    const std::uint64_t key = band_leaf_key(ijk);
    const auto [it, added] = slot.emplace(key, leaves.size());
    if (added) {
      const Coord origin(ijk[0] & ~7, ijk[1] & ~7, ijk[2] & ~7);
      BandLeaf leaf{std::make_unique<FloatLeaf>(origin, std::numeric_limits<float>::max(), false),
                    std::make_unique<Int32Leaf>(origin, std::int32_t(openvdb::util::INVALID_IDX),
                                                false)};
      leaf.d2 = leaf.dist->buffer().data();
      leaf.id = leaf.index->buffer().data();
      leaves.emplace_back(key, std::move(leaf));
    }
    return leaves[it->second].second;
  }
};

/// meshToVolume's measurement of voxel ijk against triangle (a, b, c): the squared distance, in
/// the same operations (note the order a, c, b).
float band_distance2(const Coord& ijk, const openvdb::Vec3d& a, const openvdb::Vec3d& b,
                     const openvdb::Vec3d& c) {
  openvdb::Vec3d uvw;
  const openvdb::Vec3d center(ijk[0], ijk[1], ijk[2]);
  return float(
      (center - openvdb::math::closestPointOnTriangleToPoint(a, c, b, center, uvw)).lengthSqr());
}

/// Keeps (d2, index) at ijk if it is smaller, or equal with a smaller index; NaN is not kept.
void band_keep(BandLeaf& leaf, const Coord& ijk, float d2, std::int32_t index) {
  if (std::isnan(d2)) return;
  const openvdb::Index pos = FloatLeaf::coordToOffset(ijk);
  if (d2 < leaf.d2[pos]) {
    leaf.d2[pos] = d2;
    leaf.id[pos] = index;
    leaf.dist->setActiveState(pos, true);
    leaf.index->setActiveState(pos, true);
  } else if (d2 == leaf.d2[pos]) {
    leaf.id[pos] = std::min(leaf.id[pos], index);
  }
}

/// Largest triangle box (voxels) voxelized here; larger ones go to meshToVolume whole.
constexpr std::size_t kBandMaxBoxVoxels = std::size_t(1) << 27;

/// Voxelizes triangle `index` into `out` as meshToVolume does (see above).
void band_voxelize_triangle(const IndexMesh& m, std::size_t index, BandVoxels& out) {
  const openvdb::Vec3I& t = m.triangles[index];
  const openvdb::Vec3d a(m.points[t[0]]), b(m.points[t[1]]), c(m.points[t[2]]);
  const std::int32_t id = std::int32_t(index);
  const Coord f = Coord::floor(a);
  // Every reached voxel lies within 2 of the triangle's bounding box.
  const Coord lo = Coord::floor(openvdb::math::minComponent(openvdb::math::minComponent(a, b), c))
                       .offsetBy(-2);
  const Coord hi = Coord::floor(openvdb::math::maxComponent(openvdb::math::maxComponent(a, b), c))
                       .offsetBy(2);
  const int nx = hi[0] - lo[0] + 1, ny = hi[1] - lo[1] + 1, nz = hi[2] - lo[2] + 1;
  const std::size_t volume = std::size_t(nx) * std::size_t(ny) * std::size_t(nz);
  const Coord leaf_lo(lo[0] >> 3, lo[1] >> 3, lo[2] >> 3);
  const int lx = (hi[0] >> 3) - leaf_lo[0] + 1, ly = (hi[1] >> 3) - leaf_lo[1] + 1,
            lz = (hi[2] >> 3) - leaf_lo[2] + 1;
  out.box_leaves.assign(std::size_t(lx) * std::size_t(ly) * std::size_t(lz), nullptr);
  auto keep = [&](const Coord& ijk, float d2) {
    BandLeaf*& leaf = out.box_leaves[(std::size_t((ijk[0] >> 3) - leaf_lo[0]) * std::size_t(ly) +
                                      std::size_t((ijk[1] >> 3) - leaf_lo[1])) *
                                         std::size_t(lz) +
                                     std::size_t((ijk[2] >> 3) - leaf_lo[2])];
    if (!leaf) leaf = &out.leaf_at(ijk);
    band_keep(*leaf, ijk, d2, id);
  };

  const openvdb::Vec3d ab = b - a, ac = c - a, cross = ab.cross(ac);
  const double d00 = ab.dot(ab), d01 = ab.dot(ac), d11 = ac.dot(ac);
  // Slivers (sin^2 of the angle at a below 1e-8, or NaN) leave the bound's barycentric
  // coordinates too ill-conditioned to trust near 0.75: they take the flood fill.
  const bool thin = !(cross.lengthSqr() > 1e-8 * d00 * d11);
  if (nz <= 64 && volume <= (std::size_t(1) << 21) && !thin) {
    // Lower bound of the squared distance: to the plane, plus within it to the farthest edge
    // line the projection lies beyond (heights over the edges times the barycentric deficit;
    // lower_to_closest()'s bound, in double: it decides which voxels are measured at all).
    const double len = std::sqrt(cross.lengthSqr()), inv = 1.0 / (d00 * d11 - d01 * d01);
    const openvdb::Vec3d n = cross / len, bv = (ab * d11 - ac * d01) * inv,
                         bw = (ac * d00 - ab * d01) * inv;
    const double hb = len / std::sqrt(d11), hc = len / std::sqrt(d00),
                 ha = len / (ac - ab).length();
    const std::size_t rows = std::size_t(nx) * std::size_t(ny);
    out.bits.assign(3 * rows, 0);
    std::uint64_t* hit = out.bits.data();  // intersecting voxels, then reused
    std::uint64_t* done = hit + rows;      // measured near the plane
    std::uint64_t* grow = done + rows;
    out.measured.resize(volume);
    // The intersecting voxels: measured only where the bound allows a squared distance of 0.75
    // (0.76: the bound is a double, the distance a float; either rounds far less).
    for (int x = 1; x < nx - 1; ++x)
      for (int y = 1; y < ny - 1; ++y) {
        const std::size_t r = std::size_t(x) * std::size_t(ny) + std::size_t(y);
        for (int z = 1; z < nz - 1; ++z) {
          const openvdb::Vec3d ap(lo[0] + x - a[0], lo[1] + y - a[1], lo[2] + z - a[2]);
          const double pd = n.dot(ap), v = bv.dot(ap), w = bw.dot(ap);
          const double e = std::max({0.0, -v * hb, -w * hc, (v + w - 1.0) * ha});
          if (!(pd * pd + e * e <= 0.76)) continue;
          const float d2 = band_distance2(lo.offsetBy(x, y, z), a, b, c);
          out.measured[r * std::size_t(nz) + std::size_t(z)] = d2;
          done[r] |= std::uint64_t(1) << z;
          if (!(d2 > 0.75f) && !std::isnan(d2)) hit[r] |= std::uint64_t(1) << z;
        }
      }
    // Reached: their 3^3 neighbourhoods (dilated along z, then y, then x), and floor(a)'s.
    for (std::size_t r = 0; r < rows; ++r) grow[r] = hit[r] | hit[r] << 1 | hit[r] >> 1;
    for (int x = 0; x < nx; ++x)
      for (int y = 0; y < ny; ++y) {
        const std::size_t r = std::size_t(x) * std::size_t(ny) + std::size_t(y);
        hit[r] = grow[r] | (y > 0 ? grow[r - 1] : 0) | (y + 1 < ny ? grow[r + 1] : 0);
      }
    for (int x = 0; x < nx; ++x)
      for (int y = 0; y < ny; ++y) {
        const std::size_t r = std::size_t(x) * std::size_t(ny) + std::size_t(y);
        grow[r] = hit[r] | (x > 0 ? hit[r - std::size_t(ny)] : 0) |
                  (x + 1 < nx ? hit[r + std::size_t(ny)] : 0);
      }
    const Coord fl = f - lo;
    for (int x = fl[0] - 1; x <= fl[0] + 1; ++x)
      for (int y = fl[1] - 1; y <= fl[1] + 1; ++y) {
        grow[std::size_t(x) * std::size_t(ny) + std::size_t(y)] |= std::uint64_t(7) << (fl[2] - 1);
      }
    for (int x = 0; x < nx; ++x)
      for (int y = 0; y < ny; ++y) {
        const std::size_t r = std::size_t(x) * std::size_t(ny) + std::size_t(y);
        for (std::uint64_t bits = grow[r]; bits; bits &= bits - 1) {
          const int z = __builtin_ctzll(bits);
          const Coord ijk = lo.offsetBy(x, y, z);
          keep(ijk, done[r] >> z & 1u ? out.measured[r * std::size_t(nz) + std::size_t(z)]
                                      : band_distance2(ijk, a, b, c));
        }
      }
    return;
  }
  // Thin triangles (the plane bound is unreliable) and tall boxes: the flood fill itself.
  ++out.flood_filled;
  out.bits.assign((volume + 63) / 64, 0);
  auto first_visit = [&](const Coord& ijk) {
    const Coord d = ijk - lo;
    // (Outside the box only if rounding put an intersecting voxel beyond sqrt(0.75) + 1.)
    if (d[0] < 0 || d[1] < 0 || d[2] < 0 || d[0] >= nx || d[1] >= ny || d[2] >= nz) return false;
    const std::size_t i =
        (std::size_t(d[0]) * std::size_t(ny) + std::size_t(d[1])) * std::size_t(nz) +
        std::size_t(d[2]);
    const std::uint64_t bit = std::uint64_t(1) << (i & 63);
    const bool seen = (out.bits[i >> 6] & bit) != 0;
    out.bits[i >> 6] |= bit;
    return !seen;
  };
  auto visit = [&](const Coord& ijk) {
    const float d2 = band_distance2(ijk, a, b, c);
    keep(ijk, d2);
    return !(d2 > 0.75f) && !std::isnan(d2);
  };
  out.stack.assign(1, f);
  first_visit(f);
  visit(f);
  while (!out.stack.empty()) {
    const Coord ijk = out.stack.back();
    out.stack.pop_back();
    for (int i = 0; i < 26; ++i) {
      const Coord nijk = ijk + openvdb::util::COORD_OFFSETS[i];
      if (first_visit(nijk) && visit(nijk)) out.stack.push_back(nijk);
    }
  }
}

/// True if band_voxels() handles `m`: OpenVDB subdivides the large triangles of meshes with
/// fewer than 1000 polygons (measuring against the parts), and the boxes must fit.
bool band_voxels_apply(const IndexMesh& m) {
  if (m.triangles.size() < 1000) return false;
  for (const openvdb::Vec3I& t : m.triangles) {
    openvdb::Vec3d lo(m.points[t[0]]), hi(lo);
    for (int k = 1; k < 3; ++k) {
      lo = openvdb::math::minComponent(lo, openvdb::Vec3d(m.points[t[k]]));
      hi = openvdb::math::maxComponent(hi, openvdb::Vec3d(m.points[t[k]]));
    }
    if (!(lo[0] > -4.0e6 && lo[1] > -4.0e6 && lo[2] > -4.0e6 && hi[0] < 4.0e6 &&
          hi[1] < 4.0e6 && hi[2] < 4.0e6)) {
      return false;
    }
    const openvdb::Vec3d d = hi - lo + openvdb::Vec3d(5.0);
    if (d[0] * d[1] * d[2] > double(kBandMaxBoxVoxels)) return false;
  }
  return true;
}

/// meshToVolume's distance and index trees after voxelization (see above), leaf for leaf.
/// Returns the number of triangles voxelized by the flood fill.
std::size_t band_voxels(const IndexMesh& m, FloatTree& dist, openvdb::Int32Tree& index) {
  tbb::enumerable_thread_specific<BandVoxels> threads;
  const StageMonitor* monitor = StageMonitor::active();  // build_fields()'s, checked per range
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, m.triangles.size(), 64),
                    [&](const tbb::blocked_range<std::size_t>& range) {
    if (monitor) monitor->check();
    BandVoxels& out = threads.local();
    for (std::size_t i = range.begin(); i < range.end(); ++i) band_voxelize_triangle(m, i, out);
  });
  // Leaves of the same key from different threads: the smaller distance, then the smaller index
  // (the same whatever the order, as in meshToVolume's own merge).
  std::vector<std::pair<std::uint64_t, BandLeaf*>> all;
  std::size_t flood_filled = 0;
  for (BandVoxels& t : threads) {
    for (auto& [key, leaf] : t.leaves) all.emplace_back(key, &leaf);
    flood_filled += t.flood_filled;
  }
  std::sort(all.begin(), all.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
  std::vector<std::size_t> first;
  for (std::size_t i = 0; i < all.size(); ++i) {
    if (i == 0 || all[i].first != all[i - 1].first) first.push_back(i);
  }
  first.push_back(all.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, first.size() - 1, 64),
                    [&](const tbb::blocked_range<std::size_t>& range) {
    for (std::size_t j = range.begin(); j < range.end(); ++j) {
      BandLeaf& to = *all[first[j]].second;
      for (std::size_t k = first[j] + 1; k < first[j + 1]; ++k) {
        const BandLeaf& from = *all[k].second;
        for (auto it = from.dist->cbeginValueOn(); it; ++it) {
          band_keep(to, it.getCoord(), *it, from.index->getValue(it.pos()));
        }
      }
    }
  });
  for (std::size_t j = 0; j + 1 < first.size(); ++j) {
    BandLeaf& leaf = *all[first[j]].second;
    dist.addLeaf(leaf.dist.release());
    index.addLeaf(leaf.index.release());
  }
  return flood_filled;
}

/// The seed band: meshToVolume(m, xform, ex, in, DISABLE_RENORMALIZATION, index_grid) with
/// band_voxels() for its voxelization where that applies, the same result either way. Widths in
/// voxels, at most 2 (meshToVolume widens wider bands after the steps below). `flood_filled`,
/// if given, receives the number of triangles voxelized by the flood fill (0 when meshToVolume
/// did everything).
FloatGrid::Ptr mesh_to_band(const IndexMesh& m, const openvdb::math::Transform& xform, float ex,
                            float in, openvdb::Int32Grid& index_grid,
                            std::size_t* flood_filled = nullptr) {
  namespace internal = openvdb::tools::mesh_to_volume_internal;
  if (!(ex <= 2.0f && in <= 2.0f) || !band_voxels_apply(m)) {
    if (flood_filled) *flood_filled = 0;
    return mesh_to_volume(m, xform, ex, in, &index_grid, openvdb::tools::DISABLE_RENORMALIZATION);
  }
  // From here on, meshToVolume's own steps for a signed band no wider than two voxels.
  using Adapter = openvdb::tools::QuadAndTriangleDataAdapter<openvdb::Vec3s, openvdb::Vec3I>;
  const Adapter adapter(m.points, m.triangles);
  FloatGrid::Ptr grid(new FloatGrid(std::numeric_limits<float>::max()));
  grid->setTransform(xform.copy());
  grid->setGridClass(openvdb::GRID_LEVEL_SET);
  index_grid.newTree();
  index_grid.setTransform(xform.copy());
  FloatTree& dist = grid->tree();
  openvdb::Int32Tree& index = index_grid.tree();
  const float h = float(xform.voxelSize()[0]);
  const float exterior = ex * h, interior = in * h;

  const std::size_t flooded = band_voxels(m, dist, index);
  if (flood_filled) *flood_filled = flooded;
  openvdb::tools::traceExteriorBoundaries(dist);
  std::vector<FloatLeaf*> nodes;
  nodes.reserve(dist.leafCount());
  dist.getNodes(nodes);
  const tbb::blocked_range<std::size_t> range(0, nodes.size());
  tbb::parallel_for(range,
                    internal::ComputeIntersectingVoxelSign<FloatTree, Adapter>(nodes, dist, index,
                                                                               adapter));
  tbb::parallel_for(range, internal::ValidateIntersectingVoxels<FloatTree>(dist, nodes));
  tbb::parallel_for(range, internal::RemoveSelfIntersectingSurface<FloatTree>(nodes, dist, index));
  openvdb::tools::pruneInactive(dist, /*threaded=*/true);
  openvdb::tools::pruneInactive(index, /*threaded=*/true);
  if (dist.activeVoxelCount() == 0) {
    dist.clear();
    dist.root().setBackground(exterior, /*updateChildNodes=*/false);
    return grid;
  }
  nodes.clear();
  dist.getNodes(nodes);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nodes.size()),
                    internal::TransformValues<FloatTree>(nodes, h, /*unsignedDist=*/false));
  dist.root().setBackground(exterior, /*updateChildNodes=*/false);
  openvdb::tools::signedFloodFillWithValues(dist, exterior, -interior);
  // (meshToVolume widens the band here when a width exceeds 2 voxels, and renormalizes when
  // asked; neither applies.)
  nodes.clear();
  dist.getNodes(nodes);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nodes.size()),
                    internal::InactivateValues<FloatTree>(nodes, exterior, interior));
  openvdb::tools::pruneLevelSet(dist, exterior, -interior);
  return grid;
}

/// Squared distance from p to triangle (a, b, c) (Ericson, Real-Time Collision Detection 5.1.5).
double point_triangle_distance2(const openvdb::Vec3d& p, const openvdb::Vec3d& a,
                                const openvdb::Vec3d& b, const openvdb::Vec3d& c) {
  const openvdb::Vec3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0.0 && d2 <= 0.0) return ap.lengthSqr();
  const openvdb::Vec3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3) return bp.lengthSqr();
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
    const double v = d1 / (d1 - d3);
    return (ap - ab * v).lengthSqr();
  }
  const openvdb::Vec3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6) return cp.lengthSqr();
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
    const double w = d2 / (d2 - d6);
    return (ap - ac * w).lengthSqr();
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return (bp - (c - b) * w).lengthSqr();
  }
  const double denom = 1.0 / (va + vb + vc);
  const double v = vb * denom, w = vc * denom;
  return (ap - ab * v - ac * w).lengthSqr();
}

/// One Jacobi pass of closest-triangle propagation: every active voxel also measures its distance
/// to the triangles its 26 neighbours found closest and keeps the smallest. OpenVDB's band
/// expansion only looks at triangles of voxels within a Manhattan radius and never revisits a
/// voxel, which leaves bumps of up to ~0.3 voxels a few voxels deep; this pass removes most.
/// Only |phi| decreases (every candidate is a true distance to a triangle); signs are kept.
/// Reads triangle ids, writes only each voxel's own phi: deterministic for any thread count.
void refine_with_neighbour_triangles(FloatGrid& sdf, const openvdb::Int32Grid& index_grid,
                                     const IndexMesh& m) {
  using IntLeaf = openvdb::Int32Tree::LeafNodeType;
  std::vector<FloatLeaf*> leaves;
  leaves.reserve(sdf.tree().leafCount());
  sdf.tree().getNodes(leaves);
  const double h = sdf.voxelSize()[0];
  const std::int32_t n_tris = std::int32_t(m.triangles.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, leaves.size(), 16),
                    [&](const tbb::blocked_range<std::size_t>& range) {
    openvdb::Int32Grid::ConstAccessor acc = index_grid.getConstAccessor();
    constexpr int kB = 10;  // leaf plus one voxel each side
    std::array<std::int32_t, kB * kB * kB> ids;
    for (std::size_t li = range.begin(); li < range.end(); ++li) {
      FloatLeaf& leaf = *leaves[li];
      const Coord origin = leaf.origin();
      for (int nx = -1; nx <= 1; ++nx)
        for (int ny = -1; ny <= 1; ++ny)
          for (int nz = -1; nz <= 1; ++nz) {
            const IntLeaf* il = acc.probeConstLeaf(origin.offsetBy(nx * 8, ny * 8, nz * 8));
            auto lo = [](int n) { return n < 0 ? 0 : (n == 0 ? 1 : 9); };
            auto hi = [](int n) { return n < 0 ? 1 : (n == 0 ? 9 : 10); };
            for (int bx = lo(nx); bx < hi(nx); ++bx)
              for (int by = lo(ny); by < hi(ny); ++by)
                for (int bz = lo(nz); bz < hi(nz); ++bz) {
                  std::int32_t id = -1;
                  if (il) {
                    const openvdb::Index pos =
                        (((bx - 1) & 7) << 6) | (((by - 1) & 7) << 3) | ((bz - 1) & 7);
                    if (il->isValueOn(pos)) id = il->getValue(pos);
                  }
                  ids[(bx * kB + by) * kB + bz] = id;
                }
          }
      for (auto it = leaf.beginValueOn(); it; ++it) {
        const Coord c = it.getCoord() - origin;
        const std::int32_t own = ids[((c[0] + 1) * kB + c[1] + 1) * kB + c[2] + 1];
        std::array<std::int32_t, 27> cand;
        int n = 0;
        for (int dx = 0; dx < 3; ++dx)
          for (int dy = 0; dy < 3; ++dy)
            for (int dz = 0; dz < 3; ++dz) {
              const std::int32_t id = ids[((c[0] + dx) * kB + c[1] + dy) * kB + c[2] + dz];
              if (id < 0 || id >= n_tris || id == own) continue;
              if (std::find(cand.begin(), cand.begin() + n, id) == cand.begin() + n) {
                cand[n++] = id;
              }
            }
        if (n == 0) continue;
        const openvdb::Vec3d p = it.getCoord().asVec3d();
        const float phi = *it;
        double best = double(std::abs(phi)) / h;
        best *= best;
        for (int k = 0; k < n; ++k) {
          const openvdb::Vec3I& t = m.triangles[std::size_t(cand[k])];
          best = std::min(best, point_triangle_distance2(p, m.points[t[0]], m.points[t[1]],
                                                         m.points[t[2]]));
        }
        const float d = float(std::sqrt(best) * h);
        if (d < std::abs(phi)) it.setValue(phi < 0.0f ? -d : d);
      }
    }
  });
}

// ---------------------------------------------------------------------------------------------
// Band widening and interior fill by a closest-triangle wavefront (SdfMethod::kExactInterior).
//
// Seeds: the voxels within kSeedBandVoxels of the surface from meshToVolume (its voxelization
// alone: OpenVDB widens a band only beyond 2 voxels, at ~3x the wavefront's cost per voxel), whose
// voxels know their closest triangle (the polygon index grid). Every interior voxel, and every
// outside voxel up to the exterior band's width, then takes the closest of the triangles that its
// 26 neighbours took, and voxels are accepted in order of distance: outer iteration t accepts the
// voxels whose best distance so far is below seed band + 1 + t voxels. Accepting by distance
// rather than by topological layer matters: a voxel reached first along a diagonal would
// otherwise keep a triangle from the side (several voxels too far on a fine sphere). A voxel
// keeps its tentative (distance, triangle) between iterations and only measures triangles of
// neighbours accepted in the previous iteration, so each (voxel, triangle) pair is measured about
// once.
//
// Determinism: iteration t reads only what iteration t - 1 wrote (the `fresh` masks and the
// triangles of accepted voxels); each leaf writes only its own voxels and masks; ties go to the
// smaller triangle index. The result does not depend on the thread count or schedule.

/// A triangle in index space, float, prepared for point_triangle_distance2f.
struct TriangleF {
  float a[3], ab[3], ac[3];
  /// Face region test: the barycentric coordinates (v, w) of p's projection are (bv . ap,
  /// bw . ap); the distance there is |n . ap| (n: unit normal). NaN for degenerate triangles
  /// (every comparison false: the face test fails, and no normal "faces away").
  float bv[3], bw[3], n[3];
  /// Heights of b, c and a over the opposite edges (ac, ab, bc): a point whose barycentric
  /// coordinate of b is bv < 0 lies at least -bv * height[0] from the triangle within its plane.
  float height[3];
};

inline float dot3(const float* u, const float* v) {
  return u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
}

std::vector<TriangleF> float_triangles(const IndexMesh& m) {
  std::vector<TriangleF> out(m.triangles.size());
  for (std::size_t i = 0; i < out.size(); ++i) {
    const openvdb::Vec3s& a = m.points[m.triangles[i][0]];
    const openvdb::Vec3s& b = m.points[m.triangles[i][1]];
    const openvdb::Vec3s& c = m.points[m.triangles[i][2]];
    TriangleF& t = out[i];
    for (int k = 0; k < 3; ++k) {
      t.a[k] = a[k];
      t.ab[k] = b[k] - a[k];
      t.ac[k] = c[k] - a[k];
    }
    const float d00 = dot3(t.ab, t.ab), d01 = dot3(t.ab, t.ac), d11 = dot3(t.ac, t.ac);
    const float inv = 1.0f / (d00 * d11 - d01 * d01);
    const float cr[3] = {t.ab[1] * t.ac[2] - t.ab[2] * t.ac[1],
                         t.ab[2] * t.ac[0] - t.ab[0] * t.ac[2],
                         t.ab[0] * t.ac[1] - t.ab[1] * t.ac[0]};
    const float len = std::sqrt(dot3(cr, cr));
    for (int k = 0; k < 3; ++k) {
      t.bv[k] = (d11 * t.ab[k] - d01 * t.ac[k]) * inv;
      t.bw[k] = (d00 * t.ac[k] - d01 * t.ab[k]) * inv;
      t.n[k] = cr[k] / len;
    }
    const float bc[3] = {t.ac[0] - t.ab[0], t.ac[1] - t.ab[1], t.ac[2] - t.ab[2]};
    t.height[0] = len / std::sqrt(d11);
    t.height[1] = len / std::sqrt(d00);
    t.height[2] = len / std::sqrt(dot3(bc, bc));
  }
  return out;
}


/// Squared distance from p to a triangle, float (Ericson 5.1.5, as point_triangle_distance2).
inline float point_triangle_distance2f(const float (&p)[3], const TriangleF& t) {
  const float ap[3] = {p[0] - t.a[0], p[1] - t.a[1], p[2] - t.a[2]};
  // Most points project into the triangle: the plane's distance, without Ericson's regions.
  const float bv = dot3(t.bv, ap), bw = dot3(t.bw, ap);
  if (bv >= 0.0f && bw >= 0.0f && bv + bw <= 1.0f) {
    const float d = dot3(t.n, ap);
    return d * d;
  }
  const float d1 = dot3(t.ab, ap), d2 = dot3(t.ac, ap);
  if (d1 <= 0.0f && d2 <= 0.0f) return dot3(ap, ap);
  const float bp[3] = {ap[0] - t.ab[0], ap[1] - t.ab[1], ap[2] - t.ab[2]};
  const float d3 = dot3(t.ab, bp), d4 = dot3(t.ac, bp);
  if (d3 >= 0.0f && d4 <= d3) return dot3(bp, bp);
  const float vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0f && d1 >= 0.0f && d3 <= 0.0f) {
    const float v = d1 / (d1 - d3);
    const float q[3] = {ap[0] - t.ab[0] * v, ap[1] - t.ab[1] * v, ap[2] - t.ab[2] * v};
    return dot3(q, q);
  }
  const float cp[3] = {ap[0] - t.ac[0], ap[1] - t.ac[1], ap[2] - t.ac[2]};
  const float d5 = dot3(t.ab, cp), d6 = dot3(t.ac, cp);
  if (d6 >= 0.0f && d5 <= d6) return dot3(cp, cp);
  const float vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0f && d2 >= 0.0f && d6 <= 0.0f) {
    const float w = d2 / (d2 - d6);
    const float q[3] = {ap[0] - t.ac[0] * w, ap[1] - t.ac[1] * w, ap[2] - t.ac[2] * w};
    return dot3(q, q);
  }
  const float va = d3 * d6 - d5 * d4;
  if (va <= 0.0f && (d4 - d3) >= 0.0f && (d5 - d6) >= 0.0f) {
    const float w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    const float bc[3] = {t.ac[0] - t.ab[0], t.ac[1] - t.ab[1], t.ac[2] - t.ab[2]};
    const float q[3] = {bp[0] - bc[0] * w, bp[1] - bc[1] * w, bp[2] - bc[2] * w};
    return dot3(q, q);
  }
  const float denom = 1.0f / (va + vb + vc);
  const float v = vb * denom, w = vc * denom;
  const float q[3] = {ap[0] - t.ab[0] * v - t.ac[0] * w, ap[1] - t.ab[1] * v - t.ac[1] * w,
                      ap[2] - t.ab[2] * v - t.ac[2] * w};
  return dot3(q, q);
}

/// Lowers (best, best_id) to the closest of the triangles cand[0, nc) to p (squared distance,
/// ties to the smaller index), exactly as measuring each with point_triangle_distance2f() would,
/// but cheaper: the triangles p projects into are measured first (their distance is the
/// plane's), and the others only where a lower bound of their distance (to the plane, and within
/// it to the triangle's nearest edge line) does not already exceed the best by more than
/// rounding. Fandisk 512^3: 18.5M of the wavefront's 35.2M measurements project outside the
/// triangle; the bound rules out 7.7M of them even without measuring the others first.
inline void lower_to_closest(const float (&p)[3], const std::int32_t* cand, int nc,
                             const std::vector<TriangleF>& tris, float& best,
                             std::int32_t& best_id) {
  float bound[124];  // up to the 5^3 neighbourhood's triangles (refinement)
  int later[124];
  int n_later = 0;
  for (int q = 0; q < nc; ++q) {
    const TriangleF& t = tris[std::size_t(cand[q])];
    const float ap[3] = {p[0] - t.a[0], p[1] - t.a[1], p[2] - t.a[2]};
    const float bv = dot3(t.bv, ap), bw = dot3(t.bw, ap);
    const float d = dot3(t.n, ap);
    if (bv >= 0.0f && bw >= 0.0f && bv + bw <= 1.0f) {
      const float d2 = d * d;
      if (d2 < best || (d2 == best && cand[q] < best_id)) {
        best = d2;
        best_id = cand[q];
      }
    } else {
      const float m = std::max(std::max(-bv * t.height[0], -bw * t.height[1]),
                               (bv + bw - 1.0f) * t.height[2]);
      bound[n_later] = d * d + m * m;
      later[n_later++] = q;
    }
  }
  for (int r = 0; r < n_later; ++r) {
    // Rounding of either value stays far below this margin (relative 1e-5, absolute 1e-3
    // voxels^2); NaN bounds (degenerate triangles) fail the test and are measured.
    if (bound[r] > best * 1.00001f + 1e-3f) continue;
    const std::int32_t id = cand[later[r]];
    const float d2 = point_triangle_distance2f(p, tris[std::size_t(id)]);
    if (d2 < best || (d2 == best && id < best_id)) {
      best = d2;
      best_id = id;
    }
  }
}

/// Width of the band meshToVolume computes for the wavefront's seeds, voxels: at most 2, where
/// OpenVDB stops at its voxelization (which reaches ~2 voxels) and does not widen the band.
constexpr float kSeedBandVoxels = 2.0f;

/// Makes every voxel inside the narrow band's surface an active voxel (the band's inactive
/// negative voxels and tiles), in leaf nodes.
void activate_interior(FloatTree& tree) {
  std::vector<std::pair<openvdb::CoordBBox, float>> tiles;
  FloatTree::ValueOffCIter it = tree.cbeginValueOff();
  it.setMaxDepth(FloatTree::ValueOffCIter::LEAF_DEPTH - 1);  // tiles only
  for (; it; ++it) {
    if (!(*it < 0.0f)) continue;
    openvdb::CoordBBox box;
    it.getBoundingBox(box);
    tiles.emplace_back(box, *it);
  }
  std::vector<FloatLeaf*> leaves;
  leaves.reserve(tree.leafCount());
  tree.getNodes(leaves);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, leaves.size(), 64),
                    [&](const tbb::blocked_range<std::size_t>& range) {
    for (std::size_t i = range.begin(); i < range.end(); ++i) {
      FloatLeaf& leaf = *leaves[i];
      const float* phi = leaf.buffer().data();
      for (auto off = leaf.getValueMask().beginOff(); off; ++off) {
        if (phi[off.pos()] < 0.0f) leaf.setValueOn(off.pos());
      }
    }
  });
  for (const auto& [box, value] : tiles) tree.fill(box, value, true);
  tree.voxelizeActiveTiles(true);
}

/// The leaves of a tree in its own order, with each leaf's 26 neighbours (index or -1).
struct LeafTable {
  std::vector<FloatLeaf*> leaves;
  /// Each leaf's values and origin, read without touching the leaf node (a cache miss each in
  /// the wavefront's scattered order; LeafBuffer::data() also checks for out-of-core data).
  std::vector<float*> values;
  std::vector<Coord> origins;
  /// neighbours[i][(sx * 3 + sy) * 3 + sz]: the leaf at origin + 8 * (sx - 1, sy - 1, sz - 1).
  std::vector<std::array<std::int32_t, 27>> neighbours;
};

LeafTable make_leaf_table(FloatTree& tree) {
  LeafTable t;
  t.leaves.reserve(tree.leafCount());
  tree.getNodes(t.leaves);
  // Leaf indices in a tree with one voxel per leaf (coordinates origin / 8).
  openvdb::Int32Tree index_of(-1);
  {
    openvdb::tree::ValueAccessor<openvdb::Int32Tree> acc(index_of);
    for (std::size_t i = 0; i < t.leaves.size(); ++i) {
      acc.setValue(t.leaves[i]->origin() >> 3, std::int32_t(i));
    }
  }
  t.neighbours.resize(t.leaves.size());
  t.values.resize(t.leaves.size());
  t.origins.resize(t.leaves.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, t.leaves.size(), 256),
                    [&](const tbb::blocked_range<std::size_t>& range) {
    openvdb::tree::ValueAccessor<const openvdb::Int32Tree> acc(index_of);
    for (std::size_t i = range.begin(); i < range.end(); ++i) {
      t.values[i] = t.leaves[i]->buffer().data();
      t.origins[i] = t.leaves[i]->origin();
      const Coord c = t.origins[i] >> 3;
      for (int s = 0; s < 27; ++s) {
        t.neighbours[i][s] = acc.getValue(c.offsetBy(s / 9 - 1, s / 3 % 3 - 1, s % 3 - 1));
      }
    }
  });
  return t;
}

/// An uninitialized array that asks the kernel for transparent huge pages (where enabled on
/// request, "madvise"): the wavefront reads it one leaf (2 KiB) at a time in scattered order, so
/// with 4 KiB pages nearly every read of a leaf is also a TLB miss.
template <typename T>
class HugeArray {
 public:
  explicit HugeArray(std::size_t n) {
    constexpr std::size_t kHuge = std::size_t(2) << 20;
    const std::size_t bytes = (n * sizeof(T) + kHuge - 1) / kHuge * kHuge;
    data_.reset(static_cast<T*>(std::aligned_alloc(kHuge, bytes)));
    if (!data_) throw std::bad_alloc();
#ifdef MADV_HUGEPAGE
    madvise(data_.get(), bytes, MADV_HUGEPAGE);
#endif
  }
  T* get() const { return data_.get(); }
  T& operator[](std::size_t i) const { return data_.get()[i]; }

 private:
  struct Free {
    void operator()(T* p) const { std::free(p); }
  };
  std::unique_ptr<T, Free> data_;
};

/// 512 bits, one per voxel of a leaf; word x holds the voxels (x, y, z) at bit 8 * y + z.
using LeafBits = std::array<std::uint64_t, 8>;

bool any_bit(const LeafBits& m) {
  std::uint64_t a = 0;
  for (std::uint64_t w : m) a |= w;
  return a != 0;
}

/// The bits of `masks` over a leaf and its one-voxel halo: halo[x + 1][y + 1] bit z + 1 is
/// voxel (x, y, z) of the leaf's frame, x, y, z in [-1, 8]. With `touched` (per leaf, its
/// mask's touched_neighbours()), neighbours with nothing in the slab facing the leaf are skipped.
void gather_halo_bits(const std::vector<LeafBits>& masks, const std::array<std::int32_t, 27>& nb,
                      std::uint16_t (&halo)[10][10], const std::uint32_t* touched = nullptr) {
  std::memset(halo, 0, sizeof(halo));
  for (int sx = 0; sx < 3; ++sx)
    for (int sy = 0; sy < 3; ++sy)
      for (int sz = 0; sz < 3; ++sz) {
        const int s = (sx * 3 + sy) * 3 + sz;
        const std::int32_t ni = nb[s];
        if (ni < 0) continue;
        // This leaf is at offset 26 - s from the neighbour.
        if (touched && !(touched[ni] >> (26 - s) & 1u)) continue;
        const LeafBits& m = masks[std::size_t(ni)];
        const int x0 = sx == 0 ? 7 : 0, x1 = sx == 1 ? 8 : x0 + 1;
        const int y0 = sy == 0 ? 7 : 0, y1 = sy == 1 ? 8 : y0 + 1;
        for (int x = x0; x < x1; ++x) {
          if (!m[x]) continue;
          const int hx = sx == 0 ? 0 : (sx == 1 ? x + 1 : 9);
          for (int y = y0; y < y1; ++y) {
            const unsigned row = unsigned(m[x] >> (8 * y)) & 0xffu;
            const int hy = sy == 0 ? 0 : (sy == 1 ? y + 1 : 9);
            halo[hx][hy] |= std::uint16_t(sz == 1 ? row << 1
                                                  : (sz == 0 ? (row >> 7) & 1u : (row & 1u) << 9));
          }
        }
      }
}

/// The triangles of the voxels in `known` over a leaf and a halo of kW voxels,
/// block[((x + kW) * kN + y + kW) * kN + z + kW] with kN = 8 + 2 kW; -1 elsewhere.
template <int kW>
void gather_ids_block(const std::vector<LeafBits>& known, const std::array<std::int32_t, 27>& nb,
                      const std::int32_t* ids, std::int32_t* block) {
  constexpr int kN = 8 + 2 * kW;
  for (int x = -kW; x < 8 + kW; ++x)
    for (int y = -kW; y < 8 + kW; ++y) {
      std::int32_t* row = block + ((x + kW) * kN + y + kW) * kN;
      for (int z = -kW; z < 8 + kW; ++z) {
        const std::int32_t ni = nb[(((x + 8) >> 3) * 3 + ((y + 8) >> 3)) * 3 + ((z + 8) >> 3)];
        const int pos = ((x & 7) << 6) | ((y & 7) << 3) | (z & 7);
        row[z + kW] = ni >= 0 && (known[std::size_t(ni)][pos >> 6] >> (pos & 63) & 1u)
                          ? ids[std::size_t(ni) * 512 + std::size_t(pos)]
                          : -1;
      }
    }
}

/// Bit (sx * 3 + sy) * 3 + sz is set when `m` has a voxel in the halo of the leaf at offset
/// 8 * (sx - 1, sy - 1, sz - 1): the one-voxel slab (edge, corner) of the leaf facing it.
std::uint32_t touched_neighbours(const LeafBits& m) {
  std::uint64_t any = 0;
  for (std::uint64_t w : m) any |= w;
  if (!any) return 0;
  const std::uint64_t xs[3] = {m[0], any, m[7]};
  constexpr std::uint64_t ys[3] = {0xffull, ~0ull, 0xffull << 56};
  constexpr std::uint64_t zs[3] = {0x0101010101010101ull, ~0ull, 0x8080808080808080ull};
  std::uint32_t out = 0;
  for (int s = 0; s < 27; ++s) {
    if (xs[s / 9] & ys[s / 3 % 3] & zs[s % 3]) out |= std::uint32_t(1) << s;
  }
  return out;
}

/// A map of triangles to small numbers (one per thread) that clears in O(1): triangle i maps to
/// slot[i] when stamp[i] == now.
struct TriangleSlots {
  explicit TriangleSlots(std::size_t n_triangles) : stamp(n_triangles, 0u), slot(n_triangles, 0u) {}
  std::vector<std::uint32_t> stamp;
  std::vector<std::uint32_t> slot;
  std::uint32_t now = 0;
  void clear() {
    if (++now == 0) {
      std::fill(stamp.begin(), stamp.end(), 0u);
      now = 1;
    }
  }
  bool has(std::int32_t id) const { return stamp[std::size_t(id)] == now; }
  /// The bit of triangle `id`, appended to distinct[0, n_distinct) with the next slot if new;
  /// 0 when it is new and all 64 slots are taken.
  std::uint64_t bit(std::int32_t id, std::int32_t (&distinct)[64], int& n_distinct) {
    const std::size_t t = std::size_t(id);
    if (stamp[t] != now) {
      if (n_distinct == 64) return 0;
      stamp[t] = now;
      slot[t] = std::uint32_t(n_distinct);
      distinct[n_distinct++] = id;
    }
    return std::uint64_t(1) << slot[t];
  }
};

/// `masks` dilated by one voxel (26-neighbourhood), for every leaf.
std::vector<LeafBits> dilate_bits(const LeafTable& table, const std::vector<LeafBits>& masks) {
  std::vector<LeafBits> out(masks.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, masks.size(), 64),
                    [&](const tbb::blocked_range<std::size_t>& range) {
    for (std::size_t li = range.begin(); li < range.end(); ++li) {
      std::uint16_t halo[10][10];
      gather_halo_bits(masks, table.neighbours[li], halo);
      std::uint16_t grown[10][10];
      for (int x = 0; x < 10; ++x)
        for (int y = 0; y < 10; ++y) {
          const unsigned v = halo[x][y];
          grown[x][y] = std::uint16_t(v | (v << 1) | (v >> 1));
        }
      for (int x = 0; x < 8; ++x)
        for (int y = 0; y < 8; ++y) {
          unsigned near = 0;
          for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b) near |= grown[x + a][y + b];
          out[li][x] |= std::uint64_t((near >> 1) & 0xffu) << (8 * y);
        }
    }
  });
  return out;
}

/// Where the closest triangles of neighbouring voxels face directions this far apart (cosine of
/// the angle between their normals), the voxel lies on or next to the medial surface of a
/// rounded part (the centre of a sphere, the axis of a cylinder): closest-triangle cells there
/// are thinner than a voxel and its neighbours may not know its closest triangle.
constexpr float kMedialNormalCos = -0.25f;

/// Refinement after the wavefront; reads triangles, writes only each voxel's own phi (|phi| only
/// decreases; signs and triangles are kept): deterministic.
///  1. The band's voxels (`seeds`) whose 26 neighbours' triangles face away from their own join
///     `medial` (the wavefront marked only the voxels it filled). Their distances are OpenVDB's
///     voxelization's: measuring the neighbours' triangles there changes 8 voxels of fertility at
///     256^3 by more than 0.1 voxel (at most 0.13), none of fandisk's at 512^3.
///  2. The voxels within 2 of `medial` ones (the flux stencil) measure the triangles of their
///     5^3 neighbourhood: there, closest-triangle cells are thinner than a voxel and the
///     wavefront may have missed a voxel's closest triangle by a few hundredths of a voxel, which
///     shows in the flux (the centre of a sphere). Per leaf, the block's triangles become bits
///     of a word (up to 64 distinct ones; else per octant of the leaf, else one voxel at a time)
///     and a voxel's neighbourhood is the union of 5 x 5 x 5 words, taken along z, then y, then
///     x: fandisk 512^3 measures 689k voxels in 3,685 leaves, 0.20 s -> 0.12 s on 2 threads,
///     fertility x16 0.33 s -> 0.29 s, same grids byte for byte.
void refine_by_neighbour_triangles(const LeafTable& table, const std::vector<LeafBits>& known,
                                   const std::vector<LeafBits>& seeds,
                                   std::vector<LeafBits> medial, const std::int32_t* ids,
                                   const std::vector<TriangleF>& tris, float h) {
  const std::size_t n_leaves = table.leaves.size();
  // Neighbour offsets in the blocks of halo 1 (10^3) and 2 (12^3).
  std::vector<int> off1, off2;
  for (int x = -2; x <= 2; ++x)
    for (int y = -2; y <= 2; ++y)
      for (int z = -2; z <= 2; ++z) {
        if (x == 0 && y == 0 && z == 0) continue;
        if (std::abs(x) <= 1 && std::abs(y) <= 1 && std::abs(z) <= 1) {
          off1.push_back((x * 10 + y) * 10 + z);
        }
        off2.push_back((x * 12 + y) * 12 + z);
      }
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n_leaves, 16),
                    [&](const tbb::blocked_range<std::size_t>& range) {
    std::int32_t block[1000];
    for (std::size_t li = range.begin(); li < range.end(); ++li) {
      if (!any_bit(seeds[li])) continue;
      gather_ids_block<1>(known, table.neighbours[li], ids, block);
      for (int x = 0; x < 8; ++x)
        for (std::uint64_t bits = seeds[li][x]; bits; bits &= bits - 1) {
          const int b = __builtin_ctzll(bits), y = b >> 3, z = b & 7;
          const int c = ((x + 1) * 10 + y + 1) * 10 + z + 1;
          const std::int32_t own = block[c];
          for (int k : off1) {
            const std::int32_t id = block[c + k];
            if (id >= 0 && id != own &&
                dot3(tris[std::size_t(own)].n, tris[std::size_t(id)].n) <
                    kMedialNormalCos) {
              medial[li][x] |= std::uint64_t(1) << b;
              break;
            }
          }
        }
    }
  });
  tbb::enumerable_thread_specific<TriangleSlots> slots(TriangleSlots(tris.size()));
  // Lowers phi at voxel (x, y, z) of a leaf to its distance to triangles cand[0, nc).
  auto lower = [&](FloatLeaf& leaf, int x, int y, int z, const std::int32_t* cand, int nc) {
    if (nc == 0) return;
    float* phi = leaf.buffer().data();
    const int pos = (x << 6) | (y << 3) | z;
    const Coord origin = leaf.origin();
    const float p[3] = {float(origin[0] + x), float(origin[1] + y), float(origin[2] + z)};
    float best = (phi[pos] / h) * (phi[pos] / h);
    std::int32_t best_id = -1;
    lower_to_closest(p, cand, nc, tris, best, best_id);
    const float d = std::sqrt(best) * h;
    if (d < std::abs(phi[pos])) phi[pos] = phi[pos] < 0.0f ? -d : d;
  };
  const std::vector<LeafBits> wide = dilate_bits(table, dilate_bits(table, medial));
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n_leaves, 16),
                    [&](const tbb::blocked_range<std::size_t>& range) {
    constexpr int kN = 12;  // block side: the leaf and a halo of 2
    std::vector<std::int32_t> block(kN * kN * kN);
    // Per block voxel of a window, the bit of its triangle among the window's distinct ones;
    // their unions over 5 neighbours along z, then over 5 x 5 in y and z.
    std::vector<std::uint64_t> bit(kN * kN * kN), along_z(kN * kN * 8), along_yz(kN * 8 * 8);
    std::int32_t distinct[64];
    std::int32_t cand[124];
    TriangleSlots& map = slots.local();
    // Lowers the voxels `todo` of the leaf's cube [o, o + n)^3 (n = 8 or 4) by the triangles of
    // their 5^3 neighbourhoods, taken as unions of bit words; false (nothing done) when the
    // cube's window [o - 2, o + n + 2)^3 holds more than 64 distinct triangles.
    auto by_words = [&](FloatLeaf& leaf, const LeafBits& todo, int ox, int oy, int oz, int n) {
      const int w = n + 4;  // window side
      map.clear();
      int n_distinct = 0;
      for (int x = 0; x < w; ++x)
        for (int y = 0; y < w; ++y) {
          const std::int32_t* src = &block[std::size_t(((ox + x) * kN + oy + y) * kN + oz)];
          std::uint64_t* dst = &bit[std::size_t((x * w + y) * w)];
          std::int32_t previous = -1;
          std::uint64_t previous_bit = 0;
          for (int z = 0; z < w; ++z) {
            const std::int32_t id = src[z];
            if (id != previous && id >= 0) {
              previous = id;
              previous_bit = map.bit(id, distinct, n_distinct);
              if (!previous_bit) return false;
            }
            dst[z] = id >= 0 ? previous_bit : 0;
          }
        }
      for (int x = 0; x < w; ++x)
        for (int y = 0; y < w; ++y)
          for (int z = 0; z < n; ++z) {
            const std::uint64_t* row = &bit[std::size_t((x * w + y) * w + z)];
            along_z[std::size_t((x * w + y) * n + z)] = row[0] | row[1] | row[2] | row[3] | row[4];
          }
      for (int x = 0; x < w; ++x)
        for (int y = 0; y < n; ++y)
          for (int z = 0; z < n; ++z) {
            const std::uint64_t* col = &along_z[std::size_t((x * w + y) * n + z)];
            along_yz[std::size_t((x * n + y) * n + z)] =
                col[0] | col[n] | col[2 * n] | col[3 * n] | col[4 * n];
          }
      const std::uint64_t z_mask = ((std::uint64_t(1) << n) - 1) << oz;
      for (int x = 0; x < n; ++x)
        for (int y = 0; y < n; ++y) {
          for (std::uint64_t bits = (todo[ox + x] >> (8 * (oy + y))) & z_mask; bits;
               bits &= bits - 1) {
            const int z = __builtin_ctzll(bits) - oz;
            const std::uint64_t* sheet = &along_yz[std::size_t((x * n + y) * n + z)];
            const int nn = n * n;
            std::uint64_t around =
                sheet[0] | sheet[nn] | sheet[2 * nn] | sheet[3 * nn] | sheet[4 * nn];
            around &= ~bit[std::size_t(((x + 2) * w + y + 2) * w + z + 2)];
            int nc = 0;
            for (; around; around &= around - 1) cand[nc++] = distinct[__builtin_ctzll(around)];
            lower(leaf, ox + x, oy + y, oz + z, cand, nc);
          }
        }
      return true;
    };
    for (std::size_t li = range.begin(); li < range.end(); ++li) {
      LeafBits todo = wide[li];
      for (int x = 0; x < 8; ++x) todo[x] &= known[li][x];
      if (!any_bit(todo)) continue;
      FloatLeaf& leaf = *table.leaves[li];
      gather_ids_block<2>(known, table.neighbours[li], ids, block.data());
      if (by_words(leaf, todo, 0, 0, 0, 8)) continue;
      // Many small triangles: the leaf's octants, else voxel by voxel.
      for (int octant = 0; octant < 8; ++octant) {
        const int ox = 4 * (octant >> 2), oy = 4 * (octant >> 1 & 1), oz = 4 * (octant & 1);
        if (by_words(leaf, todo, ox, oy, oz, 4)) continue;
        for (int x = ox; x < ox + 4; ++x)
          for (std::uint64_t bits = todo[x] & (std::uint64_t(0x0f0f0f0f) << (8 * oy + oz));
               bits; bits &= bits - 1) {
            const int b = __builtin_ctzll(bits), y = b >> 3, z = b & 7;
            const int c = ((x + 2) * kN + y + 2) * kN + z + 2;
            const std::int32_t own = block[std::size_t(c)];
            map.clear();
            int nc = 0;
            for (int k : off2) {
              const std::int32_t id = block[std::size_t(c + k)];
              if (id < 0 || id == own || map.stamp[std::size_t(id)] == map.now) continue;
              map.stamp[std::size_t(id)] = map.now;
              cand[nc++] = id;
            }
            lower(leaf, x, y, z, cand, nc);
          }
      }
    }
  });
}

/// Upper bound of the interior depth of a level set, voxels: half the smallest side of the
/// active bounding box, plus a margin.
int interior_depth_bound(const FloatGrid& grid) {
  const openvdb::CoordBBox b = grid.evalActiveVoxelBoundingBox();
  const openvdb::Coord d = b.dim();
  return std::min({d[0], d[1], d[2]}) / 2 + 2;
}

/// Fills the interior of `sdf` (a narrow band from meshToVolume with its polygon index grid) with
/// distances to the closest triangles, as described above. `band_in_voxels` is the band's
/// interior width, voxels.
void fill_by_wavefront(FloatGrid& sdf, const openvdb::Int32Grid& index_grid, const IndexMesh& m,
                       float exterior_voxels, const StageMonitor& monitor) {
  const std::vector<TriangleF> tris = float_triangles(m);
  const std::int32_t n_tris = std::int32_t(tris.size());
  const float h = float(sdf.voxelSize()[0]);
  const float seed_band = kSeedBandVoxels * h;
  // Every voxel within `exterior_voxels` (< 8) of the surface is in a seed's leaf or one of its
  // 26 neighbours: the front fills those leaves' outside voxels too and stops at that width.
  {
    std::vector<Coord> origins;
    origins.reserve(sdf.tree().leafCount());
    for (auto it = sdf.tree().cbeginLeaf(); it; ++it) origins.push_back(it->origin());
    openvdb::tree::ValueAccessor<FloatTree> acc(sdf.tree());
    for (const Coord& o : origins) {
      for (int s = 0; s < 27; ++s) {
        acc.touchLeaf(o.offsetBy(8 * (s / 9 - 1), 8 * (s / 3 % 3 - 1), 8 * (s % 3 - 1)));
      }
    }
  }
  activate_interior(sdf.tree());
  const LeafTable table = make_leaf_table(sdf.tree());
  const std::size_t n = table.leaves.size();

  // Per leaf: the closest triangle of each voxel (valid where accepted or tentative); bit masks
  // of the voxels still to fill, of the tentative ones and of those accepted last iteration.
  HugeArray<std::int32_t> ids(n * 512);
  std::vector<LeafBits> known(n), todo(n), tentative(n), medial(n), outside(n);
  std::array<std::vector<LeafBits>, 2> fresh = {std::vector<LeafBits>(n),
                                                std::vector<LeafBits>(n)};
  // Per leaf, touched_neighbours() of its `fresh` mask.
  std::array<std::vector<std::uint32_t>, 2> fresh_touched = {std::vector<std::uint32_t>(n),
                                                             std::vector<std::uint32_t>(n)};
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 64),
                    [&](const tbb::blocked_range<std::size_t>& range) {
    openvdb::Int32Grid::ConstAccessor acc = index_grid.getConstAccessor();
    for (std::size_t i = range.begin(); i < range.end(); ++i) {
      const FloatLeaf& leaf = *table.leaves[i];
      const openvdb::Int32Tree::LeafNodeType* il = acc.probeConstLeaf(leaf.origin());
      // Every voxel not a seed is to fill: inside, all are active; outside, any may be.
      LeafBits dn{}, td{}, out{};
      for (int w = 0; w < 8; ++w) {
        if (il) dn[w] = il->getValueMask().getWord<std::uint64_t>(w);
      }
      const float* phi = leaf.buffer().data();
      const std::int32_t* src = il ? il->buffer().data() : nullptr;
      std::int32_t* dst = &ids[i * 512];
      for (int w = 0; w < 8; ++w) {
        for (std::uint64_t bits = dn[w]; bits; bits &= bits - 1) {
          const int pos = 64 * w + __builtin_ctzll(bits);
          // The index grid keeps the voxels meshToVolume trimmed from the band (and set to
          // +-its width): not seeds.
          if (src[pos] >= 0 && src[pos] < n_tris && std::abs(phi[pos]) < seed_band) {
            dst[pos] = src[pos];
          } else {
            dn[w] &= ~(std::uint64_t(1) << (pos & 63));
          }
        }
        td[w] = ~dn[w];
        for (std::uint64_t bits = td[w]; bits; bits &= bits - 1) {
          const int pos = 64 * w + __builtin_ctzll(bits);
          if (!(phi[pos] < 0.0f)) out[w] |= std::uint64_t(1) << (pos & 63);
        }
      }
      todo[i] = td;
      outside[i] = out;
      fresh[0][i] = dn;
      fresh_touched[0][i] = touched_neighbours(dn);
      known[i] = dn;
    }
  });

  // Offsets in a 10^3 block of the 27 voxels around one, indexed (a * 3 + b) * 3 + c for the
  // offset (a - 1, b - 1, c - 1); candidates are listed in this order.
  int off27[27];
  for (int i = 0; i < 27; ++i) off27[i] = ((i / 9 - 1) * 10 + (i / 3 % 3 - 1)) * 10 + i % 3 - 1;
  const std::vector<LeafBits> seeds = known;
  std::vector<std::int32_t> active, previous;
  for (std::size_t i = 0; i < n; ++i) {
    if (any_bit(todo[i])) active.push_back(std::int32_t(i));
  }
  std::unique_ptr<std::atomic<std::uint8_t>[]> next_mark(new std::atomic<std::uint8_t>[n]);
  for (std::size_t i = 0; i < n; ++i) next_mark[i].store(0, std::memory_order_relaxed);
  float limit = kSeedBandVoxels + 1.0f;  // voxels; accepted distances grow by one per iteration
  tbb::enumerable_thread_specific<TriangleSlots> slots(TriangleSlots(tris.size()));
  // Progress: one iteration per voxel of depth, at most interior_depth_bound() of them.
  const double depth_bound = interior_depth_bound(sdf);
  for (int iteration = 0; !active.empty(); ++iteration, limit += 1.0f) {
    monitor.report(0.25 + 0.5 * std::min(1.0, iteration / depth_bound));
    const std::vector<LeafBits>& fresh_in = fresh[iteration & 1];
    std::vector<LeafBits>& fresh_out = fresh[(iteration + 1) & 1];
    const std::vector<std::uint32_t>& touched_in = fresh_touched[iteration & 1];
    std::vector<std::uint32_t>& touched_out = fresh_touched[(iteration + 1) & 1];
    const float limit2 = limit * limit;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, active.size(), 4),
                      [&](const tbb::blocked_range<std::size_t>& range) {
      monitor.check();
      std::int32_t block[1000];
      std::uint64_t words[1000];
      std::int32_t distinct[64];
      TriangleSlots& map = slots.local();
      for (std::size_t j = range.begin(); j < range.end(); ++j) {
        const std::size_t li = std::size_t(active[j]);
        // The leaves of an iteration are far apart in memory and their triangles and distances
        // were written iterations ago: fetching them a few leaves ahead hides most misses.
        if (j + 3 < range.end()) {
          const std::size_t lp = std::size_t(active[j + 3]);
          const char* a = reinterpret_cast<const char*>(&ids[lp * 512]);
          const char* b = reinterpret_cast<const char*>(table.values[lp]);
          for (int k = 0; k < 2048; k += 64) {
            __builtin_prefetch(a + k);
            __builtin_prefetch(b + k);
          }
          // And the triangles of the face neighbours' fresh voxels facing it.
          constexpr int kFace[6] = {4, 22, 10, 16, 12, 14};  // -x, +x, -y, +y, -z, +z
          const std::array<std::int32_t, 27>& nbp = table.neighbours[lp];
          for (int f = 0; f < 6; ++f) {
            const int s = kFace[f];
            const std::int32_t ni = nbp[s];
            if (ni < 0 || !(touched_in[std::size_t(ni)] >> (26 - s) & 1u)) continue;
            const std::int32_t* base = &ids[std::size_t(ni) * 512];
            if (f < 2) {  // the neighbour's plane x = 7 or 0: 64 consecutive
              const std::int32_t* plane = base + (f == 0 ? 7 * 64 : 0);
              for (int k = 0; k < 64; k += 16) __builtin_prefetch(plane + k);
            } else if (f < 4) {  // rows y = 7 or 0: 8 of 8
              for (int x = 0; x < 8; ++x) __builtin_prefetch(base + x * 64 + (f == 2 ? 56 : 0));
            } else {  // columns z = 7 or 0: every 8th
              for (int k = 0; k < 512; k += 16) __builtin_prefetch(base + k);
            }
          }
        }
        const std::array<std::int32_t, 27>& nb = table.neighbours[li];
        std::uint16_t halo[10][10];
        gather_halo_bits(fresh_in, nb, halo, touched_in.data());
        float* phi = table.values[li];
        std::int32_t* own = &ids[li * 512];
        LeafBits& tn = tentative[li];
        const Coord& origin = table.origins[li];
        bool any_fresh = false;
        for (int x = 0; x < 10; ++x)
          for (int y = 0; y < 10; ++y) any_fresh |= halo[x][y] != 0;
        // Without fresh voxels around, the leaf only accepts its pending tentative voxels.
        if (any_fresh) {
          // Triangles of the voxels accepted last iteration, over the leaf and its halo; only
          // read where `halo` has a bit. With at most 64 distinct ones, each also becomes a bit
          // (`words`): a voxel's candidates are then the union of its fresh neighbours' bits,
          // distinct by construction (fandisk 512^3: 5-8 distinct in most leaves).
          map.clear();
          int n_distinct = 0;
          bool by_words = true;
          for (int hx = 0; hx < 10; ++hx)
            for (int hy = 0; hy < 10; ++hy)
              for (unsigned row = halo[hx][hy]; row; row &= row - 1) {
                const int hz = __builtin_ctz(row);
                const int x = hx - 1, y = hy - 1, z = hz - 1;
                const std::int32_t ni =
                    nb[(((x + 8) >> 3) * 3 + ((y + 8) >> 3)) * 3 + ((z + 8) >> 3)];
                const std::int32_t id = ids[std::size_t(ni) * 512 +
                                            std::size_t(((x & 7) << 6) | ((y & 7) << 3) | (z & 7))];
                const int c = (hx * 10 + hy) * 10 + hz;
                block[c] = id;
                if (!by_words) continue;
                words[c] = map.bit(id, distinct, n_distinct);
                by_words = words[c] != 0;  // else too many: voxel by voxel
              }
          for (int x = 0; x < 8; ++x)
            for (int y = 0; y < 8; ++y) {
              const unsigned todo_row = unsigned(todo[li][x] >> (8 * y)) & 0xffu;
              if (!todo_row) continue;
              unsigned rows[9];
              unsigned near = 0;
              for (int a = 0; a < 3; ++a)
                for (int b = 0; b < 3; ++b) {
                  rows[a * 3 + b] = halo[x + a][y + b];
                  near |= rows[a * 3 + b];
                }
              near |= (near << 1) | (near >> 1);
              unsigned front = (near >> 1) & todo_row;
              for (; front; front &= front - 1) {
                const int z = __builtin_ctz(front);
                const int pos = (x << 6) | (y << 3) | z;
                const std::uint64_t bit = std::uint64_t(1) << ((y << 3) | z);
                const bool has = (tn[x] & bit) != 0;
                std::int32_t best_id = has ? own[pos] : -1;
                float best = has ? (phi[pos] / h) * (phi[pos] / h)
                                 : std::numeric_limits<float>::max();
                // The fresh neighbours, bit (a * 3 + b) * 3 + c for offset (a-1, b-1, c-1); the
                // voxel itself is never fresh (it is still to fill).
                std::uint32_t around = 0;
                for (int r = 0; r < 9; ++r) around |= ((rows[r] >> z) & 7u) << (3 * r);
                std::int32_t cand[26];
                int nc = 0;
                const int c = ((x + 1) * 10 + y + 1) * 10 + z + 1;
                // The triangle of the first fresh neighbour (offset order).
                const std::int32_t first = block[c + off27[__builtin_ctz(around)]];
                if (by_words) {
                  std::uint64_t word = 0;
                  for (; around; around &= around - 1) {
                    word |= words[c + off27[__builtin_ctz(around)]];
                  }
                  if (has && map.has(best_id)) {
                    word &= ~(std::uint64_t(1) << map.slot[std::size_t(best_id)]);
                  }
                  for (; word; word &= word - 1) cand[nc++] = distinct[__builtin_ctzll(word)];
                } else {
                  for (; around; around &= around - 1) {
                    const std::int32_t id = block[c + off27[__builtin_ctz(around)]];
                    if (id == best_id) continue;
                    bool seen = false;
                    for (int q = 0; q < nc; ++q) seen |= cand[q] == id;
                    if (!seen) cand[nc++] = id;
                  }
                }
                if (nc == 0) continue;
                const float p[3] = {float(origin[0] + x), float(origin[1] + y),
                                    float(origin[2] + z)};
                const bool out = (outside[li][x] & bit) != 0;
                // Candidates facing apart: wavefronts from different sides meet here (inside:
                // the medial surface, where the flux lives).
                // (Without a tentative triangle, `first` is a candidate itself: one is not
                // enough.)
                const float* n0 = tris[std::size_t(has ? best_id : first)].n;
                for (int q = 0; q < nc && !out && (has || nc > 1); ++q) {
                  if (dot3(n0, tris[std::size_t(cand[q])].n) < kMedialNormalCos) {
                    medial[li][x] |= bit;
                  }
                }
                lower_to_closest(p, cand, nc, tris, best, best_id);
                own[pos] = best_id;
                phi[pos] = out ? std::sqrt(best) * h : -std::sqrt(best) * h;
                tn[x] |= bit;
              }
            }
        }
        // Accept the tentative voxels below the limit; those outside the exterior band are
        // final too, but dropped: they never become fresh, so the front stops there.
        LeafBits accepted{};
        bool pending = false;
        for (int x = 0; x < 8; ++x) {
          std::uint64_t dropped = 0;
          for (std::uint64_t bits = tn[x]; bits; bits &= bits - 1) {
            const int b = __builtin_ctzll(bits);
            const float d = phi[(x << 6) | b] / h;
            if (d * d < limit2) {
              (d >= exterior_voxels ? dropped : accepted[x]) |= std::uint64_t(1) << b;
            } else {
              pending = true;
            }
          }
          tn[x] &= ~(accepted[x] | dropped);
          todo[li][x] &= ~(accepted[x] | dropped);
          known[li][x] |= accepted[x];
        }
        fresh_out[li] = accepted;
        touched_out[li] = touched_neighbours(accepted);
        if (pending) next_mark[li].store(1, std::memory_order_relaxed);
        // Wake the neighbours whose halo holds a voxel accepted here (the leaf itself included).
        for (std::uint32_t t = touched_out[li]; t; t &= t - 1) {
          const std::int32_t ni = nb[std::size_t(__builtin_ctz(t))];
          if (ni >= 0) next_mark[std::size_t(ni)].store(1, std::memory_order_relaxed);
        }
      }
    });
    // Clear what the previous iteration (or the seeding) wrote into fresh_in, so that fresh_out
    // is all zero but for this iteration's leaves; then list the next leaves in index order.
    if (iteration == 0) {
      std::fill(fresh[0].begin(), fresh[0].end(), LeafBits{});
      std::fill(fresh_touched[0].begin(), fresh_touched[0].end(), 0u);
    } else {
      for (std::int32_t li : previous) {
        fresh[iteration & 1][std::size_t(li)] = LeafBits{};
        fresh_touched[iteration & 1][std::size_t(li)] = 0u;
      }
    }
    previous.swap(active);
    active.clear();
    for (std::size_t i = 0; i < n; ++i) {
      if (next_mark[i].load(std::memory_order_relaxed)) {
        next_mark[i].store(0, std::memory_order_relaxed);
        if (any_bit(todo[i])) active.push_back(std::int32_t(i));
      }
    }
  }
  refine_by_neighbour_triangles(table, known, seeds, std::move(medial), ids.get(), tris, h);
  // Outside, only the exterior band stays active (the voxels the front accepted below its width);
  // then the background becomes that width.
  const float exterior = exterior_voxels * h;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 64),
                    [&](const tbb::blocked_range<std::size_t>& range) {
    for (std::size_t i = range.begin(); i < range.end(); ++i) {
      // Without outside voxels to fill, a leaf holds seeds (|phi| below the seed band) and
      // inside voxels (negative): nothing to do.
      if (!any_bit(outside[i])) continue;
      FloatLeaf& leaf = *table.leaves[i];
      float* phi = table.values[i];
      for (int pos = 0; pos < 512; ++pos) {
        const bool filled = outside[i][pos >> 6] >> (pos & 63) & 1u;
        if (!(phi[pos] < exterior) || (filled && !(known[i][pos >> 6] >> (pos & 63) & 1u))) {
          phi[pos] = exterior;
          leaf.setValueOff(pos);
        } else if (filled) {
          leaf.setValueOn(pos);
        }
      }
    }
  });
  openvdb::tools::changeLevelSetBackground(sdf.tree(), exterior);
  openvdb::tools::pruneLevelSet(sdf.tree());
}

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

// ---------------------------------------------------------------------------------------------
// Gradient and flux: one pass over the SDF's leaves with a padded dense block per leaf.

namespace {

constexpr int kLeafDim = int(FloatLeaf::DIM);  // 8
constexpr int kPad = 2;                        // flux needs gradients at +-1, i.e. phi at +-2
constexpr int kBlock = kLeafDim + 2 * kPad;    // 12

/// Copies phi over [origin - 2, origin + 9]^3 into `block` (x-major), reading leaf buffers
/// directly and tile values where there is no leaf.
void gather_block(FloatGrid::ConstAccessor& acc, const Coord& origin, float* block) {
  for (int nx = -1; nx <= 1; ++nx)
    for (int ny = -1; ny <= 1; ++ny)
      for (int nz = -1; nz <= 1; ++nz) {
        const Coord nb_origin = origin.offsetBy(nx * kLeafDim, ny * kLeafDim, nz * kLeafDim);
        const FloatLeaf* leaf = acc.probeConstLeaf(nb_origin);
        const float tile = leaf ? 0.0f : acc.getValue(nb_origin);
        const float* data = leaf ? leaf->buffer().data() : nullptr;
        // Block index ranges covered by this neighbour along each axis.
        auto lo = [](int n) { return n < 0 ? 0 : (n == 0 ? kPad : kPad + kLeafDim); };
        auto hi = [](int n) { return n < 0 ? kPad : (n == 0 ? kPad + kLeafDim : kBlock); };
        for (int bx = lo(nx); bx < hi(nx); ++bx)
          for (int by = lo(ny); by < hi(ny); ++by) {
            float* row = block + (bx * kBlock + by) * kBlock;
            const int lxy =
                (((bx - kPad) & (kLeafDim - 1)) << 6) | (((by - kPad) & (kLeafDim - 1)) << 3);
            for (int bz = lo(nz); bz < hi(nz); ++bz) {
              row[bz] = data ? data[lxy | ((bz - kPad) & (kLeafDim - 1))] : tile;
            }
          }
      }
}

/// Average outward flux (eq. 7 / 26, index units: multiply by 1 / h) of the central-difference
/// gradient of `phi` (a 12^3 block, leaf at 2..9) at the 512 voxels of the leaf, into flux[512]
/// (x-major). The 26 terms g(c + d) . d / |d| are regrouped per axis: for x,
/// sum over (dy, dz) of (g_x(c + (1, dy, dz)) - g_x(c - (1, dy, dz))) / sqrt(1 + dy^2 + dz^2),
/// so the loops over z vectorise.
struct FluxScratch {
  float diff[3][10][10][10];
};

void flux_of_block(const float* phi, float* flux, FluxScratch& scratch) {
  constexpr int B = kBlock;
  auto& diff = scratch.diff;
  // diff[a][x + 1][y + 1][z + 1]: g_a at +1 minus g_a at -1 along axis a, where
  // g_a = (phi(+e_a) - phi(-e_a)) / 2, i.e. (phi(+2 e_a) + phi(-2 e_a)) / 2 - phi; needed with
  // the a-coordinate in [0, 7] and the other two in [-1, 8].
  for (int a = 0; a < 3; ++a) {
    const int s2 = a == 0 ? 2 * B * B : (a == 1 ? 2 * B : 2);
    for (int x = a == 0 ? 1 : 0; x < (a == 0 ? 9 : 10); ++x)
      for (int y = a == 1 ? 1 : 0; y < (a == 1 ? 9 : 10); ++y) {
        const float* c = phi + ((x + 1) * B + y + 1) * B + 1;
        float* out = diff[a][x][y];
        const int z0 = a == 2 ? 1 : 0, z1 = a == 2 ? 9 : 10;
        for (int z = z0; z < z1; ++z) out[z] = 0.5f * (c[z + s2] + c[z - s2]) - c[z];
      }
  }
  const float w1 = 1.0f, w2 = float(1.0 / std::sqrt(2.0)), w3 = float(1.0 / std::sqrt(3.0));
  const float w[3][3] = {{w3, w2, w3}, {w2, w1, w2}, {w3, w2, w3}};
  for (int x = 0; x < 8; ++x)
    for (int y = 0; y < 8; ++y) {
      float acc[8] = {0, 0, 0, 0, 0, 0, 0, 0};
      for (int u = 0; u < 3; ++u)
        for (int v = 0; v < 3; ++v) {
          const float wt = w[u][v];
          // x: offsets (dy, dz) = (u - 1, v - 1); y: (dx, dz); z: (dx, dy).
          const float* fx = &diff[0][x + 1][y + u][v];
          const float* fy = &diff[1][x + u][y + 1][v];
          const float* fz = &diff[2][x + u][y + v][1];
          for (int z = 0; z < 8; ++z) acc[z] += wt * (fx[z] + fy[z] + fz[z]);
        }
      for (int z = 0; z < 8; ++z) flux[(x << 6) | (y << 3) | z] = acc[z];
    }
}

struct DerivedLeaves {
  std::vector<FloatLeaf*> flux;  ///< one slot per SDF leaf, null when nothing is stored
  std::vector<Vec3SLeaf*> gradient;
  std::vector<std::size_t> interior;  ///< interior voxel count per SDF leaf
};

/// Builds the flux grid (and the gradient grid) of `sdf`.
void derive_fields(const FloatGrid& sdf, const GradientMap& gmap, double flux_min,
                   bool store_gradient, FloatGrid::Ptr& flux_out, Vec3SGrid::Ptr& gradient_out,
                   std::size_t& interior_voxels, double& seconds_flux, double& seconds_gradient,
                   const StageMonitor& monitor) {
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<const FloatLeaf*> leaves;
  leaves.reserve(sdf.tree().leafCount());
  sdf.tree().getNodes(leaves);
  DerivedLeaves out;
  out.flux.assign(leaves.size(), nullptr);
  out.interior.assign(leaves.size(), 0);
  if (store_gradient) out.gradient.assign(leaves.size(), nullptr);

  const double h = gmap.voxel_size;
  const float phi_limit = float(kFluxPhiLimitVoxels * h);
  const float inv_26h = float(1.0 / (26.0 * h));
  const float fmin = float(flux_min);

  monitor.begin_part(0.75, 1.0, leaves.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, leaves.size(), 16),
                    [&](const tbb::blocked_range<std::size_t>& range) {
    monitor.advance(range.size());
    FloatGrid::ConstAccessor acc = sdf.getConstAccessor();
    std::vector<float> phi(kBlock * kBlock * kBlock);
    float flux[512];
    auto scratch = std::make_unique<FluxScratch>();
    for (std::size_t li = range.begin(); li < range.end(); ++li) {
      const FloatLeaf& leaf = *leaves[li];
      const Coord origin = leaf.origin();
      const float* own = leaf.buffer().data();
      // Bit loops over the mask's words: the interior is dense, and OpenVDB's mask iterators
      // cost more than the flux itself there.
      std::uint64_t on[8];
      for (int w = 0; w < 8; ++w) on[w] = leaf.getValueMask().getWord<std::uint64_t>(w);
      std::size_t interior = 0;
      bool any_near = false;  // an active voxel with phi < phi_limit
      for (int pos = 0; pos < 512; ++pos) {
        const bool active = (on[pos >> 6] >> (pos & 63)) & 1u;
        interior += active && own[pos] < 0.0f;
        any_near |= active && own[pos] < phi_limit;
      }
      FloatLeaf* flux_leaf = nullptr;
      if (any_near || store_gradient) gather_block(acc, origin, phi.data());
      auto p_at = [&](int x, int y, int z) { return phi[(x * kBlock + y) * kBlock + z]; };
      if (any_near) {
        flux_of_block(phi.data(), flux, *scratch);
        for (int w = 0; w < 8; ++w)
          for (std::uint64_t bits = on[w]; bits; bits &= bits - 1) {
            const openvdb::Index pos = openvdb::Index(64 * w + __builtin_ctzll(bits));
            if (!(own[pos] < phi_limit)) continue;
            const float f = std::clamp(flux[pos] * inv_26h, -1.0f, 1.0f);
            if (std::abs(f) < fmin) continue;
            if (!flux_leaf) flux_leaf = new FloatLeaf(origin, 0.0f, false);
            flux_leaf->setValueOn(pos, f);
          }
      }
      out.flux[li] = flux_leaf;
      out.interior[li] = interior;
      if (store_gradient) {
        auto* gl = new Vec3SLeaf(origin, openvdb::Vec3s(0.0f), false);
        for (auto it = leaf.cbeginValueOn(); it; ++it) {
          const Coord c = it.getCoord() - origin + Coord(kPad);
          // Central differences, index units (phi difference / 2).
          const openvdb::Vec3d g(
              0.5 * double(p_at(c[0] + 1, c[1], c[2]) - p_at(c[0] - 1, c[1], c[2])),
              0.5 * double(p_at(c[0], c[1] + 1, c[2]) - p_at(c[0], c[1] - 1, c[2])),
              0.5 * double(p_at(c[0], c[1], c[2] + 1) - p_at(c[0], c[1], c[2] - 1)));
          const openvdb::Vec3d w = apply_map(gmap.g, g);
          gl->setValueOn(it.pos(), openvdb::Vec3s(w));
        }
        out.gradient[li] = gl;
      }
    }
  });

  flux_out = FloatGrid::create(0.0f);
  flux_out->setTransform(sdf.transform().copy());
  flux_out->setName("flux");
  flux_out->setGridClass(openvdb::GRID_UNKNOWN);
  interior_voxels = 0;
  for (std::size_t li = 0; li < leaves.size(); ++li) {
    interior_voxels += out.interior[li];
    if (out.flux[li]) flux_out->tree().addLeaf(out.flux[li]);
  }
  seconds_flux = seconds_since(t0);
  if (store_gradient) {
    const auto t1 = std::chrono::steady_clock::now();
    gradient_out = Vec3SGrid::create(openvdb::Vec3s(0.0f));
    gradient_out->setTransform(sdf.transform().copy());
    gradient_out->setName("gradient");
    gradient_out->setGridClass(openvdb::GRID_UNKNOWN);
    gradient_out->setVectorType(openvdb::VEC_COVARIANT);
    for (Vec3SLeaf* gl : out.gradient) gradient_out->tree().addLeaf(gl);
    seconds_gradient = seconds_since(t1);
  }
}

std::unique_ptr<Fields> finish_fields(FloatGrid::Ptr sdf, const FieldOptions& options,
                                      FieldStats stats,
                                      std::chrono::steady_clock::time_point t0,
                                      const StageMonitor& monitor) {
  auto impl = std::make_unique<Fields::Impl>();
  impl->gmap = gradient_map(sdf->transform());
  sdf->setName("surface");
  sdf->setGridClass(openvdb::GRID_LEVEL_SET);
  derive_fields(*sdf, impl->gmap, options.flux_min, options.store_gradient, impl->flux,
                impl->gradient, stats.interior_voxels, stats.seconds_flux,
                stats.seconds_gradient, monitor);
  impl->sdf = std::move(sdf);
  stats.voxel_size = impl->gmap.voxel_size;
  const openvdb::Coord dim = impl->sdf->evalActiveVoxelBoundingBox().dim();
  stats.dims = {dim[0], dim[1], dim[2]};
  stats.sdf_active_voxels = impl->sdf->activeVoxelCount();
  stats.flux_active_voxels = impl->flux->activeVoxelCount();
  stats.grid_bytes = impl->sdf->memUsage() + impl->flux->memUsage();
  if (impl->gradient) {
    stats.gradient_active_voxels = impl->gradient->activeVoxelCount();
    stats.grid_bytes += impl->gradient->memUsage();
  }
  stats.seconds_total = seconds_since(t0);

  auto& p = impl->parameters;
  p["vdb_shell_voxel_size"] = format_double(stats.voxel_size);
  p["vdb_shell_exterior_band_voxels"] = format_double(kExteriorBandVoxels);
  p["vdb_shell_flux_min"] = format_double(options.flux_min);
  p["vdb_shell_flux_definition"] =
      "average outward flux of grad(phi) through the 26-neighbour cube, eq. 7 / 26";
  p["vdb_shell_sdf_strategy"] = stats.strategy;
  p["vdb_shell_source"] = stats.source;
  impl->stats = std::move(stats);
  return std::make_unique<Fields>(std::move(impl));
}

}  // namespace

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
        refine_with_neighbour_triangles(*sdf, *index_grid, im);
        stats.seconds_refine = seconds_since(t1);
      } else {
        FloatGrid::Ptr band = mesh_to_volume(im, *xform, float(kExteriorBandVoxels),
                                             float(kExteriorBandVoxels));
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

SeedBandComparison compare_seed_band(const SurfaceMesh& mesh, const FieldOptions& options) {
  init_openvdb();
  const FieldPlan plan = plan_fields(mesh, options);
  const openvdb::math::Transform::Ptr xform =
      transform_of(frame_of(bounding_box(mesh), plan.voxel_size));
  const IndexMesh im = to_index_space(mesh, *xform);
  SeedBandComparison out;
  openvdb::Int32Grid ours_index(-1), their_index(-1);
  auto t0 = std::chrono::steady_clock::now();
  std::size_t flood_filled = 0;
  const FloatGrid::Ptr ours =
      mesh_to_band(im, *xform, kSeedBandVoxels, kSeedBandVoxels, ours_index, &flood_filled);
  out.seconds = seconds_since(t0);
  t0 = std::chrono::steady_clock::now();
  const FloatGrid::Ptr theirs = mesh_to_volume(im, *xform, kSeedBandVoxels, kSeedBandVoxels,
                                               &their_index,
                                               openvdb::tools::DISABLE_RENORMALIZATION);
  out.seconds_mesh_to_volume = seconds_since(t0);
  out.voxelized_here = band_voxels_apply(im);
  out.flood_filled = flood_filled;
  out.band_voxels = std::size_t(ours->activeVoxelCount());
  // Every voxel of either grid's leaves, then every tile (value and state) of either tree.
  FloatGrid::ConstAccessor a = ours->getConstAccessor(), b = theirs->getConstAccessor();
  openvdb::Int32Grid::ConstAccessor ai = ours_index.getConstAccessor(),
                                    bi = their_index.getConstAccessor();
  auto differ = [&](const Coord& c) {
    return a.getValue(c) != b.getValue(c) || a.isValueOn(c) != b.isValueOn(c) ||
           ai.getValue(c) != bi.getValue(c) || ai.isValueOn(c) != bi.isValueOn(c);
  };
  std::set<std::array<int, 3>> leaves;
  auto add_leaves = [&](const auto& tree) {
    for (auto it = tree.cbeginLeaf(); it; ++it) {
      leaves.insert({it->origin()[0], it->origin()[1], it->origin()[2]});
    }
  };
  add_leaves(ours->tree());
  add_leaves(theirs->tree());
  add_leaves(ours_index.tree());
  add_leaves(their_index.tree());
  for (const auto& o : leaves) {
    for (int i = 0; i < 512; ++i) {
      out.differing_voxels += differ(Coord(o[0] + (i >> 6), o[1] + (i >> 3 & 7), o[2] + (i & 7)));
    }
  }
  auto tiles = [](const auto& tree) {
    std::vector<std::tuple<int, int, int, double, bool>> out;
    auto it = tree.cbeginValueAll();
    it.setMaxDepth(std::decay_t<decltype(tree)>::ValueAllCIter::LEAF_DEPTH - 1);
    for (; it; ++it) {
      const Coord c = it.getCoord();
      out.emplace_back(c[0], c[1], c[2], double(*it), it.isValueOn());
    }
    return out;
  };
  if (tiles(ours->tree()) != tiles(theirs->tree())) ++out.differing_voxels;
  if (tiles(ours_index.tree()) != tiles(their_index.tree())) ++out.differing_voxels;
  if (ours->tree().background() != theirs->tree().background()) ++out.differing_voxels;
  return out;
}

FieldStats build_narrow_band_reference(const SurfaceMesh& mesh, const FieldOptions& options) {
  init_openvdb();
  const FieldPlan plan = plan_fields(mesh, options);
  const GridFrame frame = frame_of(bounding_box(mesh), plan.voxel_size);
  const openvdb::math::Transform::Ptr xform = transform_of(frame);
  std::vector<openvdb::Vec3s> points;
  points.reserve(mesh.num_vertices());
  for (const Vec3d& p : mesh.points) points.emplace_back(float(p.x), float(p.y), float(p.z));
  std::vector<openvdb::Vec3I> triangles;
  triangles.reserve(mesh.num_faces());
  for (const Triangle& t : mesh.triangles) triangles.emplace_back(t[0], t[1], t[2]);
  const auto t0 = std::chrono::steady_clock::now();
  openvdb::util::NullInterrupter interrupter;
  FloatGrid::Ptr grid = openvdb::tools::meshToLevelSet<FloatGrid>(interrupter, *xform, points,
                                                                  triangles, 3.0f);
  FieldStats stats;
  stats.strategy = "meshToLevelSet narrow band, half-width 3";
  stats.source = "mesh";
  stats.seconds_sdf = stats.seconds_total = seconds_since(t0);
  stats.voxel_size = plan.voxel_size;
  stats.sdf_active_voxels = grid->activeVoxelCount();
  stats.grid_bytes = grid->memUsage();
  return stats;
}

// ---------------------------------------------------------------------------------------------
// Probe

namespace {

class VdbProbe final : public FieldProbe {
 public:
  explicit VdbProbe(const Fields::Impl& f)
      : f_(f),
        xform_(f.sdf->transform()),
        sdf_acc_(f.sdf->getConstAccessor()),
        flux_acc_(f.flux->getConstAccessor()) {
    if (f.gradient) grad_acc_ = std::make_unique<Vec3SGrid::ConstAccessor>(
                        f.gradient->getConstAccessor());
  }

  double phi(const Vec3d& p) override {
    return openvdb::tools::BoxSampler::sample(sdf_acc_, to_index(p));
  }

  double flux(const Vec3d& p) override {
    return openvdb::tools::BoxSampler::sample(flux_acc_, to_index(p));
  }

  Vec3d gradient(const Vec3d& p) override {
    const openvdb::Vec3d xyz = to_index(p);
    if (grad_acc_) {
      const openvdb::Vec3s g = openvdb::tools::BoxSampler::sample(*grad_acc_, xyz);
      return {g[0], g[1], g[2]};
    }
    const Coord base(int(std::floor(xyz[0])), int(std::floor(xyz[1])), int(std::floor(xyz[2])));
    const openvdb::Vec3d t = xyz - base.asVec3d();
    // phi over base + [-1, 2]^3 (only the 32 entries central differences need are read).
    float v[4][4][4];
    fetch_stencil(base, v);
    openvdb::Vec3d g(0.0, 0.0, 0.0);
    for (int cx = 0; cx < 2; ++cx)
      for (int cy = 0; cy < 2; ++cy)
        for (int cz = 0; cz < 2; ++cz) {
          const double w = (cx ? t[0] : 1.0 - t[0]) * (cy ? t[1] : 1.0 - t[1]) *
                           (cz ? t[2] : 1.0 - t[2]);
          const int x = cx + 1, y = cy + 1, z = cz + 1;
          g[0] += w * 0.5 * double(v[x + 1][y][z] - v[x - 1][y][z]);
          g[1] += w * 0.5 * double(v[x][y + 1][z] - v[x][y - 1][z]);
          g[2] += w * 0.5 * double(v[x][y][z + 1] - v[x][y][z - 1]);
        }
    const openvdb::Vec3d w = apply_map(f_.gmap.g, g);
    return {w[0], w[1], w[2]};
  }

 private:
  openvdb::Vec3d to_index(const Vec3d& p) const {
    return xform_.worldToIndex(openvdb::Vec3d(p.x, p.y, p.z));
  }

  /// Reads phi at base + (i-1, j-1, k-1) for the entries of the 4^3 block that central
  /// differences at the 8 inner corners use, through at most 8 leaf lookups.
  void fetch_stencil(const Coord& base, float (&v)[4][4][4]) {
    const Coord lo = base.offsetBy(-1);
    const FloatLeaf* leaves[2][2][2];
    float tiles[2][2][2];
    const Coord lo_leaf = lo & ~(kLeafDim - 1);
    // The block spans a second leaf along an axis only when it starts in the leaf's last 3.
    const int na = (lo[0] & 7) > 4 ? 2 : 1, nb = (lo[1] & 7) > 4 ? 2 : 1,
              nc = (lo[2] & 7) > 4 ? 2 : 1;
    for (int a = 0; a < na; ++a)
      for (int b = 0; b < nb; ++b)
        for (int c = 0; c < nc; ++c) {
          const Coord o = lo_leaf.offsetBy(a * kLeafDim, b * kLeafDim, c * kLeafDim);
          leaves[a][b][c] = sdf_acc_.probeConstLeaf(o);
          tiles[a][b][c] = leaves[a][b][c] ? 0.0f : sdf_acc_.getValue(o);
        }
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j)
        for (int k = 0; k < 4; ++k) {
          const int inner = (i == 1 || i == 2) + (j == 1 || j == 2) + (k == 1 || k == 2);
          if (inner < 2) continue;  // corners and edges of the 4^3 block are not needed
          const int x = lo[0] + i, y = lo[1] + j, z = lo[2] + k;
          const int a = (x - lo_leaf[0]) >> 3, b = (y - lo_leaf[1]) >> 3,
                    c = (z - lo_leaf[2]) >> 3;
          const FloatLeaf* leaf = leaves[a][b][c];
          v[i][j][k] = leaf ? leaf->getValue(((x & 7) << 6) | ((y & 7) << 3) | (z & 7))
                            : tiles[a][b][c];
        }
  }

  const Fields::Impl& f_;
  const openvdb::math::Transform& xform_;
  FloatGrid::ConstAccessor sdf_acc_;
  FloatGrid::ConstAccessor flux_acc_;
  std::unique_ptr<Vec3SGrid::ConstAccessor> grad_acc_;
};

}  // namespace

std::unique_ptr<FieldProbe> Fields::probe() const { return std::make_unique<VdbProbe>(*impl_); }

// ---------------------------------------------------------------------------------------------
// .vdb files

namespace {

std::uint64_t fnv1a(std::uint64_t h, const void* data, std::size_t n) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < n; ++i) {
    h ^= p[i];
    h *= 1099511628211ull;
  }
  return h;
}

template <typename GridT>
std::uint64_t checksum_of(const GridT& grid) {
  std::uint64_t h = 14695981039346656037ull;
  // Value iteration order is the tree's (deterministic for equal topology).
  for (auto it = grid.cbeginValueOn(); it; ++it) {
    openvdb::CoordBBox box;
    it.getBoundingBox(box);
    const auto value = *it;
    h = fnv1a(h, &box, sizeof(box));
    h = fnv1a(h, &value, sizeof(value));
  }
  return h;
}

VdbGridInfo info_of(const openvdb::GridBase& grid) {
  VdbGridInfo info;
  info.name = grid.getName();
  info.value_type = grid.valueType();
  info.grid_class = openvdb::GridBase::gridClassToString(grid.getGridClass());
  info.active_voxels = grid.activeVoxelCount();
  info.voxel_size = grid.voxelSize()[0];
  for (auto it = grid.beginMeta(); it != grid.endMeta(); ++it) {
    info.metadata[it->first] = it->second ? it->second->str() : std::string();
  }
  if (const auto* f = dynamic_cast<const FloatGrid*>(&grid)) {
    info.checksum = checksum_of(*f);
  } else if (const auto* v = dynamic_cast<const Vec3SGrid*>(&grid)) {
    info.checksum = checksum_of(*v);
  }
  return info;
}

openvdb::GridPtrVec output_grids(const Fields& fields,
                                 const std::map<std::string, std::string>& metadata) {
  const Fields::Impl& f = fields.impl();
  openvdb::GridPtrVec grids;
  std::vector<openvdb::GridBase::Ptr> all = {f.sdf->copyGrid(), f.flux->copyGrid()};
  if (f.gradient) all.push_back(f.gradient->copyGrid());
  for (openvdb::GridBase::Ptr& g : all) {
    for (const auto& [k, v] : fields.parameters()) g->insertMeta(k, openvdb::StringMetadata(v));
    for (const auto& [k, v] : metadata) g->insertMeta(k, openvdb::StringMetadata(v));
    grids.push_back(g);
  }
  return grids;
}

/// OpenVDB writes a random UUID into every file header, as 36 characters at byte kUuidOffset
/// (after the magic number, three version numbers and a flag), so two writes of the same grids
/// would differ. write_grids() replaces it by one derived from the rest of the file: the same
/// grids give the same bytes (for any thread count, on every run), and different content still
/// gets a different UUID, which is what OpenVDB compares it for.
constexpr std::streamoff kUuidOffset = 21;
constexpr std::size_t kUuidChars = 36;

/// Forwards every byte to `target`, hashing all but the header's UUID and keeping a copy of it.
class HashingBuf final : public std::streambuf {
 public:
  explicit HashingBuf(std::streambuf* target) : target_(target) {}

  /// "xxxxxxxx-xxxx-8xxx-axxx-xxxxxxxxxxxx" from the hash (RFC 9562 version 8, custom), or ""
  /// when the header did not hold a UUID where expected (then the file is left as written).
  std::string content_uuid() const {
    if (!is_uuid(uuid_)) return "";
    std::uint64_t hi = hash_, lo = hash_ ^ (bytes_ * 0x9e3779b97f4a7c15ull);
    lo ^= lo >> 30, lo *= 0xbf58476d1ce4e5b9ull, lo ^= lo >> 27, lo *= 0x94d049bb133111ebull;
    lo ^= lo >> 31;  // splitmix64 finaliser
    hi = (hi & ~0xf000ull) | 0x8000ull;                      // version 8
    lo = (lo & ~(0x3ull << 62)) | (0x2ull << 62);            // variant 10
    char buf[40];
    std::snprintf(buf, sizeof buf, "%08llx-%04llx-%04llx-%04llx-%012llx",
                  static_cast<unsigned long long>(hi >> 32),
                  static_cast<unsigned long long>((hi >> 16) & 0xffff),
                  static_cast<unsigned long long>(hi & 0xffff),
                  static_cast<unsigned long long>(lo >> 48),
                  static_cast<unsigned long long>(lo & 0xffffffffffffull));
    return buf;
  }

 protected:
  std::streamsize xsputn(const char* s, std::streamsize n) override {
    const std::uint64_t begin = bytes_, end = bytes_ + static_cast<std::uint64_t>(n);
    const std::uint64_t u0 = kUuidOffset, u1 = u0 + kUuidChars;
    auto hash = [&](std::uint64_t a, std::uint64_t b) {  // absolute offsets [a, b)
      if (a < b) hash_ = fnv1a(hash_, s + (a - begin), b - a);
    };
    hash(begin, std::min(end, u0));
    const std::uint64_t c0 = std::max(begin, u0), c1 = std::min(end, u1);
    if (c0 < c1) uuid_.append(s + (c0 - begin), c1 - c0);
    hash(std::max(begin, u1), end);
    bytes_ = end;
    return target_->sputn(s, n);
  }
  int_type overflow(int_type c) override {
    if (traits_type::eq_int_type(c, traits_type::eof())) return traits_type::not_eof(c);
    const char ch = traits_type::to_char_type(c);
    return xsputn(&ch, 1) == 1 ? c : traits_type::eof();
  }
  int sync() override { return target_->pubsync(); }

 private:
  static bool is_uuid(const std::string& u) {
    if (u.size() != kUuidChars) return false;
    for (std::size_t i = 0; i < u.size(); ++i) {
      const bool dash = i == 8 || i == 13 || i == 18 || i == 23;
      if (dash ? u[i] != '-' : !std::isxdigit(static_cast<unsigned char>(u[i]))) return false;
    }
    return true;
  }

  std::streambuf* target_;
  std::uint64_t hash_ = 14695981039346656037ull;
  std::uint64_t bytes_ = 0;
  std::string uuid_;
};

void require_readable(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    throw InputError("cannot read level set file '" + path + "': no such file");
  }
}

}  // namespace

void write_grids(const std::string& path, const Fields& fields,
                 const std::map<std::string, std::string>& metadata,
                 const TraceResult* traces) {
  init_openvdb();
  auto tag = [&](openvdb::MetaMap& m) {
    for (const auto& [k, v] : fields.parameters()) m.insertMeta(k, openvdb::StringMetadata(v));
    for (const auto& [k, v] : metadata) m.insertMeta(k, openvdb::StringMetadata(v));
  };
  openvdb::GridPtrVec grids = output_grids(fields, metadata);
  if (traces) {
    grids.push_back(make_trace_points_grid(*traces, fields.impl().sdf->transform()));
    tag(*grids.back());
  }
  openvdb::MetaMap file_meta;
  tag(file_meta);
  write_file_atomically(path, [&](std::ostream& os) {
    HashingBuf hashing(os.rdbuf());
    std::ostream hashed(&hashing);
    try {
      openvdb::io::Stream(hashed).write(grids, file_meta);
    } catch (const openvdb::Exception& e) {
      throw ResourceError("cannot write '" + path + "': " + e.what());
    }
    const std::string uuid = hashing.content_uuid();
    if (hashed && !uuid.empty()) {
      os.seekp(kUuidOffset);
      os.write(uuid.data(), static_cast<std::streamsize>(uuid.size()));
      os.seekp(0, std::ios::end);
    }
    if (!hashed || !os)
      throw ResourceError("cannot write '" + path + "': write failed (disk full?)");
  });
}

std::vector<VdbGridInfo> read_vdb_grid_infos(const std::string& path) {
  init_openvdb();
  require_readable(path);
  std::vector<VdbGridInfo> out;
  try {
    openvdb::io::File file(path);
    file.open(false);
    openvdb::GridPtrVecPtr grids = file.getGrids();
    file.close();
    for (const openvdb::GridBase::Ptr& g : *grids) out.push_back(info_of(*g));
  } catch (const openvdb::Exception& e) {
    throw InputError("cannot read '" + path + "' as a .vdb file: " + e.what());
  }
  return out;
}

std::vector<VdbGridInfo> grid_infos(const Fields& fields) {
  std::vector<VdbGridInfo> out;
  for (const openvdb::GridBase::Ptr& g : output_grids(fields, {})) out.push_back(info_of(*g));
  return out;
}

/// Reads the float level set `grid_name` of `vdb_path` (empty name: 'surface', else the first
/// float level set) and checks its type and class. `where` names it for messages.
/// \throw InputError naming the file, the grid and the fix.
FloatGrid::Ptr read_level_set_grid(const std::string& vdb_path, const std::string& grid_name,
                                   std::string& where) {
  openvdb::GridBase::Ptr base;
  std::string chosen;
  try {
    openvdb::io::File file(vdb_path);
    file.open(false);
    openvdb::GridPtrVecPtr metas = file.readAllGridMetadata();
    std::string names;
    for (const auto& m : *metas) names += (names.empty() ? "'" : ", '") + m->getName() + "'";
    if (!grid_name.empty()) {
      if (!file.hasGrid(grid_name)) {
        throw InputError("'" + vdb_path + "' has no grid named '" + grid_name +
                         "'; its grids are " + (names.empty() ? "none" : names));
      }
      chosen = grid_name;
    } else {
      auto is_float_ls = [](const openvdb::GridBase& g) {
        return g.isType<FloatGrid>() && g.getGridClass() == openvdb::GRID_LEVEL_SET;
      };
      for (const auto& m : *metas) {
        if (m->getName() == "surface" && is_float_ls(*m)) chosen = "surface";
      }
      for (const auto& m : *metas) {
        if (chosen.empty() && is_float_ls(*m)) chosen = m->getName();
      }
      if (chosen.empty()) {
        throw InputError("'" + vdb_path + "' holds no float level set grid (its grids: " +
                         (names.empty() ? "none" : names) +
                         "); pass --grid NAME, and if that grid is a signed distance field, "
                         "set its grid class to level set");
      }
    }
    base = file.readGrid(chosen);
    file.close();
  } catch (const openvdb::Exception& e) {
    throw InputError("cannot read '" + vdb_path + "' as a .vdb file: " + e.what());
  }
  FloatGrid::Ptr grid = openvdb::gridPtrCast<FloatGrid>(base);
  where = "grid '" + chosen + "' of '" + vdb_path + "'";
  if (!grid) {
    throw InputError(where + " holds " + base->valueType() +
                     " values; a level set must be a float grid");
  }
  if (grid->getGridClass() != openvdb::GRID_LEVEL_SET) {
    throw InputError(where + " is not a level set (its class is '" +
                     openvdb::GridBase::gridClassToString(grid->getGridClass()) +
                     "'); if it holds signed distances (negative inside), try setting the grid "
                     "class to level set");
  }
  return grid;
}

std::unique_ptr<Fields> fields_from_level_set(const std::string& vdb_path,
                                              const std::string& grid_name,
                                              const SurfaceMesh& mesh,
                                              const FieldOptions& options,
                                              const StageMonitor& monitor) {
  init_openvdb();
  require_readable(vdb_path);
  if (!(options.flux_min >= 0.0 && options.flux_min <= 1.0)) {
    throw InputError("flux_min must lie in [0, 1]; got " + format_double(options.flux_min));
  }
  const auto t0 = std::chrono::steady_clock::now();
  std::string where;
  FloatGrid::Ptr grid = read_level_set_grid(vdb_path, grid_name, where);
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
                       format_double(p.z) + "); pass the level set built from this mesh, or "
                       "drop --level-set to build one");
    }
  }
  // Memory: the filled interior of a narrow band is about as large as the bounding box's
  // interior; estimate it from the mesh like plan_fields() does.
  const double h = gmap.voxel_size;
  const double interior = std::abs(signed_volume(mesh)) / (h * h * h);
  const bool unfilled = has_unfilled_interior(*grid);
  const double bytes = kFixedBytes + double(grid->memUsage()) +
                       interior * (unfilled ? build_bytes_per_voxel(SdfMethod::kFastSweeping)
                                            : 0.0) +
                       (options.store_gradient ? interior * kGradientBytesPerVoxel : 0.0);
  if (bytes > options.max_memory_gb * kGiB) {
    throw ResourceError("the fields of " + where + " need about " + format_gb(bytes) +
                        ", more than --max-memory " + format_double(options.max_memory_gb) +
                        " GiB; raise --max-memory");
  }
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


PolygonSoup level_set_to_soup(const std::string& vdb_path, const std::string& grid_name,
                              double adaptivity) {
  init_openvdb();
  require_readable(vdb_path);
  if (!(adaptivity >= 0.0 && adaptivity <= 1.0))
    throw InputError("--adaptivity must lie in [0, 1]; got " + format_double(adaptivity));
  std::string where;
  const FloatGrid::Ptr grid = read_level_set_grid(vdb_path, grid_name, where);
  std::vector<openvdb::Vec3s> points;
  std::vector<openvdb::Vec3I> triangles;
  std::vector<openvdb::Vec4I> quads;
  openvdb::tools::volumeToMesh(*grid, points, triangles, quads, 0.0, adaptivity);
  PolygonSoup soup;
  soup.points.reserve(points.size());
  for (const openvdb::Vec3s& p : points) soup.points.push_back({p[0], p[1], p[2]});
  // OpenVDB's polygons face into the negative (inside) region: reverse them to face outward.
  for (const openvdb::Vec3I& t : triangles) soup.polygons.push_back({t[2], t[1], t[0]});
  for (const openvdb::Vec4I& q : quads) soup.polygons.push_back({q[3], q[2], q[1], q[0]});
  if (soup.polygons.empty())
    throw InputError(where + " has no zero crossing: its level set holds no surface to mesh");
  return soup;
}

}  // namespace vdb_shell
