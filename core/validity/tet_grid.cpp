// tet_grid.cpp — see tet_grid.h.
#include "core/validity/tet_grid.h"

#include <array>
#include <cfloat>
#include <cmath>
#include <utility>

#include "core/base/index_lists.h"
#include "core/base/parallel.h"

namespace vdb_shell {

namespace {

// The largest float not above x, and the smallest not below it.
float float_below(double x) {
  const float f = static_cast<float>(x);
  return static_cast<double>(f) > x ? std::nextafter(f, -INFINITY) : f;
}
float float_above(double x) {
  const float f = static_cast<float>(x);
  return static_cast<double>(f) < x ? std::nextafter(f, INFINITY) : f;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// TetGrid

TetGrid::TetGrid(const BBox& box, double cell_size)
    : box_(box), cell_(cell_size), inv_cell_(1.0 / cell_size) {
  for (int a = 0; a < 3; ++a)
    dims_[a] = std::max(1L, static_cast<long>(std::ceil((box_.hi[a] - box_.lo[a]) * inv_cell_)));
}

bool TetGrid::contains(const BBox& b) const {
  return b.lo.x >= box_.lo.x && b.lo.y >= box_.lo.y && b.lo.z >= box_.lo.z && b.hi.x <= box_.hi.x &&
         b.hi.y <= box_.hi.y && b.hi.z <= box_.hi.z;
}

std::size_t TetGrid::cells_of(const TetGeometry& g, std::uint32_t* out) const {
  // The slabs in world coordinates (g's extents are relative to its first corner), widened by
  // what that rounds: the cell test stays conservative.
  const Vec3d& o = g.p[0];
  const double rounding = 1e-15 * (std::abs(o.x) + std::abs(o.y) + std::abs(o.z));
  std::array<Slab, 4> slabs;
  for (int f = 0; f < 4; ++f) {
    const double at = dot(g.n[f], o);
    slabs[f] = {g.n[f], g.lo[f] + at - rounding, g.hi[f] + at + rounding};
  }
  return cells_in(g.box, slabs, out);
}

std::size_t TetGrid::cells_of_triangle(const std::array<Vec3d, 3>& t, std::uint32_t* out) const {
  BBox box;
  for (const Vec3d& p : t) box.expand(p);
  const Vec3d n = normalized(cross(t[1] - t[0], t[2] - t[0]));
  const double plane = dot(n, t[0]);
  return cells_in(box, std::array<Slab, 1>{Slab{n, plane, plane}}, out);
}

std::size_t TetGrid::box_cells(const BBox& b) const {
  std::size_t count = 1;
  for (int a = 0; a < 3; ++a)
    count *= static_cast<std::size_t>(cell_of(b.hi[a], a) - cell_of(b.lo[a], a) + 1);
  return count;
}

std::size_t TetGrid::num_cells() const {
  return static_cast<std::size_t>(dims_[0]) * static_cast<std::size_t>(dims_[1]) *
         static_cast<std::size_t>(dims_[2]);
}

template <std::size_t N>
std::size_t TetGrid::cells_in(const BBox& box, const std::array<Slab, N>& slabs,
                              std::uint32_t* out) const {
  long lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
  for (int a = 0; a < 3; ++a) {
    lo[a] = cell_of(box.lo[a], a);
    hi[a] = cell_of(box.hi[a], a);
  }
  // A cell is kept when, for every slab, its centre c has lo - reach <= dot(n, c) <= hi + reach
  // (reach: the cell's half extent along n). Along a column (i, j) that bounds the centres' z, so
  // the kept cells of a column are one run of k, found from the slabs alone. Each slab's run is
  // widened by margin[f] cells, far more than its arithmetic rounds (relative to the magnitude
  // of the coordinates, divided by n.z), so that it holds every cell the test would keep.
  double magnitude = 0.0;
  for (int a = 0; a < 3; ++a)
    magnitude += std::max({std::abs(box_.lo[a]), std::abs(box.lo[a]), std::abs(box.hi[a])});
  std::array<double, N> reach, inv_nz, margin;
  for (std::size_t f = 0; f < N; ++f) {
    const Vec3d& n = slabs[f].n;
    reach[f] = 0.5 * cell_ * (std::abs(n.x) + std::abs(n.y) + std::abs(n.z));
    inv_nz[f] = n.z != 0.0 ? 1.0 / n.z : 0.0;
    margin[f] = 1e-9 + 1e-13 * (magnitude + std::abs(slabs[f].lo) + std::abs(slabs[f].hi)) *
                           std::abs(inv_nz[f]) * inv_cell_;
  }
  std::size_t count = 0;
  for (long i = lo[0]; i <= hi[0]; ++i) {
    const double x = box_.lo.x + (static_cast<double>(i) + 0.5) * cell_;
    for (long j = lo[1]; j <= hi[1]; ++j) {
      const double y = box_.lo.y + (static_cast<double>(j) + 0.5) * cell_;
      // The run's ends as cell coordinates (k + 0.5 at a centre), from every slab.
      double k_lo = static_cast<double>(lo[2]), k_hi = static_cast<double>(hi[2]);
      for (std::size_t f = 0; f < N && k_lo <= k_hi; ++f) {
        const Slab& s = slabs[f];
        const double across = s.n.x * x + s.n.y * y;
        const double z_lo = s.lo - reach[f] - across, z_hi = s.hi + reach[f] - across;
        if (s.n.z == 0.0) {
          if (z_lo > 0.0 || z_hi < 0.0) k_hi = k_lo - 1.0;
          continue;
        }
        const double a = (z_lo * inv_nz[f] - box_.lo.z) * inv_cell_ - 0.5,
                     b = (z_hi * inv_nz[f] - box_.lo.z) * inv_cell_ - 0.5;  // either order
        k_lo = std::max(k_lo, std::ceil(std::min(a, b) - margin[f]));
        k_hi = std::min(k_hi, std::floor(std::max(a, b) + margin[f]));
      }
      if (!(k_lo <= k_hi)) continue;
      const long first = static_cast<long>(k_lo), last = static_cast<long>(k_hi);
      for (long k = first; k <= last; ++k) {
        if (out) out[count] = static_cast<std::uint32_t>((i * dims_[1] + j) * dims_[2] + k);
        ++count;
      }
    }
  }
  return count;
}

long TetGrid::cell_of(double x, int axis) const {
  return std::clamp(static_cast<long>(std::floor((x - box_.lo[axis]) * inv_cell_)), 0L,
                    dims_[axis] - 1);
}

BBox bounding_box_of(const TetGeometries& geo) {
  return reduce_in_blocks(
      geo.size(), BBox{}, [&](std::size_t t) -> const BBox& { return geo[t].box; },
      [](BBox all, const BBox& b) {
        if (!b.empty()) {
          all.expand(b.lo);
          all.expand(b.hi);
        }
        return all;
      });
}

double grid_cell_size(const TetGeometries& geo, const BBox& all) {
  // The tets' count, total volume and total mean side (boxes not empty).
  const std::array<double, 3> sums = reduce_in_blocks(
      geo.size(), std::array<double, 3>{0.0, 0.0, 0.0},
      [&](std::size_t t) {
        const TetGeometry& g = geo[t];
        if (g.box.empty()) return std::array<double, 3>{0.0, 0.0, 0.0};
        const Vec3d e = g.box.extent();
        return std::array<double, 3>{1.0, std::abs(tet_volume(g.p[0], g.p[1], g.p[2], g.p[3])),
                                     (e.x + e.y + e.z) / 3.0};
      },
      [](std::array<double, 3> a, const std::array<double, 3>& b) {
        for (int k = 0; k < 3; ++k) a[k] += b[k];
        return a;
      });
  const double n = sums[0];
  const double mean_volume = n > 0.0 ? sums[1] / n : 0.0, mean_side = n > 0.0 ? sums[2] / n : 0.0;
  double h = std::max(3.0 * std::cbrt(mean_volume), mean_side / 4.0);
  if (!(h > 0.0)) h = all.max_side() > 0.0 ? all.max_side() : 1.0;
  const Vec3d ext = all.extent();
  // The mean count of cells a tet enters, over every stride-th tet.
  const std::size_t stride = std::max<std::size_t>(1, geo.size() / 4096);
  const auto mean_cells = [&](double side) {
    const TetGrid grid(all, side);
    double sum = 0.0, count = 0.0;
    for (std::size_t t = 0; t < geo.size(); t += stride)
      if (!geo[t].box.empty()) {
        sum += static_cast<double>(grid.cells_of(geo[t], nullptr));
        ++count;
      }
    return count > 0.0 ? sum / count : 0.0;
  };
  for (int round = 0; round < 200; ++round) {
    const double cells =
        std::ceil(ext.x / h + 1e-9) * std::ceil(ext.y / h + 1e-9) * std::ceil(ext.z / h + 1e-9);
    const double columns = reduce_in_blocks(
        geo.size(), 0.0,
        [&](std::size_t t) {
          const BBox& b = geo[t].box;
          if (b.empty()) return 0.0;
          const Vec3d e = b.extent();
          return (std::floor(e.x / h) + 2.0) * (std::floor(e.y / h) + 2.0);
        },
        [](double a, double b) { return a + b; });
    if (cells <= 32.0 * n + 64.0 && columns <= 64.0 * n && mean_cells(h) <= 64.0) break;
    h *= 1.25;
  }
  return h;
}

// ---------------------------------------------------------------------------------------------
// PooledLists

void PooledLists::assign(std::vector<std::uint64_t> start, std::vector<std::uint32_t> values) {
  const std::size_t slots = start.size() - 1;
  size_.resize(slots);
  for (std::size_t s = 0; s < slots; ++s)
    size_[s] = static_cast<std::uint32_t>(start[s + 1] - start[s]);
  start.pop_back();
  begin_ = std::move(start);
  pool_ = std::move(values);
  unused_ = 0;
}

std::uint64_t PooledLists::relocate(std::size_t s, std::size_t count) {
  unused_ += size_[s];
  const std::uint64_t at = pool_.size();
  pool_.resize(pool_.size() + count);
  begin_[s] = at;
  size_[s] = static_cast<std::uint32_t>(count);
  return at;
}

void PooledLists::set(std::size_t s, const std::uint32_t* first, std::size_t count) {
  if (count <= size_[s]) {
    unused_ += size_[s] - count;
    size_[s] = static_cast<std::uint32_t>(count);
  } else {
    relocate(s, count);
  }
  std::copy(first, first + count, pool_.begin() + static_cast<std::ptrdiff_t>(begin_[s]));
  compact_if_sparse();
}

void PooledLists::merge_sorted(std::size_t s, const std::uint32_t* first, std::size_t count) {
  if (count == 0) return;
  const std::uint64_t from = begin_[s];
  const std::size_t n = size_[s];
  const std::uint64_t to = relocate(s, n + count);  // pool_ may move: indices only
  std::size_t a = 0, b = 0, k = 0;
  while (a < n && b < count)
    pool_[to + k++] = pool_[from + a] < first[b] ? pool_[from + a++] : first[b++];
  while (a < n) pool_[to + k++] = pool_[from + a++];
  while (b < count) pool_[to + k++] = first[b++];
  compact_if_sparse();
}

void PooledLists::erase_flagged(std::size_t s, const std::vector<std::uint8_t>& drop) {
  const auto first = pool_.begin() + static_cast<std::ptrdiff_t>(begin_[s]);
  const auto last = first + size_[s];
  const auto kept = std::remove_if(first, last, [&](std::uint32_t v) { return drop[v] != 0; });
  const auto removed = static_cast<std::size_t>(last - kept);
  size_[s] -= static_cast<std::uint32_t>(removed);
  unused_ += removed;
}

void PooledLists::compact_if_sparse() {
  if (unused_ <= 1024 || 2 * unused_ <= pool_.size()) return;
  std::vector<std::uint32_t> pool;
  pool.reserve(pool_.size() - unused_);
  for (std::size_t s = 0; s < size_.size(); ++s) {
    const std::uint64_t at = pool.size();
    pool.insert(pool.end(), begin(s), end(s));
    begin_[s] = at;
  }
  pool_ = std::move(pool);
  unused_ = 0;
}

// ---------------------------------------------------------------------------------------------
// BroadPhase

namespace {

// The cells of items [0, n): item i's are cells[start[i], start[i + 1]). cells_of(i, out)
// writes them to `out`, which has room for bound(i) of them, and returns how many. Blocks of
// items fill buffers of their own in parallel, joined in item order.
template <class Bound, class CellsOf>
std::vector<std::uint32_t> collect_cells(std::size_t n, const Bound& bound, const CellsOf& cells_of,
                                         std::vector<std::uint64_t>& start) {
  std::vector<std::uint32_t> cells;
  lists_in_blocks(
      n, 128,
      [&](std::size_t i, std::vector<std::uint32_t>& out) {
        const std::size_t at = out.size();
        out.resize(at + bound(i));
        out.resize(at + cells_of(i, out.data() + at));
      },
      start, cells);
  return cells;
}

// Slots of groups by a Z-order curve through the centres of their boxes (`boxes`, one per group)
// in `box`: per group its slot (`slot`) and per slot its group (`group`). Ties (and empty boxes)
// in group order.
void z_order(const std::vector<BBox>& boxes, const BBox& box, std::vector<std::uint32_t>& slot,
             std::vector<std::uint32_t>& group) {
  const auto n = static_cast<std::uint32_t>(boxes.size());
  // Spreads the 21 low bits of x to every third bit.
  const auto spread = [](std::uint64_t x) {
    x &= 0x1fffff;
    x = (x | x << 32) & 0x1f00000000ffffULL;
    x = (x | x << 16) & 0x1f0000ff0000ffULL;
    x = (x | x << 8) & 0x100f00f00f00f00fULL;
    x = (x | x << 4) & 0x10c30c30c30c30c3ULL;
    x = (x | x << 2) & 0x1249249249249249ULL;
    return x;
  };
  const double scale = box.max_side() > 0.0 ? 2097151.0 / box.max_side() : 0.0;
  std::vector<std::pair<std::uint64_t, std::uint32_t>> order(n);  // (code, group)
  for_each_index(n, [&](std::size_t k) {
    order[k] = {0, static_cast<std::uint32_t>(k)};
    if (boxes[k].empty()) return;
    const Vec3d c = (boxes[k].lo + boxes[k].hi) * 0.5 - box.lo;
    std::uint64_t q[3];
    for (int a = 0; a < 3; ++a)
      q[a] = static_cast<std::uint64_t>(std::clamp(c[a] * scale, 0.0, 2097151.0));
    order[k].first = spread(q[0]) | spread(q[1]) << 1 | spread(q[2]) << 2;
  });
  parallel_sort(order.begin(), order.end());
  group.resize(n);
  slot.resize(n);
  for (std::uint32_t s = 0; s < n; ++s) {
    group[s] = order[s].second;
    slot[group[s]] = s;
  }
}

}  // namespace

BroadPhase::BroadPhase(const SurfaceMesh& surface, const BBox& box, double cell_size,
                       TetGeometries geometry, bool enter_triangles, std::uint32_t group_size)
    : surface_(surface),
      grid_(box, cell_size),
      group_(std::max<std::uint32_t>(1, group_size)),
      key_count_(geometry.size()),
      cell_slots_(grid_.num_cells()) {
  const std::size_t groups = (key_count_ + group_ - 1) / group_;
  std::vector<BBox> boxes(groups);
  for_each_index(groups, [&](std::size_t s) {
    for (std::size_t k = s * group_; k < std::min(key_count_, (s + 1) * group_); ++k)
      if (!geometry[k].box.empty()) {
        boxes[s].expand(geometry[k].box.lo);
        boxes[s].expand(geometry[k].box.hi);
      }
  });
  z_order(boxes, box, slot_, key_);
  geo_.resize(groups * group_);  // each set below; the missing keys of the last group: empty
  for_each_index(geo_.size(), [&](std::size_t k) {
    geo_[index(static_cast<std::uint32_t>(k))] = k < key_count_ ? geometry[k] : TetGeometry{};
  });
  box_.resize(geo_.size());
  present_.assign(geo_.size(), 0);
  slot_box_.resize(groups);
  slot_bounds_.resize(groups);
  corners_.resize(geo_.size() * 4);
  corner_count_.assign(groups, 0);
  state_.assign(groups, kAbsent);
  slot_cells_ = PooledLists(groups);
  if (enter_triangles) this->enter_triangles();
}

void BroadPhase::enter_triangles() {
  const std::size_t n_faces = surface_.triangles.size();
  std::vector<std::uint64_t> start;
  std::vector<BBox> boxes(n_faces);
  for_each_index(n_faces, [&](std::size_t f) {
    for (const Vec3d& p : triangle_corners(surface_, f)) boxes[f].expand(p);
  });
  const auto meets_grid = [&](std::size_t f) { return boxes_overlap(boxes[f], grid_.box()); };
  const std::vector<std::uint32_t> cells = collect_cells(
      n_faces, [&](std::size_t f) { return meets_grid(f) ? grid_.box_cells(boxes[f]) : 0; },
      [&](std::size_t f, std::uint32_t* out) -> std::size_t {
        // A triangle outside the grid's box meets no tet in the grid.
        return meets_grid(f) ? grid_.cells_of_triangle(triangle_corners(surface_, f), out) : 0;
      },
      start);
  invert_lists(
      n_faces,
      [&](std::size_t f) {
        return std::pair{cells.data() + start[f], cells.data() + start[f + 1]};
      },
      grid_.num_cells(), triangle_start_, triangle_items_);
}

void BroadPhase::set_geometry(std::uint32_t key, const TetGeometry& g) { geo_[index(key)] = g; }

std::vector<std::uint32_t> BroadPhase::slots_of(const std::vector<std::uint32_t>& keys) const {
  std::vector<std::uint32_t> slots;
  if (keys.size() * 16 >= key_.size()) {  // many: marked, then read in slot order
    std::vector<std::uint8_t> marked(key_.size(), 0);
    for (const std::uint32_t key : keys) marked[slot_[key / group_]] = 1;
    for (std::uint32_t s = 0; s < marked.size(); ++s)
      if (marked[s]) slots.push_back(s);
    return slots;
  }
  slots.resize(keys.size());
  for (std::size_t i = 0; i < keys.size(); ++i) slots[i] = slot_[keys[i] / group_];
  std::sort(slots.begin(), slots.end());
  slots.erase(std::unique(slots.begin(), slots.end()), slots.end());
  return slots;
}

void BroadPhase::insert(const std::vector<std::uint32_t>& keys) {
  const bool was_empty = size_ == 0;  // then no group is in the grid
  for (const std::uint32_t key : keys) {
    const std::uint32_t i = index(key);
    present_[i] = 1;
    box_[i] = geo_[i].box;
  }
  size_ += keys.size();
  reenter(slots_of(keys), was_empty);
}

void BroadPhase::remove(const std::vector<std::uint32_t>& keys) {
  std::vector<std::uint32_t> gone;
  for (const std::uint32_t key : keys) {
    const std::uint32_t i = index(key);
    if (!present_[i]) continue;
    present_[i] = 0;
    box_[i] = BBox{};
    gone.push_back(key);
    --size_;
  }
  reenter(slots_of(gone), false);
}

void BroadPhase::rebuild_cell_slots() {
  std::vector<std::uint64_t> start;
  std::vector<std::uint32_t> items;
  invert_lists(
      state_.size(),
      [&](std::size_t s) {
        return std::pair{slot_cells_.begin(s), slot_cells_.end(s)};
      },
      grid_.num_cells(), start, items);
  cell_slots_.assign(std::move(start), std::move(items));
}

void BroadPhase::reenter(const std::vector<std::uint32_t>& slots, bool was_empty) {
  // When many groups move, editing their cells' lists one by one costs more than building every
  // list again from the groups' own lists, which is done then.
  const bool rebuild = !was_empty && slots.size() * kRebuildShare >= state_.size();
  // Out of the grid: the cells they were in lose them, each cell's list edited once.
  if (!was_empty) {
    std::vector<std::uint8_t> drop(state_.size(), 0);
    std::vector<std::uint32_t> cells;
    bool stray = false;
    for (const std::uint32_t slot : slots) {
      if (state_[slot] == kAbsent) continue;
      drop[slot] = 1;
      if (state_[slot] == kStray) {
        stray = true;
      } else {
        if (!rebuild) cells.insert(cells.end(), slot_cells_.begin(slot), slot_cells_.end(slot));
        slot_cells_.set(slot, nullptr, 0);
      }
      state_[slot] = kAbsent;
    }
    if (stray)
      stray_slots_.erase(std::remove_if(stray_slots_.begin(), stray_slots_.end(),
                                        [&](std::uint32_t s) { return drop[s] != 0; }),
                         stray_slots_.end());
    if (!rebuild) {
      parallel_sort(cells.begin(), cells.end());  // equal cells are the same value
      cells.erase(std::unique(cells.begin(), cells.end()), cells.end());
      for (const std::uint32_t c : cells) cell_slots_.erase_flagged(c, drop);
    }
  }
  // Back in, with the cells of their present tets.
  const std::size_t n = slots.size();
  std::vector<std::uint8_t> stray(n, 0);
  for_each_index(n, [&](std::size_t i) {
    const std::uint32_t s = slots[i];
    BBox b;
    Vec3d* corners = corners_.data() + std::size_t{4} * group_ * s;
    std::uint32_t count = 0;
    for (std::uint32_t j = s * group_; j < (s + 1) * group_; ++j)
      if (present_[j]) {
        b.expand(box_[j].lo);
        b.expand(box_[j].hi);
        if (!grid_.contains(box_[j])) stray[i] = 1;
        for (const Vec3d& p : geo_[j].p) corners[count++] = p;
      }
    const auto lexicographic = [](const Vec3d& a, const Vec3d& b) {
      return a.x != b.x ? a.x < b.x : a.y != b.y ? a.y < b.y : a.z < b.z;
    };
    std::sort(corners, corners + count, lexicographic);
    count = static_cast<std::uint32_t>(std::unique(corners, corners + count) - corners);
    slot_box_[s] = b;
    corner_count_[s] = count;
    // Relative to the grid's corner: subtracting one origin from every value keeps their order,
    // and the floats keep the precision of the grid's scale wherever it lies.
    const Vec3d& o = grid_.box().lo;
    double lo[7], hi[7];
    for (int a = 0; a < 3; ++a) lo[a] = b.lo[a] - o[a], hi[a] = b.hi[a] - o[a];
    for (int k = 3; k < 7; ++k) lo[k] = INFINITY, hi[k] = -INFINITY;
    for (std::uint32_t c = 0; c < count; ++c) {
      const Vec3d q = corners[c] - o;
      const double along[4] = {q.x + q.y + q.z, q.x + q.y - q.z, q.x - q.y + q.z, -q.x + q.y + q.z};
      // Widened by more than the sums' and the subtraction's rounding: far from the origin the
      // extents still hold the corners, and groups they find apart are apart.
      const double e = 4 * DBL_EPSILON * (std::abs(q.x) + std::abs(q.y) + std::abs(q.z));
      for (int k = 0; k < 4; ++k) {
        lo[3 + k] = std::min(lo[3 + k], along[k] - e);
        hi[3 + k] = std::max(hi[3 + k], along[k] + e);
      }
    }
    SlotBounds& bounds = slot_bounds_[s];
    for (int k = 0; k < 7; ++k) {
      bounds.lo[k] = float_below(lo[k]);
      bounds.hi[k] = float_above(hi[k]);
    }
    bounds.lo[7] = bounds.hi[7] = 0.0f;
  });
  const auto in_grid = [&](std::size_t i) { return !stray[i] && !slot_box_[slots[i]].empty(); };
  std::vector<std::uint64_t> start;
  std::vector<std::uint32_t> cells = collect_cells(
      n,
      [&](std::size_t i) {
        std::size_t bound = 0;
        if (in_grid(i))
          for (std::uint32_t j = slots[i] * group_; j < (slots[i] + 1) * group_; ++j)
            if (present_[j]) bound += grid_.box_cells(box_[j]);
        return bound;
      },
      [&](std::size_t i, std::uint32_t* out) -> std::size_t {
        if (!in_grid(i)) return 0;
        std::size_t count = 0;
        for (std::uint32_t j = slots[i] * group_; j < (slots[i] + 1) * group_; ++j)
          if (present_[j]) count += grid_.cells_of(geo_[j], out + count);
        if (group_ > 1) {  // the union of the tets' ascending lists
          std::sort(out, out + count);
          count = static_cast<std::size_t>(std::unique(out, out + count) - out);
        }
        return count;
      },
      start);
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t slot = slots[i];
    state_[slot] = stray[i] ? kStray : (slot_box_[slot].empty() ? kAbsent : kInGrid);
    if (state_[slot] == kStray) stray_slots_.push_back(slot);
  }
  if (was_empty || rebuild) {
    if (was_empty) {  // every list is empty: all of them in one pass
      std::vector<std::uint64_t> slot_start(state_.size() + 1, 0);
      for (std::size_t i = 0; i < n; ++i) slot_start[slots[i] + 1] = start[i + 1] - start[i];
      for (std::size_t k = 0; k < state_.size(); ++k) slot_start[k + 1] += slot_start[k];
      slot_cells_.assign(std::move(slot_start), std::move(cells));  // slots ascending: in order
    } else {
      for (std::size_t i = 0; i < n; ++i)
        slot_cells_.set(slots[i], cells.data() + start[i], start[i + 1] - start[i]);
    }
    rebuild_cell_slots();
    return;
  }
  // Every (cell, slot) entry, by cell and then slot: each cell's list is merged once.
  std::vector<std::uint64_t> entries;
  entries.reserve(cells.size());
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t slot = slots[i];
    slot_cells_.set(slot, cells.data() + start[i], start[i + 1] - start[i]);
    for (std::uint64_t k = start[i]; k < start[i + 1]; ++k)
      entries.push_back(std::uint64_t{cells[k]} << 32 | slot);
  }
  parallel_sort(entries.begin(), entries.end());  // distinct entries: the same order always
  std::vector<std::uint32_t> run;
  for (std::size_t i = 0; i < entries.size();) {
    const auto cell = static_cast<std::uint32_t>(entries[i] >> 32);
    run.clear();
    for (; i < entries.size() && static_cast<std::uint32_t>(entries[i] >> 32) == cell; ++i)
      run.push_back(static_cast<std::uint32_t>(entries[i]));
    cell_slots_.merge_sorted(cell, run.data(), run.size());
  }
}

}  // namespace vdb_shell
