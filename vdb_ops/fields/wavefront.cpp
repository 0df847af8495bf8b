// wavefront.cpp — the interior fill of SdfMethod::kExactInterior: a closest-triangle wavefront from
// the seed band into the interior and out to the exterior band (fill_by_wavefront()).
#include "vdb_ops/fields/fields_internal.h"

#include <openvdb/tools/ChangeBackground.h>
#include <openvdb/tools/Prune.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>
#include <memory>
#include <vector>

#include "core/base/run_control.h"
#include "vdb_ops/fields/closest_triangle.h"
#include "vdb_ops/fields/leaf_bits.h"

namespace vdb_shell {
namespace fields_detail {

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

namespace {

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
                          t.neighbours[i][s] =
                              acc.getValue(c.offsetBy(s / 9 - 1, s / 3 % 3 - 1, s % 3 - 1));
                        }
                      }
                    });
  return t;
}

}  // namespace

/// Upper bound of the interior depth of a level set, voxels: half the smallest side of the
/// active bounding box, plus a margin.
int interior_depth_bound(const FloatGrid& grid) {
  const openvdb::CoordBBox b = grid.evalActiveVoxelBoundingBox();
  const openvdb::Coord d = b.dim();
  return std::min({d[0], d[1], d[2]}) / 2 + 2;
}

namespace {

/// Offsets in a 10^3 block of the 27 voxels around one, indexed (a * 3 + b) * 3 + c for the
/// offset (a - 1, b - 1, c - 1); candidates are listed in this order.
struct Offsets27 {
  int at[27];
  Offsets27() {
    for (int i = 0; i < 27; ++i) at[i] = ((i / 9 - 1) * 10 + (i / 3 % 3 - 1)) * 10 + i % 3 - 1;
  }
};

/// Per-thread scratch of one leaf's step.
struct LeafScratch {
  std::int32_t block[1000];   ///< triangles of the fresh voxels over the leaf and its halo
  std::uint64_t words[1000];  ///< their bits among the `distinct` ones (when by_words)
  std::int32_t distinct[64];
  int n_distinct = 0;
  bool by_words = true;  ///< at most 64 distinct triangles: candidates as unions of bits
};

/// One fill: the leaves' masks and triangles, and the iterations over them (the comment at the
/// top of this file describes the method).
class Wavefront {
 public:
  Wavefront(FloatGrid& sdf, const IndexMesh& m, float exterior_voxels)
      : sdf_(sdf),
        tris_(float_triangles(m)),
        h_(float(sdf.voxelSize()[0])),
        exterior_voxels_(exterior_voxels) {}

  /// Widens the band's leaves by their neighbours, activates the interior and seeds the front
  /// with the band's voxels that know their triangle.
  void seed(const openvdb::Int32Grid& index_grid);
  /// Runs the iterations until no leaf has voxels left to fill; reports to `monitor`.
  void run(const StageMonitor& monitor);
  /// Refines the voxels near medial surfaces, trims the exterior to its band and sets the
  /// background.
  void finish();

 private:
  void seed_leaf(std::size_t i, openvdb::Int32Grid::ConstAccessor& acc);
  void iterate(int iteration, float limit2);
  void prefetch_leaf(std::size_t lp, const std::vector<std::uint32_t>& touched_in) const;
  void step_leaf(std::size_t li, const std::vector<LeafBits>& fresh_in,
                 const std::vector<std::uint32_t>& touched_in, std::vector<LeafBits>& fresh_out,
                 std::vector<std::uint32_t>& touched_out, float limit2, LeafScratch& scratch,
                 TriangleSlots& map);
  void gather_fresh_triangles(std::size_t li, const std::uint16_t (&halo)[10][10],
                              LeafScratch& scratch, TriangleSlots& map) const;
  void measure_front(std::size_t li, const std::uint16_t (&halo)[10][10],
                     const LeafScratch& scratch, const TriangleSlots& map);
  bool accept(std::size_t li, float limit2, std::vector<LeafBits>& fresh_out,
              std::vector<std::uint32_t>& touched_out);
  void list_next_leaves(int iteration);
  void trim_exterior();

  FloatGrid& sdf_;
  const std::vector<TriangleF> tris_;
  const float h_;                ///< voxel size, world units
  const float exterior_voxels_;  ///< the exterior band's width, voxels
  LeafTable table_;
  std::size_t n_ = 0;  ///< leaves
  // Per leaf: the closest triangle of each voxel (valid where accepted or tentative); bit masks
  // of the voxels known (accepted), still to fill, tentative, next to a medial surface, outside
  // the surface, and accepted in the last iteration (`fresh`, two generations).
  std::unique_ptr<HugeArray<std::int32_t>> ids_;
  std::vector<LeafBits> known_, todo_, tentative_, medial_, outside_, seeds_;
  std::array<std::vector<LeafBits>, 2> fresh_;
  // Per leaf, touched_neighbours() of its `fresh` mask.
  std::array<std::vector<std::uint32_t>, 2> fresh_touched_;
  std::vector<std::int32_t> active_, previous_;  ///< leaves of this and the last iteration
  std::unique_ptr<std::atomic<std::uint8_t>[]> next_mark_;
  const Offsets27 off27_;
};

void Wavefront::seed(const openvdb::Int32Grid& index_grid) {
  // Every voxel within `exterior_voxels` (< 8) of the surface is in a seed's leaf or one of its
  // 26 neighbours: the front fills those leaves' outside voxels too and stops at that width.
  {
    std::vector<Coord> origins;
    origins.reserve(sdf_.tree().leafCount());
    for (auto it = sdf_.tree().cbeginLeaf(); it; ++it) origins.push_back(it->origin());
    openvdb::tree::ValueAccessor<FloatTree> acc(sdf_.tree());
    for (const Coord& o : origins) {
      for (int s = 0; s < 27; ++s) {
        acc.touchLeaf(o.offsetBy(8 * (s / 9 - 1), 8 * (s / 3 % 3 - 1), 8 * (s % 3 - 1)));
      }
    }
  }
  activate_interior(sdf_.tree());
  table_ = make_leaf_table(sdf_.tree());
  n_ = table_.leaves.size();
  ids_ = std::make_unique<HugeArray<std::int32_t>>(n_ * 512);
  for (auto* v : {&known_, &todo_, &tentative_, &medial_, &outside_, &fresh_[0], &fresh_[1]})
    v->resize(n_);
  fresh_touched_[0].resize(n_);
  fresh_touched_[1].resize(n_);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n_, 64),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      openvdb::Int32Grid::ConstAccessor acc = index_grid.getConstAccessor();
                      for (std::size_t i = range.begin(); i < range.end(); ++i) seed_leaf(i, acc);
                    });
  seeds_ = known_;
  for (std::size_t i = 0; i < n_; ++i) {
    if (any_bit(todo_[i])) active_.push_back(std::int32_t(i));
  }
  next_mark_.reset(new std::atomic<std::uint8_t>[n_]);
  for (std::size_t i = 0; i < n_; ++i) next_mark_[i].store(0, std::memory_order_relaxed);
}

void Wavefront::seed_leaf(std::size_t i, openvdb::Int32Grid::ConstAccessor& acc) {
  const std::int32_t n_tris = std::int32_t(tris_.size());
  const float seed_band = kSeedBandVoxels * h_;
  const FloatLeaf& leaf = *table_.leaves[i];
  const openvdb::Int32Tree::LeafNodeType* il = acc.probeConstLeaf(leaf.origin());
  // Every voxel not a seed is to fill: inside, all are active; outside, any may be.
  LeafBits dn{}, td{}, out{};
  for (int w = 0; w < 8; ++w) {
    if (il) dn[w] = il->getValueMask().getWord<std::uint64_t>(w);
  }
  const float* phi = leaf.buffer().data();
  const std::int32_t* src = il ? il->buffer().data() : nullptr;
  std::int32_t* dst = &(*ids_)[i * 512];
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
  todo_[i] = td;
  outside_[i] = out;
  fresh_[0][i] = dn;
  fresh_touched_[0][i] = touched_neighbours(dn);
  known_[i] = dn;
}

void Wavefront::run(const StageMonitor& monitor) {
  float limit = kSeedBandVoxels + 1.0f;  // voxels; accepted distances grow by one per iteration
  // Progress: one iteration per voxel of depth, at most interior_depth_bound() of them.
  const double depth_bound = interior_depth_bound(sdf_);
  tbb::enumerable_thread_specific<TriangleSlots> slots(TriangleSlots(tris_.size()));
  for (int iteration = 0; !active_.empty(); ++iteration, limit += 1.0f) {
    monitor.report(0.25 + 0.5 * std::min(1.0, iteration / depth_bound));
    const std::vector<LeafBits>& fresh_in = fresh_[iteration & 1];
    std::vector<LeafBits>& fresh_out = fresh_[(iteration + 1) & 1];
    const std::vector<std::uint32_t>& touched_in = fresh_touched_[iteration & 1];
    std::vector<std::uint32_t>& touched_out = fresh_touched_[(iteration + 1) & 1];
    const float limit2 = limit * limit;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, active_.size(), 4),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                        monitor.check();
                        LeafScratch scratch;
                        TriangleSlots& map = slots.local();
                        for (std::size_t j = range.begin(); j < range.end(); ++j) {
                          // The leaves of an iteration are far apart in memory and their triangles
                          // and distances were written iterations ago: fetching them a few leaves
                          // ahead hides most misses.
                          if (j + 3 < range.end())
                            prefetch_leaf(std::size_t(active_[j + 3]), touched_in);
                          step_leaf(std::size_t(active_[j]), fresh_in, touched_in, fresh_out,
                                    touched_out, limit2, scratch, map);
                        }
                      });
    list_next_leaves(iteration);
  }
}

void Wavefront::prefetch_leaf(std::size_t lp, const std::vector<std::uint32_t>& touched_in) const {
  const char* a = reinterpret_cast<const char*>(&(*ids_)[lp * 512]);
  const char* b = reinterpret_cast<const char*>(table_.values[lp]);
  for (int k = 0; k < 2048; k += 64) {
    __builtin_prefetch(a + k);
    __builtin_prefetch(b + k);
  }
  // And the triangles of the face neighbours' fresh voxels facing it.
  constexpr int kFace[6] = {4, 22, 10, 16, 12, 14};  // -x, +x, -y, +y, -z, +z
  const std::array<std::int32_t, 27>& nbp = table_.neighbours[lp];
  for (int f = 0; f < 6; ++f) {
    const int s = kFace[f];
    const std::int32_t ni = nbp[s];
    if (ni < 0 || !(touched_in[std::size_t(ni)] >> (26 - s) & 1u)) continue;
    const std::int32_t* base = &(*ids_)[std::size_t(ni) * 512];
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

void Wavefront::step_leaf(std::size_t li, const std::vector<LeafBits>& fresh_in,
                          const std::vector<std::uint32_t>& touched_in,
                          std::vector<LeafBits>& fresh_out, std::vector<std::uint32_t>& touched_out,
                          float limit2, LeafScratch& scratch, TriangleSlots& map) {
  std::uint16_t halo[10][10];
  gather_halo_bits(fresh_in, table_.neighbours[li], halo, touched_in.data());
  bool any_fresh = false;
  for (int x = 0; x < 10; ++x)
    for (int y = 0; y < 10; ++y) any_fresh |= halo[x][y] != 0;
  // Without fresh voxels around, the leaf only accepts its pending tentative voxels.
  if (any_fresh) {
    gather_fresh_triangles(li, halo, scratch, map);
    measure_front(li, halo, scratch, map);
  }
  if (accept(li, limit2, fresh_out, touched_out)) {
    next_mark_[li].store(1, std::memory_order_relaxed);
  }
  // Wake the neighbours whose halo holds a voxel accepted here (the leaf itself included).
  for (std::uint32_t t = touched_out[li]; t; t &= t - 1) {
    const std::int32_t ni = table_.neighbours[li][std::size_t(__builtin_ctz(t))];
    if (ni >= 0) next_mark_[std::size_t(ni)].store(1, std::memory_order_relaxed);
  }
}

void Wavefront::gather_fresh_triangles(std::size_t li, const std::uint16_t (&halo)[10][10],
                                       LeafScratch& scratch, TriangleSlots& map) const {
  // Triangles of the voxels accepted last iteration, over the leaf and its halo; only read
  // where `halo` has a bit. With at most 64 distinct ones, each also becomes a bit (`words`):
  // a voxel's candidates are then the union of its fresh neighbours' bits, distinct by
  // construction (a handful of distinct triangles in most leaves).
  const std::array<std::int32_t, 27>& nb = table_.neighbours[li];
  map.clear();
  scratch.n_distinct = 0;
  scratch.by_words = true;
  for (int hx = 0; hx < 10; ++hx)
    for (int hy = 0; hy < 10; ++hy)
      for (unsigned row = halo[hx][hy]; row; row &= row - 1) {
        const int hz = __builtin_ctz(row);
        const int x = hx - 1, y = hy - 1, z = hz - 1;
        const std::int32_t ni = nb[(((x + 8) >> 3) * 3 + ((y + 8) >> 3)) * 3 + ((z + 8) >> 3)];
        const std::int32_t id =
            (*ids_)[std::size_t(ni) * 512 + std::size_t(((x & 7) << 6) | ((y & 7) << 3) | (z & 7))];
        const int c = (hx * 10 + hy) * 10 + hz;
        scratch.block[c] = id;
        if (!scratch.by_words) continue;
        scratch.words[c] = map.bit(id, scratch.distinct, scratch.n_distinct);
        scratch.by_words = scratch.words[c] != 0;  // else too many: voxel by voxel
      }
}

void Wavefront::measure_front(std::size_t li, const std::uint16_t (&halo)[10][10],
                              const LeafScratch& scratch, const TriangleSlots& map) {
  float* phi = table_.values[li];
  std::int32_t* own = &(*ids_)[li * 512];
  LeafBits& tn = tentative_[li];
  const Coord& origin = table_.origins[li];
  const float h = h_;
  for (int x = 0; x < 8; ++x)
    for (int y = 0; y < 8; ++y) {
      const unsigned todo_row = unsigned(todo_[li][x] >> (8 * y)) & 0xffu;
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
        float best = has ? (phi[pos] / h) * (phi[pos] / h) : std::numeric_limits<float>::max();
        // The fresh neighbours, bit (a * 3 + b) * 3 + c for offset (a-1, b-1, c-1); the
        // voxel itself is never fresh (it is still to fill).
        std::uint32_t around = 0;
        for (int r = 0; r < 9; ++r) around |= ((rows[r] >> z) & 7u) << (3 * r);
        std::int32_t cand[26];
        int nc = 0;
        const int c = ((x + 1) * 10 + y + 1) * 10 + z + 1;
        // The triangle of the first fresh neighbour (offset order).
        const std::int32_t first = scratch.block[c + off27_.at[__builtin_ctz(around)]];
        if (scratch.by_words) {
          std::uint64_t word = 0;
          for (; around; around &= around - 1) {
            word |= scratch.words[c + off27_.at[__builtin_ctz(around)]];
          }
          if (has && map.has(best_id)) {
            word &= ~(std::uint64_t(1) << map.slot[std::size_t(best_id)]);
          }
          for (; word; word &= word - 1) cand[nc++] = scratch.distinct[__builtin_ctzll(word)];
        } else {
          for (; around; around &= around - 1) {
            const std::int32_t id = scratch.block[c + off27_.at[__builtin_ctz(around)]];
            if (id == best_id) continue;
            bool seen = false;
            for (int q = 0; q < nc; ++q) seen |= cand[q] == id;
            if (!seen) cand[nc++] = id;
          }
        }
        if (nc == 0) continue;
        const float p[3] = {float(origin[0] + x), float(origin[1] + y), float(origin[2] + z)};
        const bool out = (outside_[li][x] & bit) != 0;
        // Candidates facing apart: wavefronts from different sides meet here (inside: the
        // medial surface, where the flux lives). (Without a tentative triangle, `first` is a
        // candidate itself: one is not enough.)
        const float* n0 = tris_[std::size_t(has ? best_id : first)].n;
        for (int q = 0; q < nc && !out && (has || nc > 1); ++q) {
          if (dot3(n0, tris_[std::size_t(cand[q])].n) < kMedialNormalCos) {
            medial_[li][x] |= bit;
          }
        }
        lower_to_closest(p, cand, nc, tris_, best, best_id);
        if (best_id < 0) continue;  // no finite distance (not expected): never accepted
        own[pos] = best_id;
        phi[pos] = out ? std::sqrt(best) * h : -std::sqrt(best) * h;
        tn[x] |= bit;
      }
    }
}

bool Wavefront::accept(std::size_t li, float limit2, std::vector<LeafBits>& fresh_out,
                       std::vector<std::uint32_t>& touched_out) {
  // Accept the tentative voxels below the limit; those outside the exterior band are final
  // too, but dropped: they never become fresh, so the front stops there.
  const float* phi = table_.values[li];
  LeafBits& tn = tentative_[li];
  LeafBits accepted{};
  bool pending = false;
  for (int x = 0; x < 8; ++x) {
    std::uint64_t dropped = 0;
    for (std::uint64_t bits = tn[x]; bits; bits &= bits - 1) {
      const int b = __builtin_ctzll(bits);
      const float d = phi[(x << 6) | b] / h_;
      if (d * d < limit2) {
        (d >= exterior_voxels_ ? dropped : accepted[x]) |= std::uint64_t(1) << b;
      } else {
        pending = true;
      }
    }
    tn[x] &= ~(accepted[x] | dropped);
    todo_[li][x] &= ~(accepted[x] | dropped);
    known_[li][x] |= accepted[x];
  }
  fresh_out[li] = accepted;
  touched_out[li] = touched_neighbours(accepted);
  return pending;
}

void Wavefront::list_next_leaves(int iteration) {
  // Clear what the previous iteration (or the seeding) wrote into fresh_in, so that fresh_out
  // is all zero but for this iteration's leaves; then list the next leaves in index order.
  if (iteration == 0) {
    std::fill(fresh_[0].begin(), fresh_[0].end(), LeafBits{});
    std::fill(fresh_touched_[0].begin(), fresh_touched_[0].end(), 0u);
  } else {
    for (std::int32_t li : previous_) {
      fresh_[iteration & 1][std::size_t(li)] = LeafBits{};
      fresh_touched_[iteration & 1][std::size_t(li)] = 0u;
    }
  }
  previous_.swap(active_);
  active_.clear();
  for (std::size_t i = 0; i < n_; ++i) {
    if (next_mark_[i].load(std::memory_order_relaxed)) {
      next_mark_[i].store(0, std::memory_order_relaxed);
      if (any_bit(todo_[i])) active_.push_back(std::int32_t(i));
    }
  }
}

void Wavefront::finish() {
  refine_medial_voxels(table_, known_, seeds_, std::move(medial_), ids_->get(), tris_, h_);
  trim_exterior();
  const float exterior = exterior_voxels_ * h_;
  openvdb::tools::changeLevelSetBackground(sdf_.tree(), exterior);
  openvdb::tools::pruneLevelSet(sdf_.tree());
}

void Wavefront::trim_exterior() {
  // Outside, only the exterior band stays active (the voxels the front accepted below its
  // width); the background becomes that width.
  const float exterior = exterior_voxels_ * h_;
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, n_, 64),
      [&](const tbb::blocked_range<std::size_t>& range) {
        for (std::size_t i = range.begin(); i < range.end(); ++i) {
          // Without outside voxels to fill, a leaf holds seeds (|phi| below the seed band) and
          // inside voxels (negative): nothing to do.
          if (!any_bit(outside_[i])) continue;
          FloatLeaf& leaf = *table_.leaves[i];
          float* phi = table_.values[i];
          for (int pos = 0; pos < 512; ++pos) {
            const bool filled = outside_[i][pos >> 6] >> (pos & 63) & 1u;
            if (!(phi[pos] < exterior) || (filled && !(known_[i][pos >> 6] >> (pos & 63) & 1u))) {
              phi[pos] = exterior;
              leaf.setValueOff(pos);
            } else if (filled) {
              leaf.setValueOn(pos);
            }
          }
        }
      });
}

}  // namespace

void fill_by_wavefront(FloatGrid& sdf, const openvdb::Int32Grid& index_grid, const IndexMesh& m,
                       float exterior_voxels, const StageMonitor& monitor) {
  Wavefront front(sdf, m, exterior_voxels);
  front.seed(index_grid);
  front.run(monitor);
  front.finish();
}

}  // namespace fields_detail
}  // namespace vdb_shell
