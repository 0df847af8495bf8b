// refine.cpp — the refinement passes after an interior fill: refine_medial_voxels() for
// SdfMethod::kExactInterior's wavefront, and refine_by_neighbours_jacobi() for
// SdfMethod::kMeshToVolumeInterior. Both only lower |phi| to true distances to triangles, and each
// voxel writes only its own value: deterministic for any thread count.
#include "vdb_ops/fields/fields_internal.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "core/base/geometry.h"
#include "vdb_ops/fields/closest_triangle.h"
#include "vdb_ops/fields/leaf_bits.h"

namespace vdb_shell {
namespace fields_detail {

/// One Jacobi pass of closest-triangle propagation: every active voxel also measures its distance
/// to the triangles its 26 neighbours found closest and keeps the smallest. OpenVDB's band
/// expansion only looks at triangles of voxels within a Manhattan radius and never revisits a
/// voxel, which leaves bumps of up to ~0.3 voxels a few voxels deep; this pass removes most.
/// Only |phi| decreases (every candidate is a true distance to a triangle); signs are kept.
/// Reads triangle ids, writes only each voxel's own phi: deterministic for any thread count.
void refine_by_neighbours_jacobi(FloatGrid& sdf, const openvdb::Int32Grid& index_grid,
                                 const IndexMesh& m) {
  using IntLeaf = openvdb::Int32Tree::LeafNodeType;
  std::vector<FloatLeaf*> leaves;
  leaves.reserve(sdf.tree().leafCount());
  sdf.tree().getNodes(leaves);
  const double h = sdf.voxelSize()[0];
  const std::int32_t n_tris = std::int32_t(m.triangles.size());
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, leaves.size(), 16),
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
            const Vec3d p(it.getCoord()[0], it.getCoord()[1], it.getCoord()[2]);
            const float phi = *it;
            double best = double(std::abs(phi)) / h;
            best *= best;
            for (int k = 0; k < n; ++k) {
              const openvdb::Vec3I& t = m.triangles[std::size_t(cand[k])];
              auto corner = [&](int c) {
                const openvdb::Vec3s& q = m.points[t[c]];
                return Vec3d(q[0], q[1], q[2]);
              };
              best = std::min(best, point_triangle_distance2(p, corner(0), corner(1), corner(2)));
            }
            const float d = float(std::sqrt(best) * h);
            if (d < std::abs(phi)) it.setValue(phi < 0.0f ? -d : d);
          }
        }
      });
}

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

namespace {

/// Neighbour offsets in the blocks of halo 1 (10^3: the 26 neighbours) and 2 (12^3: the 124 of
/// the 5^3 neighbourhood).
struct NeighbourOffsets {
  std::vector<int> halo1, halo2;
  NeighbourOffsets() {
    for (int x = -2; x <= 2; ++x)
      for (int y = -2; y <= 2; ++y)
        for (int z = -2; z <= 2; ++z) {
          if (x == 0 && y == 0 && z == 0) continue;
          if (std::abs(x) <= 1 && std::abs(y) <= 1 && std::abs(z) <= 1) {
            halo1.push_back((x * 10 + y) * 10 + z);
          }
          halo2.push_back((x * 12 + y) * 12 + z);
        }
  }
};

/// Step 1: the seed voxels whose 26 neighbours' triangles face away from their own join `medial`.
void mark_medial_seeds(const LeafTable& table, const std::vector<LeafBits>& known,
                       const std::vector<LeafBits>& seeds, const std::int32_t* ids,
                       const std::vector<TriangleF>& tris, const NeighbourOffsets& offsets,
                       std::vector<LeafBits>& medial) {
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, table.leaves.size(), 16),
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
              for (int k : offsets.halo1) {
                const std::int32_t id = block[c + k];
                if (id >= 0 && id != own &&
                    dot3(tris[std::size_t(own)].n, tris[std::size_t(id)].n) < kMedialNormalCos) {
                  medial[li][x] |= std::uint64_t(1) << b;
                  break;
                }
              }
            }
        }
      });
}

/// Step 2, one thread's share: lowers phi at the voxels of a leaf to the distance to the
/// triangles of their 5^3 neighbourhoods.
class NeighbourhoodRefiner {
 public:
  NeighbourhoodRefiner(const std::vector<TriangleF>& tris, float h, const NeighbourOffsets& offsets,
                       TriangleSlots& map)
      : tris_(tris), h_(h), offsets_(offsets), map_(map) {}

  /// The voxels `todo` of `leaf`, whose 12^3 block of triangles (leaf and halo 2) is `block()`.
  void refine_leaf(FloatLeaf& leaf, const LeafBits& todo) {
    if (by_words(leaf, todo, 0, 0, 0, 8)) return;
    // Many small triangles: the leaf's octants, else voxel by voxel.
    for (int octant = 0; octant < 8; ++octant) {
      const int ox = 4 * (octant >> 2), oy = 4 * (octant >> 1 & 1), oz = 4 * (octant & 1);
      if (!by_words(leaf, todo, ox, oy, oz, 4)) voxel_by_voxel(leaf, todo, ox, oy, oz);
    }
  }

  std::int32_t* block() { return block_.data(); }

 private:
  static constexpr int kN = 12;  // block side: the leaf and a halo of 2

  /// Lowers phi at voxel (x, y, z) of a leaf to its distance to triangles cand[0, nc).
  void lower(FloatLeaf& leaf, int x, int y, int z, int nc) {
    if (nc == 0) return;
    float* phi = leaf.buffer().data();
    const int pos = (x << 6) | (y << 3) | z;
    const Coord origin = leaf.origin();
    const float p[3] = {float(origin[0] + x), float(origin[1] + y), float(origin[2] + z)};
    float best = (phi[pos] / h_) * (phi[pos] / h_);
    std::int32_t best_id = -1;
    lower_to_closest(p, cand_, nc, tris_, best, best_id);
    const float d = std::sqrt(best) * h_;
    if (d < std::abs(phi[pos])) phi[pos] = phi[pos] < 0.0f ? -d : d;
  }

  /// Lowers the voxels `todo` of the leaf's cube [o, o + n)^3 (n = 8 or 4) by the triangles of
  /// their 5^3 neighbourhoods, taken as unions of bit words (one bit per distinct triangle of
  /// the window, OR-ed along z, then y, then x); false (nothing done) when the cube's window
  /// [o - 2, o + n + 2)^3 holds more than 64 distinct triangles.
  bool by_words(FloatLeaf& leaf, const LeafBits& todo, int ox, int oy, int oz, int n) {
    const int w = n + 4;  // window side
    map_.clear();
    int n_distinct = 0;
    for (int x = 0; x < w; ++x)
      for (int y = 0; y < w; ++y) {
        const std::int32_t* src = &block_[std::size_t(((ox + x) * kN + oy + y) * kN + oz)];
        std::uint64_t* dst = &bit_[std::size_t((x * w + y) * w)];
        std::int32_t previous = -1;
        std::uint64_t previous_bit = 0;
        for (int z = 0; z < w; ++z) {
          const std::int32_t id = src[z];
          if (id != previous && id >= 0) {
            previous = id;
            previous_bit = map_.bit(id, distinct_, n_distinct);
            if (!previous_bit) return false;
          }
          dst[z] = id >= 0 ? previous_bit : 0;
        }
      }
    for (int x = 0; x < w; ++x)
      for (int y = 0; y < w; ++y)
        for (int z = 0; z < n; ++z) {
          const std::uint64_t* row = &bit_[std::size_t((x * w + y) * w + z)];
          along_z_[std::size_t((x * w + y) * n + z)] = row[0] | row[1] | row[2] | row[3] | row[4];
        }
    for (int x = 0; x < w; ++x)
      for (int y = 0; y < n; ++y)
        for (int z = 0; z < n; ++z) {
          const std::uint64_t* col = &along_z_[std::size_t((x * w + y) * n + z)];
          along_yz_[std::size_t((x * n + y) * n + z)] =
              col[0] | col[n] | col[2 * n] | col[3 * n] | col[4 * n];
        }
    const std::uint64_t z_mask = ((std::uint64_t(1) << n) - 1) << oz;
    for (int x = 0; x < n; ++x)
      for (int y = 0; y < n; ++y) {
        for (std::uint64_t bits = (todo[ox + x] >> (8 * (oy + y))) & z_mask; bits;
             bits &= bits - 1) {
          const int z = __builtin_ctzll(bits) - oz;
          const std::uint64_t* sheet = &along_yz_[std::size_t((x * n + y) * n + z)];
          const int nn = n * n;
          std::uint64_t around =
              sheet[0] | sheet[nn] | sheet[2 * nn] | sheet[3 * nn] | sheet[4 * nn];
          around &= ~bit_[std::size_t(((x + 2) * w + y + 2) * w + z + 2)];
          int nc = 0;
          for (; around; around &= around - 1) cand_[nc++] = distinct_[__builtin_ctzll(around)];
          lower(leaf, ox + x, oy + y, oz + z, nc);
        }
      }
    return true;
  }

  /// The voxels `todo` of the octant at o, each with its own list of distinct triangles.
  void voxel_by_voxel(FloatLeaf& leaf, const LeafBits& todo, int ox, int oy, int oz) {
    for (int x = ox; x < ox + 4; ++x)
      for (std::uint64_t bits = todo[x] & (std::uint64_t(0x0f0f0f0f) << (8 * oy + oz)); bits;
           bits &= bits - 1) {
        const int b = __builtin_ctzll(bits), y = b >> 3, z = b & 7;
        const int c = ((x + 2) * kN + y + 2) * kN + z + 2;
        const std::int32_t own = block_[std::size_t(c)];
        map_.clear();
        int nc = 0;
        for (int k : offsets_.halo2) {
          const std::int32_t id = block_[std::size_t(c + k)];
          if (id < 0 || id == own || map_.stamp[std::size_t(id)] == map_.now) continue;
          map_.stamp[std::size_t(id)] = map_.now;
          cand_[nc++] = id;
        }
        lower(leaf, x, y, z, nc);
      }
  }

  const std::vector<TriangleF>& tris_;
  const float h_;
  const NeighbourOffsets& offsets_;
  TriangleSlots& map_;
  std::vector<std::int32_t> block_ = std::vector<std::int32_t>(kN * kN * kN);
  // Per block voxel of a window, the bit of its triangle among the window's distinct ones;
  // their unions over 5 neighbours along z, then over 5 x 5 in y and z.
  std::vector<std::uint64_t> bit_ = std::vector<std::uint64_t>(kN * kN * kN);
  std::vector<std::uint64_t> along_z_ = std::vector<std::uint64_t>(kN * kN * 8);
  std::vector<std::uint64_t> along_yz_ = std::vector<std::uint64_t>(kN * 8 * 8);
  std::int32_t distinct_[64];
  std::int32_t cand_[124];
};

}  // namespace

/// Refinement after the wavefront; reads triangles, writes only each voxel's own phi (|phi| only
/// decreases; signs and triangles are kept): deterministic.
///  1. The band's voxels (`seeds`) whose 26 neighbours' triangles face away from their own join
///     `medial` (the wavefront marked only the voxels it filled). Their distances are OpenVDB's
///     voxelization's, and may miss a closer triangle by a little more than 0.1 voxel there.
///  2. The voxels within 2 of `medial` ones (the flux stencil) measure the triangles of their
///     5^3 neighbourhood: there, closest-triangle cells are thinner than a voxel and the
///     wavefront may have missed a voxel's closest triangle by a few hundredths of a voxel, which
///     shows in the flux (the centre of a sphere). Per leaf, the block's triangles become bits
///     of a word (up to 64 distinct ones; else per octant of the leaf, else one voxel at a time)
///     and a voxel's neighbourhood is the union of 5 x 5 x 5 words.
void refine_medial_voxels(const LeafTable& table, const std::vector<LeafBits>& known,
                          const std::vector<LeafBits>& seeds, std::vector<LeafBits> medial,
                          const std::int32_t* ids, const std::vector<TriangleF>& tris, float h) {
  const NeighbourOffsets offsets;
  mark_medial_seeds(table, known, seeds, ids, tris, offsets, medial);
  const std::vector<LeafBits> wide = dilate_bits(table, dilate_bits(table, medial));
  tbb::enumerable_thread_specific<TriangleSlots> slots(TriangleSlots(tris.size()));
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, table.leaves.size(), 16),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      NeighbourhoodRefiner refiner(tris, h, offsets, slots.local());
                      for (std::size_t li = range.begin(); li < range.end(); ++li) {
                        LeafBits todo = wide[li];
                        for (int x = 0; x < 8; ++x) todo[x] &= known[li][x];
                        if (!any_bit(todo)) continue;
                        gather_ids_block<2>(known, table.neighbours[li], ids, refiner.block());
                        refiner.refine_leaf(*table.leaves[li], todo);
                      }
                    });
}

}  // namespace fields_detail
}  // namespace vdb_shell
