// leaf_bits.h — per-leaf bit masks and leaf tables: how the interior fill (wavefront.cpp) and its
// refinement (refine.cpp) walk the SDF's leaves and their 26 neighbours without tree lookups.
// Internal to vdb_ops/fields/.
#pragma once

#include <sys/mman.h>

#include <array>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <new>
#include <vector>

#include "vdb_ops/fields/fields_internal.h"

namespace vdb_shell {
namespace fields_detail {

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

inline bool any_bit(const LeafBits& m) {
  std::uint64_t a = 0;
  for (std::uint64_t w : m) a |= w;
  return a != 0;
}

/// The bits of `masks` over a leaf and its one-voxel halo: halo[x + 1][y + 1] bit z + 1 is
/// voxel (x, y, z) of the leaf's frame, x, y, z in [-1, 8]. With `touched` (per leaf, its
/// mask's touched_neighbours()), neighbours with nothing in the slab facing the leaf are skipped.
inline void gather_halo_bits(const std::vector<LeafBits>& masks,
                             const std::array<std::int32_t, 27>& nb, std::uint16_t (&halo)[10][10],
                             const std::uint32_t* touched = nullptr) {
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
            halo[hx][hy] |=
                std::uint16_t(sz == 1 ? row << 1 : (sz == 0 ? (row >> 7) & 1u : (row & 1u) << 9));
          }
        }
      }
}

/// The triangles of the voxels in `known` over a leaf and a halo of kW voxels,
/// block[((x + kW) * kN + y + kW) * kN + z + kW] with kN = 8 + 2 kW; -1 elsewhere.
template <int kW>
inline void gather_ids_block(const std::vector<LeafBits>& known,
                             const std::array<std::int32_t, 27>& nb, const std::int32_t* ids,
                             std::int32_t* block) {
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
inline std::uint32_t touched_neighbours(const LeafBits& m) {
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
std::vector<LeafBits> dilate_bits(const LeafTable& table, const std::vector<LeafBits>& masks);

struct TriangleF;  // closest_triangle.h

/// The refinement after the wavefront (refine.cpp): the seed voxels next to a medial surface join
/// `medial`, and the voxels within 2 of `medial` ones measure the triangles of their 5^3
/// neighbourhood. `known`: the voxels with a closest triangle in `ids` (512 per leaf).
void refine_medial_voxels(const LeafTable& table, const std::vector<LeafBits>& known,
                          const std::vector<LeafBits>& seeds, std::vector<LeafBits> medial,
                          const std::int32_t* ids, const std::vector<TriangleF>& tris, float h);

}  // namespace fields_detail
}  // namespace vdb_shell
