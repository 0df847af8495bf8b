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
        t.neighbours[i][s] = acc.getValue(c.offsetBy(s / 9 - 1, s / 3 % 3 - 1, s % 3 - 1));
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
  refine_medial_voxels(table, known, seeds, std::move(medial), ids.get(), tris, h);
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
}  // namespace fields_detail
}  // namespace vdb_shell
