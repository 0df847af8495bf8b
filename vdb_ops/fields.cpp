// fields.cpp — see fields.h. The only translation unit that includes OpenVDB's tools.
//
// Layout: options and plan; the two SDF methods; the per-leaf gradient/flux pass; the probe;
// .vdb reading and writing. Parallel loops run over leaf nodes in the tree's own (fixed) order and
// write one output slot per leaf, merged serially in that order, so results do not depend on the
// thread count.
#include "vdb_ops/fields.h"

#include <openvdb/openvdb.h>
#include <openvdb/io/File.h>
#include <openvdb/io/Stream.h>
#include <openvdb/tools/FastSweeping.h>
#include <openvdb/tools/Interpolation.h>
#include <openvdb/tools/MeshToVolume.h>
#include <openvdb/tools/Prune.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <mutex>
#include <new>
#include <sstream>

#include "core/atomic_file.h"
#include "core/errors.h"

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

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
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
  return m == SdfMethod::kExactInterior ? "meshToVolume exact interior"
                                        : "narrow band + fast sweeping interior";
}

// ---------------------------------------------------------------------------------------------
// Memory model (bytes), calibrated on tests/bench measurements (peak RSS at 128..1024).

/// Peak bytes per interior voxel while the SDF is built (distance + closest-polygon trees).
double build_bytes_per_voxel(SdfMethod m) { return m == SdfMethod::kExactInterior ? 10.0 : 50.0; }
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
  openvdb::math::Transform::Ptr xform = openvdb::math::Transform::createLinearTransform(f.voxel_size);
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
                              float in, openvdb::Int32Grid* index_grid = nullptr) {
  openvdb::tools::QuadAndTriangleDataAdapter<openvdb::Vec3s, openvdb::Vec3I> adapter(m.points,
                                                                                     m.triangles);
  openvdb::util::NullInterrupter interrupter;
  return openvdb::tools::meshToVolume<FloatGrid>(interrupter, adapter, xform, ex, in, 0,
                                                 index_grid);
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

/// Upper bound of the interior depth of a level set, voxels: half the smallest side of the
/// active bounding box, plus a margin.
int interior_depth_bound(const FloatGrid& grid) {
  const openvdb::CoordBBox b = grid.evalActiveVoxelBoundingBox();
  const openvdb::Coord d = b.dim();
  return std::min({d[0], d[1], d[2]}) / 2 + 2;
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
constexpr int kGrad = kLeafDim + 2;            // gradients at leaf +-1: 10

struct Offsets26 {
  std::array<std::array<int, 3>, 26> d{};
  std::array<std::array<float, 3>, 26> n{};  ///< unit outward normals d / |d|
};

const Offsets26& offsets26() {
  static const Offsets26 table = [] {
    Offsets26 t;
    int k = 0;
    for (int x = -1; x <= 1; ++x)
      for (int y = -1; y <= 1; ++y)
        for (int z = -1; z <= 1; ++z) {
          if (x == 0 && y == 0 && z == 0) continue;
          const float len = std::sqrt(float(x * x + y * y + z * z));
          t.d[k] = {x, y, z};
          t.n[k] = {x / len, y / len, z / len};
          ++k;
        }
    return t;
  }();
  return table;
}

/// Copies phi over [origin - 2, origin + 9]^3 into `block` (x-major), reading leaf buffers
/// directly and tile values where there is no leaf.
void gather_block(FloatGrid::ConstAccessor& acc, const Coord& origin, float* block) {
  for (int nx = -1; nx <= 1; ++nx)
    for (int ny = -1; ny <= 1; ++ny)
      for (int nz = -1; nz <= 1; ++nz) {
        const Coord nb_origin = origin.offsetBy(nx * kLeafDim, ny * kLeafDim, nz * kLeafDim);
        const FloatLeaf* leaf = acc.probeConstLeaf(nb_origin);
        const float tile = leaf ? 0.0f : acc.getValue(nb_origin);
        // Block index ranges covered by this neighbour along each axis.
        auto lo = [](int n) { return n < 0 ? 0 : (n == 0 ? kPad : kPad + kLeafDim); };
        auto hi = [](int n) { return n < 0 ? kPad : (n == 0 ? kPad + kLeafDim : kBlock); };
        for (int bx = lo(nx); bx < hi(nx); ++bx)
          for (int by = lo(ny); by < hi(ny); ++by)
            for (int bz = lo(nz); bz < hi(nz); ++bz) {
              float v = tile;
              if (leaf) {
                const int lx = (bx - kPad) & (kLeafDim - 1);
                const int ly = (by - kPad) & (kLeafDim - 1);
                const int lz = (bz - kPad) & (kLeafDim - 1);
                v = leaf->getValue((lx << 6) | (ly << 3) | lz);
              }
              block[(bx * kBlock + by) * kBlock + bz] = v;
            }
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
                   std::size_t& interior_voxels, double& seconds_flux, double& seconds_gradient) {
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
  const Offsets26& off = offsets26();

  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, leaves.size(), 16),
                    [&](const tbb::blocked_range<std::size_t>& range) {
    FloatGrid::ConstAccessor acc = sdf.getConstAccessor();
    std::vector<float> phi(kBlock * kBlock * kBlock);
    std::vector<std::array<float, 3>> grad(kGrad * kGrad * kGrad);
    for (std::size_t li = range.begin(); li < range.end(); ++li) {
      const FloatLeaf& leaf = *leaves[li];
      const Coord origin = leaf.origin();
      gather_block(acc, origin, phi.data());
      auto p_at = [&](int x, int y, int z) { return phi[(x * kBlock + y) * kBlock + z]; };
      // Central differences (index units: phi difference / 2) at block positions 1..10.
      for (int x = 0; x < kGrad; ++x)
        for (int y = 0; y < kGrad; ++y)
          for (int z = 0; z < kGrad; ++z) {
            const int bx = x + 1, by = y + 1, bz = z + 1;
            grad[(x * kGrad + y) * kGrad + z] = {
                0.5f * (p_at(bx + 1, by, bz) - p_at(bx - 1, by, bz)),
                0.5f * (p_at(bx, by + 1, bz) - p_at(bx, by - 1, bz)),
                0.5f * (p_at(bx, by, bz + 1) - p_at(bx, by, bz - 1))};
          }
      auto g_at = [&](int x, int y, int z) -> const std::array<float, 3>& {
        return grad[(x * kGrad + y) * kGrad + z];
      };
      std::size_t interior = 0;
      FloatLeaf* flux_leaf = nullptr;
      for (int x = 0; x < kLeafDim; ++x)
        for (int y = 0; y < kLeafDim; ++y)
          for (int z = 0; z < kLeafDim; ++z) {
            const openvdb::Index pos = (x << 6) | (y << 3) | z;
            if (!leaf.isValueOn(pos)) continue;
            const float p = p_at(x + kPad, y + kPad, z + kPad);
            if (p < 0.0f) ++interior;
            if (!(p < phi_limit)) continue;
            float sum = 0.0f;
            for (int k = 0; k < 26; ++k) {
              const std::array<float, 3>& g =
                  g_at(x + 1 + off.d[k][0], y + 1 + off.d[k][1], z + 1 + off.d[k][2]);
              sum += g[0] * off.n[k][0] + g[1] * off.n[k][1] + g[2] * off.n[k][2];
            }
            const float f = std::clamp(sum * inv_26h, -1.0f, 1.0f);
            if (std::abs(f) < fmin) continue;
            if (!flux_leaf) flux_leaf = new FloatLeaf(origin, 0.0f, false);
            flux_leaf->setValueOn(pos, f);
          }
      out.flux[li] = flux_leaf;
      out.interior[li] = interior;
      if (store_gradient) {
        auto* gl = new Vec3SLeaf(origin, openvdb::Vec3s(0.0f), false);
        for (auto it = leaf.cbeginValueOn(); it; ++it) {
          const Coord c = it.getCoord() - origin;
          const std::array<float, 3>& g = g_at(c[0] + 1, c[1] + 1, c[2] + 1);
          const openvdb::Vec3d w = apply_map(gmap.g, openvdb::Vec3d(g[0], g[1], g[2]));
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
                                      std::chrono::steady_clock::time_point t0) {
  auto impl = std::make_unique<Fields::Impl>();
  impl->gmap = gradient_map(sdf->transform());
  sdf->setName("surface");
  sdf->setGridClass(openvdb::GRID_LEVEL_SET);
  derive_fields(*sdf, impl->gmap, options.flux_min, options.store_gradient, impl->flux,
                impl->gradient, stats.interior_voxels, stats.seconds_flux,
                stats.seconds_gradient);
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

std::unique_ptr<Fields> build_fields(const SurfaceMesh& mesh, const FieldOptions& options) {
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
        openvdb::Int32Grid::Ptr index_grid = openvdb::Int32Grid::create(-1);
        sdf = mesh_to_volume(im, *xform, float(kExteriorBandVoxels),
                             std::numeric_limits<float>::max(), index_grid.get());
        const auto t1 = std::chrono::steady_clock::now();
        refine_with_neighbour_triangles(*sdf, *index_grid, im);
        stats.seconds_refine = seconds_since(t1);
      } else {
        FloatGrid::Ptr band = mesh_to_volume(im, *xform, float(kExteriorBandVoxels),
                                             float(kExteriorBandVoxels));
        sdf = fill_interior_by_sweeping(*band);
      }
    }
    stats.seconds_sdf = seconds_since(t0);
    auto fields = finish_fields(std::move(sdf), options, std::move(stats), t0);
    return fields;
  } catch (const std::bad_alloc&) {
    throw ResourceError("out of memory while building the fields at resolution " +
                        std::to_string(plan.resolution) + " (estimated " +
                        format_gb(double(plan.estimated_bytes)) + "); lower --resolution");
  }
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

void require_readable(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    throw InputError("cannot read level set file '" + path + "': no such file");
  }
}

}  // namespace

void write_grids(const std::string& path, const Fields& fields,
                 const std::map<std::string, std::string>& metadata) {
  init_openvdb();
  const openvdb::GridPtrVec grids = output_grids(fields, metadata);
  openvdb::MetaMap file_meta;
  for (const auto& [k, v] : fields.parameters()) file_meta.insertMeta(k, openvdb::StringMetadata(v));
  for (const auto& [k, v] : metadata) file_meta.insertMeta(k, openvdb::StringMetadata(v));
  write_file_atomically(path, [&](std::ostream& os) {
    try {
      openvdb::io::Stream(os).write(grids, file_meta);
    } catch (const openvdb::Exception& e) {
      throw ResourceError("cannot write '" + path + "': " + e.what());
    }
    if (!os) throw ResourceError("cannot write '" + path + "': write failed (disk full?)");
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

std::unique_ptr<Fields> fields_from_level_set(const std::string& vdb_path,
                                              const std::string& grid_name,
                                              const SurfaceMesh& mesh,
                                              const FieldOptions& options) {
  init_openvdb();
  require_readable(vdb_path);
  if (!(options.flux_min >= 0.0 && options.flux_min <= 1.0)) {
    throw InputError("flux_min must lie in [0, 1]; got " + format_double(options.flux_min));
  }
  const auto t0 = std::chrono::steady_clock::now();
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
  const std::string where = "grid '" + chosen + "' of '" + vdb_path + "'";
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
  stats.source = vdb_path + ":" + chosen;
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
    return finish_fields(std::move(grid), options, std::move(stats), t0);
  } catch (const std::bad_alloc&) {
    throw ResourceError("out of memory while preparing the fields of " + where);
  }
}

}  // namespace vdb_shell
