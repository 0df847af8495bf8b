// merges.cpp — merge resolution over a direction-binned grid of trace samples; see merges.h.
#include "core/trace/merges.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "core/base/grid_cell.h"
#include "core/base/parallel.h"

namespace vdb_shell {
namespace {

// Direction bins: a cube map with kFaceBins x kFaceBins bins per face, and one bin for samples
// without a direction (a single-sample trace).
constexpr int kFaceBins = 8;
constexpr int kDirectedBins = 6 * kFaceBins * kFaceBins;
constexpr std::uint32_t kUndirected = kDirectedBins;
constexpr int kBinBits = 9;  // kDirectedBins + 1 <= 2^kBinBits
constexpr int kAxisBits = 18;
constexpr std::int64_t kAxisCells = std::int64_t(1) << kAxisBits;
// Safety margin of the bins' angular bounds (radians): covers acos rounding and a sample that
// rounding placed in the bin next to its own.
constexpr double kAngleMargin = 1e-6;

/// Direction of trace v at its sample i (unit, or zero for a single-sample trace).
Vec3d sample_direction(const TraceResult& r, std::size_t v, std::size_t i) {
  const std::size_t n = r.num_samples(v);
  if (n < 2) return {};
  return i + 1 < n ? normalized(r.sample(v, i + 1) - r.sample(v, i))
                   : normalized(r.sample(v, i) - r.sample(v, i - 1));
}

/// The direction on the cube-map face `face` (axis face / 2, negative when odd) at face
/// coordinates (u, v) in [-1, 1]^2.
Vec3d face_direction(int face, double u, double v) {
  const double s = face % 2 ? -1.0 : 1.0;
  switch (face / 2) {
    case 0:
      return {s, u, v};
    case 1:
      return {v, s, u};
    default:
      return {u, v, s};
  }
}

std::uint32_t direction_bin(const Vec3d& d) {
  const double ax = std::fabs(d.x), ay = std::fabs(d.y), az = std::fabs(d.z);
  if (!(ax + ay + az > 0.0)) return kUndirected;
  int axis;
  double m, u, v;
  if (ax >= ay && ax >= az) {
    axis = 0, m = d.x, u = d.y, v = d.z;
  } else if (ay >= az) {
    axis = 1, m = d.y, u = d.z, v = d.x;
  } else {
    axis = 2, m = d.z, u = d.x, v = d.y;
  }
  const double s = 1.0 / std::fabs(m);
  auto cell = [](double t) {
    return std::clamp(static_cast<int>((t + 1.0) * 0.5 * kFaceBins), 0, kFaceBins - 1);
  };
  const int face = 2 * axis + (m < 0.0);
  return static_cast<std::uint32_t>((face * kFaceBins + cell(u * s)) * kFaceBins + cell(v * s));
}

/// A set of direction bins (the undirected one included).
struct BinMask {
  std::array<std::uint64_t, (kDirectedBins + 1 + 63) / 64> word{};
  void set(std::uint32_t bin) { word[bin / 64] |= std::uint64_t(1) << (bin % 64); }
  bool has(std::uint32_t bin) const { return (word[bin / 64] >> (bin % 64)) & 1u; }
  bool intersects(const BinMask& o) const {
    std::uint64_t any = 0;
    for (std::size_t i = 0; i < word.size(); ++i) any |= word[i] & o.word[i];
    return any != 0;
  }
  BinMask& operator|=(const BinMask& o) {
    for (std::size_t i = 0; i < word.size(); ++i) word[i] |= o.word[i];
    return *this;
  }
};

/// The bins' geometry, the same for every run: computed once.
struct BinGeometry {
  std::array<Vec3d, kDirectedBins> centre;
  /// Per bin: the largest angle between its centre and a direction in it (radians).
  std::array<double, kDirectedBins> radius;
  /// Per pair of bins: the largest angle between a direction of one and one of the other, at
  /// most pi (radians).
  std::vector<float> widest;  ///< [a * kDirectedBins + b], rounded up to float
};

const BinGeometry& bin_geometry() {
  static const BinGeometry geometry = [] {
    BinGeometry g;
    for (int face = 0; face < 6; ++face)
      for (int i = 0; i < kFaceBins; ++i)
        for (int j = 0; j < kFaceBins; ++j) {
          const int bin = (face * kFaceBins + i) * kFaceBins + j;
          auto at = [&](double a, double c) {
            return normalized(
                face_direction(face, -1.0 + 2.0 * a / kFaceBins, -1.0 + 2.0 * c / kFaceBins));
          };
          g.centre[bin] = at(i + 0.5, j + 0.5);
          // The directions within an angle of the centre meet the face in an ellipse (a convex
          // set), so the bin's farthest direction from its centre is one of its corners.
          g.radius[bin] = 0;
          for (int a = 0; a < 2; ++a)
            for (int c = 0; c < 2; ++c)
              g.radius[bin] =
                  std::max(g.radius[bin],
                           std::acos(std::clamp(dot(g.centre[bin], at(i + a, j + c)), -1.0, 1.0)));
        }
    g.widest.resize(std::size_t(kDirectedBins) * kDirectedBins);
    for (int a = 0; a < kDirectedBins; ++a)
      for (int b = 0; b < kDirectedBins; ++b) {
        const double widest = std::acos(std::clamp(dot(g.centre[a], g.centre[b]), -1.0, 1.0)) +
                              g.radius[a] + g.radius[b] + kAngleMargin;
        g.widest[std::size_t(a) * kDirectedBins + b] =
            std::nextafter(static_cast<float>(std::min(widest, kPi)), 4.0f);
      }
    return g;
  }();
  return geometry;
}

/// The bins against the merge angle.
struct Bins {
  /// Per directed bin: the cosine above which a direction's angle to the bin's centre guarantees
  /// that every direction of the bin lies within the merge angle of it (2: never).
  std::array<double, kDirectedBins> cos_skip;
  /// Per bin of a querying sample's direction: the bins holding a direction that may lie at the
  /// merge angle or more from some direction of it (all bins for the undirected one).
  std::array<BinMask, kDirectedBins + 1> may_merge;
};

Bins make_bins(double merge_angle) {
  const BinGeometry& g = bin_geometry();
  Bins b;
  for (int bin = 0; bin < kDirectedBins; ++bin) {
    const double budget = merge_angle - g.radius[bin] - kAngleMargin;
    b.cos_skip[bin] = budget > 0.0 ? std::cos(budget) : 2.0;
  }
  for (std::uint32_t q = 0; q <= kDirectedBins; ++q) {
    b.may_merge[q].set(kUndirected);
    for (std::uint32_t bin = 0; bin < kDirectedBins; ++bin) {
      // Every direction of bin q within the merge angle of every direction of `bin`.
      const bool same_way =
          q != kUndirected && double(g.widest[std::size_t(q) * kDirectedBins + bin]) < merge_angle;
      if (!same_way) b.may_merge[q].set(bin);
    }
  }
  return b;
}

/// One eligible sample in the grid. Sorted by key = (cell, bin), then sample.
struct Entry {
  std::uint64_t key;
  std::uint32_t sample;  ///< index into TraceResult::samples
  std::uint32_t trace;
  bool operator<(const Entry& o) const { return key != o.key ? key < o.key : sample < o.sample; }
};

/// The entries of one cell in one direction bin, and their bounding box.
struct Group {
  BBox box;
  std::uint32_t begin = 0;  ///< the group's entries are [begin, next group's begin)
  std::uint32_t bin = 0;
};

/// Open addressing from cell keys to dense indices (insertion order).
class CellTable {
 public:
  static constexpr std::uint32_t kNone = ~std::uint32_t(0);

  /// A table for up to `n` keys.
  explicit CellTable(std::size_t n = 0) {
    std::size_t slots = 16;
    while (slots < 2 * n) slots *= 2;
    mask_ = slots - 1;
    key_.assign(slots, kEmpty);
    index_.assign(slots, kNone);
  }
  /// The index of `key`, given the next free index if it is new.
  std::uint32_t insert(std::uint64_t key) {
    std::size_t s = slot_of(key);
    while (key_[s] != kEmpty && key_[s] != key) s = (s + 1) & mask_;
    if (key_[s] == kEmpty) {
      key_[s] = key;
      index_[s] = size_++;
    }
    return index_[s];
  }
  std::uint32_t find(std::uint64_t key) const {
    std::size_t s = slot_of(key);
    while (key_[s] != kEmpty && key_[s] != key) s = (s + 1) & mask_;
    return index_[s];  // kNone at an empty slot
  }
  std::uint32_t size() const { return size_; }

 private:
  static constexpr std::uint64_t kEmpty = ~std::uint64_t(0);
  std::size_t slot_of(std::uint64_t key) const {
    return static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ull) >> 20) & mask_;
  }
  std::size_t mask_ = 0;
  std::uint32_t size_ = 0;
  std::vector<std::uint64_t> key_;
  std::vector<std::uint32_t> index_;
};

/// Ascending keys (i << 2 * kAxisBits | j << kAxisBits | k) as rows along k: the keys of a row
/// (i, j) between two k.
class KeyRows {
 public:
  KeyRows() = default;
  explicit KeyRows(const std::vector<std::uint64_t>& keys) {
    for (std::size_t c = 0; c < keys.size(); ++c)
      if (c == 0 || (keys[c] >> kAxisBits) != (keys[c - 1] >> kAxisBits))
        begin_.push_back(static_cast<std::uint32_t>(c));
    begin_.push_back(static_cast<std::uint32_t>(keys.size()));
    rows_ = CellTable(begin_.size() - 1);
    for (std::size_t row = 0; row + 1 < begin_.size(); ++row)
      rows_.insert(keys[begin_[row]] >> kAxisBits);
    k_.resize(keys.size());
    for (std::size_t c = 0; c < keys.size(); ++c)
      k_[c] = static_cast<std::uint32_t>(keys[c] & (kAxisCells - 1));
  }
  /// The indices [first, last) of the keys (i, j, k) with k_lo <= k <= k_hi.
  std::pair<std::uint32_t, std::uint32_t> find(std::int64_t i, std::int64_t j, std::int64_t k_lo,
                                               std::int64_t k_hi) const {
    if (i < 0 || j < 0 || i >= kAxisCells || j >= kAxisCells) return {0, 0};
    const std::uint32_t row = rows_.find((std::uint64_t(i) << kAxisBits) | std::uint64_t(j));
    if (row == CellTable::kNone) return {0, 0};
    const std::uint32_t* end = k_.data() + begin_[row + 1];
    const std::uint32_t* first = std::lower_bound(
        k_.data() + begin_[row], end, static_cast<std::uint32_t>(std::max<std::int64_t>(k_lo, 0)));
    const std::uint32_t* last = first;
    while (last != end && std::int64_t(*last) <= k_hi) ++last;
    return {static_cast<std::uint32_t>(first - k_.data()),
            static_cast<std::uint32_t>(last - k_.data())};
  }

 private:
  CellTable rows_;                    ///< (i, j) of a row -> row
  std::vector<std::uint32_t> begin_;  ///< row r's keys: [begin_[r], begin_[r + 1])
  std::vector<std::uint32_t> k_;      ///< per key: its k
};

/// The eligible samples of some traces in cubic cells, each cell's samples grouped by direction
/// bin.
class SampleGrid {
 public:
  using Cell = GridCell;  // relative to the grid's corner (cell_of())

  SampleGrid(const TraceResult& r, const std::vector<std::uint32_t>& indexed,
             const std::vector<std::uint32_t>& eligible, double point_size) {
    std::vector<std::size_t> begin(indexed.size() + 1, 0);
    for (std::size_t w = 0; w < indexed.size(); ++w) begin[w + 1] = begin[w] + eligible[w];
    if (begin.back() == 0) return;
    // Cells from the lowest corner of the samples; wider than the point size only where the
    // extent needs more than kAxisBits of cell index.
    std::vector<BBox> trace_box(indexed.size());
    for_each_index(indexed.size(), [&](std::size_t w) {
      for (std::uint32_t m = 0; m < eligible[w]; ++m) trace_box[w].expand(r.sample(indexed[w], m));
    });
    BBox box;
    for (const BBox& b : trace_box)
      if (!b.empty()) {
        box.expand(b.lo);
        box.expand(b.hi);
      }
    origin_ = box.lo;
    extent_ = box.max_side();
    side_ = std::max(point_size, extent_ / double(kAxisCells - 4));
    if (!(side_ > 0.0)) side_ = 1.0;

    entries_.resize(begin.back());
    for_each_index(indexed.size(), [&](std::size_t w) {
      const std::uint32_t k = indexed[w];
      for (std::uint32_t m = 0; m < eligible[w]; ++m)
        entries_[begin[w] + m] = {(key_of(cell_of(r.sample(k, m))) << kBinBits) |
                                      direction_bin(sample_direction(r, k, m)),
                                  r.offsets[k] + m, k};
    });
    parallel_sort(entries_.begin(), entries_.end());
    local_.resize(entries_.size());
    for_each_index(entries_.size(),
                   [&](std::size_t e) { local_[e] = to_local(r.samples[entries_[e].sample]); });

    // Groups of equal (cell, bin), cells of equal cell key.
    std::vector<std::uint64_t> cell_keys;
    for (std::size_t e = 0; e < entries_.size(); ++e) {
      if (e > 0 && entries_[e].key == entries_[e - 1].key) continue;
      const std::uint64_t cell_key = entries_[e].key >> kBinBits;
      if (cell_keys.empty() || cell_keys.back() != cell_key) {
        cell_keys.push_back(cell_key);
        cell_groups_.push_back(static_cast<std::uint32_t>(groups_.size()));
      }
      Group g;
      g.begin = static_cast<std::uint32_t>(e);
      g.bin = static_cast<std::uint32_t>(entries_[e].key & ((1u << kBinBits) - 1));
      groups_.push_back(g);
    }
    cell_groups_.push_back(static_cast<std::uint32_t>(groups_.size()));
    groups_.emplace_back();
    groups_.back().begin = static_cast<std::uint32_t>(entries_.size());
    for_each_index(groups_.size() - 1, [&](std::size_t g) {
      for (std::uint32_t e = groups_[g].begin; e < groups_[g + 1].begin; ++e)
        groups_[g].box.expand(r.samples[entries_[e].sample]);
    });

    cells_ = KeyRows(cell_keys);
    own_bins_.resize(cell_keys.size());
    for_each_index(cell_keys.size(), [&](std::size_t c) {
      for (std::uint32_t g = cell_groups_[c]; g < cell_groups_[c + 1]; ++g)
        own_bins_[c].set(groups_[g].bin);
    });

    // Blocks of 2 x 2 x 2 cells in (i, j, k) order, in rows along k like the cells: the bins of
    // each block and of the 26 blocks around it.
    std::vector<std::pair<std::uint64_t, std::uint32_t>> cell_blocks(cell_keys.size());
    for_each_index(cell_keys.size(), [&](std::size_t c) {
      const Cell cell = cell_of_key(cell_keys[c]);
      cell_blocks[c] = {key_of({cell.i / 2, cell.j / 2, cell.k / 2}),
                        static_cast<std::uint32_t>(c)};
    });
    parallel_sort(cell_blocks.begin(), cell_blocks.end());
    std::vector<std::uint32_t> block_cells;  // block b's cells: [block_cells[b], [b + 1])
    std::vector<std::uint64_t> block_keys;
    for (std::size_t e = 0; e < cell_blocks.size(); ++e)
      if (e == 0 || cell_blocks[e].first != cell_blocks[e - 1].first) {
        block_cells.push_back(static_cast<std::uint32_t>(e));
        block_keys.push_back(cell_blocks[e].first);
      }
    block_cells.push_back(static_cast<std::uint32_t>(cell_blocks.size()));
    blocks_ = KeyRows(block_keys);
    block_bins_.resize(block_keys.size());
    for_each_index(block_keys.size(), [&](std::size_t b) {
      for (std::uint32_t e = block_cells[b]; e < block_cells[b + 1]; ++e)
        block_bins_[b] |= own_bins_[cell_blocks[e].second];
    });
    near_block_bins_.resize(block_keys.size());
    for_each_index(block_keys.size(), [&](std::size_t b) {
      near_block_bins_[b] = bins_around(cell_of_key(block_keys[b]));
    });
  }

  bool empty() const { return entries_.empty(); }
  const Entry& entry(std::uint32_t e) const { return entries_[e]; }

  /// A position relative to the grid's corner in single precision (within a few units in the
  /// last place of the extent of the exact difference), for a first cheap distance test.
  struct Local {
    float x, y, z;
  };
  Local to_local(const Vec3d& p) const {
    return {static_cast<float>(p.x - origin_.x), static_cast<float>(p.y - origin_.y),
            static_cast<float>(p.z - origin_.z)};
  }
  const Local& local(std::uint32_t e) const { return local_[e]; }
  /// A squared radius for Local positions that keeps every pair of points within `radius`:
  /// the rounding of the coordinates (half a unit in the last place of the extent each) and of
  /// the sum of squares, with room to spare.
  float local_radius2(double radius) const {
    const double slack = 8.0 * extent_ * std::ldexp(1.0, -24);
    return static_cast<float>((radius + slack) * (radius + slack) * (1.0 + 1e-5));
  }

  /// The bins of the samples in the block of 2 x 2 x 2 cells holding `p` and in the 26 blocks
  /// around it: every sample within the cell side of `p` has one of them. `last` keeps the
  /// answer for the block asked about last (consecutive samples of a trace mostly share one).
  struct NearBins {
    Cell block{-2, -2, -2};
    BinMask bins;
  };
  const BinMask& bins_near(const Vec3d& p, NearBins& last) const {
    const Cell c = cell_of(p);
    auto half = [](std::int64_t i) { return i >= 0 ? i / 2 : -1; };
    const Cell block{half(c.i), half(c.j), half(c.k)};
    if (block == last.block) return last.bins;
    last.block = block;
    // A block without samples of its own has no precomputed answer.
    const auto [first, end] = blocks_.find(block.i, block.j, block.k, block.k);
    last.bins = first != end ? near_block_bins_[first] : bins_around(block);
    return last.bins;
  }

  /// Calls visit(group, end of its entries) for every group of the cells within `radius` (at most
  /// the cell side) of `p` whose bin `bins` holds.
  template <class Visit>
  void for_each_group(const Vec3d& p, double radius, const BinMask& bins,
                      const Visit& visit) const {
    const Cell lo = cell_of(p - Vec3d(radius, radius, radius));
    const Cell hi = cell_of(p + Vec3d(radius, radius, radius));
    for (std::int64_t i = lo.i; i <= hi.i; ++i)
      for (std::int64_t j = lo.j; j <= hi.j; ++j) {
        const auto [first, last] = cells_.find(i, j, lo.k, hi.k);
        for (std::uint32_t id = first; id < last; ++id) {
          if (!own_bins_[id].intersects(bins)) continue;
          for (std::uint32_t g = cell_groups_[id]; g < cell_groups_[id + 1]; ++g)
            if (bins.has(groups_[g].bin)) visit(groups_[g], groups_[g + 1].begin);
        }
      }
  }

 private:
  /// The cell holding `p`, clamped to one cell beyond the grid on each side (points there or
  /// farther have no samples near them).
  Cell cell_of(const Vec3d& p) const {
    auto axis = [&](int d) {
      const double t = std::floor((p[d] - origin_[d]) / side_);
      return static_cast<std::int64_t>(std::clamp(t, -1.0, double(kAxisCells)));
    };
    return {axis(0), axis(1), axis(2)};
  }
  static std::uint64_t key_of(const Cell& c) {
    return (std::uint64_t(c.i) << (2 * kAxisBits)) | (std::uint64_t(c.j) << kAxisBits) |
           std::uint64_t(c.k);
  }
  /// The bins of the blocks within one block of `block` (block coordinates).
  BinMask bins_around(const Cell& block) const {
    BinMask bins;
    for (std::int64_t i = block.i - 1; i <= block.i + 1; ++i)
      for (std::int64_t j = block.j - 1; j <= block.j + 1; ++j) {
        const auto [first, last] = blocks_.find(i, j, block.k - 1, block.k + 1);
        for (std::uint32_t b = first; b < last; ++b) bins |= block_bins_[b];
      }
    return bins;
  }
  static Cell cell_of_key(std::uint64_t key) {
    return {static_cast<std::int64_t>(key >> (2 * kAxisBits)),
            static_cast<std::int64_t>((key >> kAxisBits) & (kAxisCells - 1)),
            static_cast<std::int64_t>(key & (kAxisCells - 1))};
  }

  Vec3d origin_;
  double extent_ = 0;  ///< largest side of the samples' bounding box
  double side_ = 1.0;
  std::vector<Entry> entries_;
  std::vector<Local> local_;                ///< per entry
  std::vector<Group> groups_;               ///< ascending (cell, bin); one more marks the end
  std::vector<std::uint32_t> cell_groups_;  ///< cell c's groups: [cell_groups_[c], [c + 1])
  std::vector<BinMask> own_bins_;           ///< per cell: the bins of its groups
  KeyRows cells_;                           ///< the cells' keys in rows along k
  KeyRows blocks_;  ///< the keys of the blocks of 2 x 2 x 2 cells (i / 2, j / 2, k / 2)
  std::vector<BinMask> block_bins_;       ///< per block: the bins of its cells
  std::vector<BinMask> near_block_bins_;  ///< per block: the bins of it and its 26 neighbours
};

/// The sample of trace j from its sample i on, within `ps` of arc past it, nearest to `target`
/// (the first of equals): where a trace that came within the point size of its partner's sample
/// at sample i passes it. Straight on towards it, it gets there within `ps`.
std::uint32_t closest_approach(const TraceResult& r, std::uint32_t j, std::uint32_t i,
                               const Vec3d& target, double ps) {
  const std::size_t first = r.offsets[j];
  std::uint32_t best = i;
  double best_d2 = norm2(r.samples[first + i] - target);
  for (std::uint32_t m = i + 1;
       m <= r.end[j] && r.arc_length[first + m] - r.arc_length[first + i] <= ps; ++m) {
    const double d2 = norm2(r.samples[first + m] - target);
    if (d2 < best_d2) {
      best_d2 = d2;
      best = m;
    }
  }
  return best;
}

}  // namespace

void resolve_merges(TraceResult& r, const std::vector<std::uint32_t>& which,
                    const std::vector<std::uint32_t>& indexed) {
  const double ps = r.parameters.point_size;
  const double ps2 = ps * ps;
  const double cos_merge = r.parameters.cos_merge;
  const Bins bins = make_bins(std::acos(std::clamp(cos_merge, -1.0, 1.0)));

  // Arc length grows along a trace, so the eligible samples are a prefix.
  std::vector<std::uint32_t> eligible(indexed.size());
  for_each_index(indexed.size(), [&](std::size_t w) {
    const std::uint32_t k = indexed[w];
    std::uint32_t m = 0;
    while (m <= r.end[k] && !(r.end_arc(k) - r.arc_length[r.offsets[k] + m] < 2.0 * ps)) ++m;
    eligible[w] = m;
  });
  const SampleGrid grid(r, indexed, eligible, ps);
  if (grid.empty()) return;
  const float ps2_local = grid.local_radius2(ps);

  std::vector<std::uint32_t> new_end(which.size());
  std::vector<std::int64_t> partner(which.size(), -1);
  struct NearGroup {
    double gap2;
    std::uint32_t begin, end;  ///< entries
    bool operator<(const NearGroup& o) const {
      return gap2 != o.gap2 ? gap2 < o.gap2 : begin < o.begin;
    }
  };
  for_each_chunk(which.size(), [&](std::size_t begin, std::size_t end) {
    SampleGrid::NearBins near;
    std::vector<NearGroup> near_groups;
    for (std::size_t w = begin; w < end; ++w) {
      const std::uint32_t j = which[w];
      new_end[w] = r.end[j];
      const Vec3d& pj = r.sample(j, 0);
      for (std::uint32_t i = 0; i <= r.end[j] && partner[w] < 0; ++i) {
        const Vec3d& q = r.sample(j, i);
        const Vec3d dir = sample_direction(r, j, i);
        // The bins that may hold a sample this one can merge with, and are found near it.
        const BinMask& may_merge = bins.may_merge[direction_bin(dir)];
        if (!grid.bins_near(q, near).intersects(may_merge)) continue;
        const bool directed = norm2(dir) > 0.0;
        double best = std::numeric_limits<double>::infinity();
        std::uint32_t best_sample = 0;
        // Local positions farther apart than this are farther than `best` (and ps) exactly too:
        // they are passed over without reading their sample.
        float reach2_local = ps2_local;
        const SampleGrid::Local ql = grid.to_local(q);
        // The groups that may hold a partner, nearest box first: once a partner is found,
        // groups farther than it are not read.
        near_groups.clear();
        grid.for_each_group(q, ps, may_merge, [&](const Group& g, std::uint32_t group_end) {
          // Every direction of the bin within the merge angle of this sample's.
          if (g.bin != kUndirected && directed &&
              dot(dir, bin_geometry().centre[g.bin]) > bins.cos_skip[g.bin])
            return;
          double gap2 = 0;  // squared distance from q to the group's box
          for (int a = 0; a < 3; ++a) {
            const double t = g.box.lo[a] > q[a]   ? g.box.lo[a] - q[a]
                             : q[a] > g.box.hi[a] ? q[a] - g.box.hi[a]
                                                  : 0;
            gap2 += t * t;
          }
          if (gap2 <= ps2) near_groups.push_back({gap2, g.begin, group_end});
        });
        std::sort(near_groups.begin(), near_groups.end());
        for (const NearGroup& g : near_groups) {
          // Rounding slack: a sample at exactly `best` must still be read (ties).
          if (partner[w] >= 0 && std::sqrt(g.gap2) > best * (1.0 + 1e-12)) break;
          for (std::uint32_t e = g.begin; e < g.end; ++e) {
            const SampleGrid::Local& l = grid.local(e);
            const float dx = l.x - ql.x, dy = l.y - ql.y, dz = l.z - ql.z;
            if (dx * dx + dy * dy + dz * dz > reach2_local) continue;
            const Entry& entry = grid.entry(e);
            const Vec3d& s = r.samples[entry.sample];
            const double d2 = norm2(s - q);
            if (d2 > ps2) continue;
            const double d = std::sqrt(d2);  // distance(q, s), bit for bit
            // Ties go to the smallest (trace, sample): the order of the samples' indices.
            if (d > best || (d == best && entry.sample > best_sample)) continue;
            const std::uint32_t k = entry.trace;
            if (k == j) continue;
            if (dot(dir, sample_direction(r, k, entry.sample - r.offsets[k])) > cos_merge) continue;
            if (distance(pj, r.sample(k, 0)) < ps) continue;  // started side by side
            best = d;
            best_sample = entry.sample;
            partner[w] = k;
            reach2_local = std::min(ps2_local, grid.local_radius2(best));
          }
        }
        if (partner[w] >= 0) new_end[w] = closest_approach(r, j, i, r.samples[best_sample], ps);
      }
    }
  });
  for (std::size_t w = 0; w < which.size(); ++w) {
    if (partner[w] < 0) continue;
    const std::uint32_t j = which[w];
    r.end[j] = new_end[w];
    r.stop[j] = StopReason::kMerge;
    r.merged_with[j] = partner[w];
  }
}

}  // namespace vdb_shell
