// seed_band.cpp — the seed band of SdfMethod::kExactInterior: meshToVolume's narrow band of two
// voxels, with its voxelization done by 64-bit rows instead of a flood fill per triangle
// (mesh_to_band()); compare_seed_band(), which builds it both ways, and OpenVDB's plain
// narrow band as the benchmarks' floor (build_narrow_band_reference(), fields_diagnostics.h).
#include "vdb_ops/fields/fields_internal.h"

#include <openvdb/tools/MeshToVolume.h>
#include <openvdb/tools/Prune.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <set>
#include <tuple>
#include <unordered_map>

#include "core/base/run_control.h"
#include "core/base/timer.h"
#include "vdb_ops/fields_diagnostics.h"

namespace vdb_shell {
namespace fields_detail {

/// Narrow band of `ex` voxels outside and `in` voxels inside (in = FLT_MAX fills the interior
/// with distances to a nearby triangle). `index_grid`, if given, receives each voxel's triangle.
FloatGrid::Ptr mesh_to_volume(const IndexMesh& m, const openvdb::math::Transform& xform, float ex,
                              float in, openvdb::Int32Grid* index_grid, int flags) {
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
// ones, the smallest triangle index. Tree accesses per voxel make this most of the band's time.
// The voxels a triangle reaches are the 3^3 neighbourhoods of floor(a) and of the voxels it
// intersects, since those are 26-connected (the voxel centre nearest to any point of the triangle
// is within sqrt(0.75) of it, and moves to a neighbour as the point moves). band_voxels() finds
// them with 64-bit rows over the triangle's bounding box, measures them with the same OpenVDB
// function, and keeps the same minimum: its distance and index trees are meshToVolume's, voxel
// for voxel. (Only a rounding split of the intersecting voxels at exactly sqrt(0.75) could
// differ: then it also measures the voxels the flood fill would not reach.) mesh_to_band() then
// runs meshToVolume's remaining steps unchanged, in its order.

namespace {

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
  std::unordered_map<std::uint64_t, std::size_t> slot;    ///< leaf key -> index in `leaves`
  std::deque<std::pair<std::uint64_t, BandLeaf>> leaves;  ///< a deque: kept by address
  std::vector<BandLeaf*> box_leaves;  ///< the leaves over the triangle's box (null: not yet)
  std::vector<std::uint64_t> bits;    ///< bit rows (fast path) or visited marks (flood fill)
  std::vector<float> measured;        ///< squared distances measured near the plane
  std::vector<Coord> stack;
  std::size_t flood_filled = 0;  ///< triangles voxelized by the flood fill

  BandLeaf& leaf_at(const Coord& ijk) {
    const std::uint64_t key = band_leaf_key(ijk);
    const auto [it, added] = slot.emplace(key, leaves.size());
    if (added) {
      const Coord origin(ijk[0] & ~7, ijk[1] & ~7, ijk[2] & ~7);
      BandLeaf leaf{
          std::make_unique<FloatLeaf>(origin, std::numeric_limits<float>::max(), false),
          std::make_unique<Int32Leaf>(origin, std::int32_t(openvdb::util::INVALID_IDX), false)};
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
  const Coord lo =
      Coord::floor(openvdb::math::minComponent(openvdb::math::minComponent(a, b), c)).offsetBy(-2);
  const Coord hi =
      Coord::floor(openvdb::math::maxComponent(openvdb::math::maxComponent(a, b), c)).offsetBy(2);
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
    if (!(lo[0] > -4.0e6 && lo[1] > -4.0e6 && lo[2] > -4.0e6 && hi[0] < 4.0e6 && hi[1] < 4.0e6 &&
          hi[2] < 4.0e6)) {
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
                      for (std::size_t i = range.begin(); i < range.end(); ++i)
                        band_voxelize_triangle(m, i, out);
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

}  // namespace

/// The seed band: meshToVolume(m, xform, ex, in, DISABLE_RENORMALIZATION, index_grid) with
/// band_voxels() for its voxelization where that applies, the same result either way. Widths in
/// voxels, at most 2 (meshToVolume widens wider bands after the steps below). `flood_filled`,
/// if given, receives the number of triangles voxelized by the flood fill (0 when meshToVolume
/// did everything).
FloatGrid::Ptr mesh_to_band(const IndexMesh& m, const openvdb::math::Transform& xform, float ex,
                            float in, openvdb::Int32Grid& index_grid, std::size_t* flood_filled) {
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
  tbb::parallel_for(range, internal::ComputeIntersectingVoxelSign<FloatTree, Adapter>(
                               nodes, dist, index, adapter));
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
}  // namespace fields_detail

using namespace fields_detail;

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
  const FloatGrid::Ptr theirs =
      mesh_to_volume(im, *xform, kSeedBandVoxels, kSeedBandVoxels, &their_index,
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
  FloatGrid::Ptr grid =
      openvdb::tools::meshToLevelSet<FloatGrid>(interrupter, *xform, points, triangles, 3.0f);
  FieldStats stats;
  stats.strategy = "meshToLevelSet narrow band, half-width 3";
  stats.source = "mesh";
  stats.seconds_sdf = stats.seconds_total = seconds_since(t0);
  stats.voxel_size = plan.voxel_size;
  stats.sdf_active_voxels = grid->activeVoxelCount();
  stats.grid_bytes = grid->memUsage();
  return stats;
}

}  // namespace vdb_shell
