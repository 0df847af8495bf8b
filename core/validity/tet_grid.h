// tet_grid.h — the broad phase of the overlap and leak tests: a uniform grid of cubic cells in
// which every tet enters the cells it may intersect and every surface triangle the cells its
// plane crosses. Two tets, or a tet and a triangle, can only intersect when they share a cell;
// the pairs that do are the candidates of the narrow phase (tet_intersections.h).
//
// TetGrid maps geometry to cells; BroadPhase keeps tets (under integer keys that the caller
// chooses) and triangles in the cells of a TetGrid, enters, moves and removes tets, and lists
// the candidates of a tet. check_shell() enters every tet once; ShellChecker keeps one
// BroadPhase over a sequence of shells and moves only the tets that changed.
//
// Lengths are world units. Internal to core/validity (not installed).
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "core/base/surface_mesh.h"
#include "core/base/uninitialized_allocator.h"
#include "core/base/vec3.h"
#include "core/validity/tet_predicates.h"

namespace vdb_shell {

/// A uniform grid of cubic cells over a box. The cells a body may intersect are those of its
/// bounding box (clamped to the grid) that a plane test does not separate from it: the test is
/// conservative. Geometry outside the box is clamped to the border cells, where the plane test
/// may drop it: callers keep their tets inside the box (contains()).
class TetGrid {
 public:
  /// \param box        the grid's extent, world units
  /// \param cell_size  side of a cell, world units, > 0
  TetGrid(const BBox& box, double cell_size);

  /// Whether `b` lies inside the grid's box.
  bool contains(const BBox& b) const;

  /// The cells tet `g` may intersect (those no face plane of the tet separates from it), written
  /// to `out` (when not null) in increasing order; returns how many.
  std::size_t cells_of(const TetGeometry& g, std::uint32_t* out) const;

  /// The cells the plane of triangle `t` (corners, world units) crosses within the triangle's
  /// bounding box, as cells_of().
  std::size_t cells_of_triangle(const std::array<Vec3d, 3>& t, std::uint32_t* out) const;

  /// How many cells `b` covers (clamped to the grid): a bound of the cells of anything inside it.
  std::size_t box_cells(const BBox& b) const;

  const BBox& box() const { return box_; }
  std::size_t num_cells() const;

 private:
  // The points x with lo <= dot(n, x) <= hi.
  struct Slab {
    Vec3d n;
    double lo, hi;
  };
  // Cells of `box` (clamped to the grid) that no slab separates from its body: a cell is kept
  // unless its centre c has dot(n, c) beyond [lo, hi] by more than the cell's half extent along
  // n. The kept cells of a column (i, j) are one run of k, whose ends the slabs give.
  template <std::size_t N>
  std::size_t cells_in(const BBox& box, const std::array<Slab, N>& slabs, std::uint32_t* out) const;
  long cell_of(double x, int axis) const;

  BBox box_;
  double cell_ = 1.0, inv_cell_ = 1.0;  // world units, 1 / world units
  long dims_[3] = {1, 1, 1};
};

/// Tets' geometry by key or index, filled in parallel (no pass of its own to initialise it).
using TetGeometries = std::vector<TetGeometry, UninitializedAllocator<TetGeometry>>;

/// The box of all of `geo`'s boxes (those not empty: an empty box marks an absent tet, here and
/// in grid_cell_size()).
BBox bounding_box_of(const TetGeometries& geo);

/// Cell size (world units) of a TetGrid over `all` for the tets `geo`: about the edge of a cube of
/// 3^3 times the mean tet volume (at least a quarter of the tets' mean box side), so that
/// slivers enter few cells (with far groups rejected by their extents first, larger cells cost
/// less than a group's entries in many small ones), made larger until `all` has at most 32 cells
/// per tet and, on average, the tets' boxes span at most 64 columns (i, j) of cells and the tets
/// enter at most 64 cells (counted on a sample of 4,096 tets): the cell lists hold at most about 64
/// entries per tet. Long needles converging on a point (a sphere's shell) keep small cells: each
/// enters the cells along it, not those of its box.
double grid_cell_size(const TetGeometries& geo, const BBox& all);

/// Lists of 32-bit values, one per slot, in one pool: built all at once (as a CSR array), then
/// edited one list at a time. A list that grows moves to the end of the pool; the pool is
/// compacted when more than half of it is unused.
class PooledLists {
 public:
  explicit PooledLists(std::size_t slots = 0) : begin_(slots, 0), size_(slots, 0) {}

  /// Replaces every list: list s becomes values[start[s], start[s + 1]); `start` has one entry
  /// per slot and one more.
  void assign(std::vector<std::uint64_t> start, std::vector<std::uint32_t> values);

  const std::uint32_t* begin(std::size_t s) const { return pool_.data() + begin_[s]; }
  const std::uint32_t* end(std::size_t s) const { return begin(s) + size_[s]; }

  /// Replaces list s by the `count` values from `first`.
  void set(std::size_t s, const std::uint32_t* first, std::size_t count);
  /// Merges the ascending `count` values from `first`, none of them in it, into the ascending
  /// list s (one copy of the list however many values come).
  void merge_sorted(std::size_t s, const std::uint32_t* first, std::size_t count);
  /// Removes from list s every value v with drop[v] != 0, keeping the others' order.
  void erase_flagged(std::size_t s, const std::vector<std::uint8_t>& drop);

 private:
  // Moves list s to `count` fresh entries at the end of the pool, its old entries unused.
  std::uint64_t relocate(std::size_t s, std::size_t count);
  void compact_if_sparse();

  std::vector<std::uint64_t> begin_;  // per slot: its first entry in pool_
  std::vector<std::uint32_t> size_;   // per slot
  std::vector<std::uint32_t> pool_;
  std::size_t unused_ = 0;  // entries of pool_ in no list
};

/// Tets and surface triangles in the cells of one TetGrid. A tet is named by a key in
/// [0, key_count()); a key is absent or present. Keys come in groups of group_size() (key k is in
/// group k / group_size(): the tets of one prism), and the grid holds groups, not tets: a group
/// enters the cells of its present tets, and two tets can only intersect when their groups share
/// a cell. A group is stray when one of its tets' boxes leaves the grid's box: it is then a
/// candidate of every group, and every triangle a candidate of it. Grouping the tets that fill the
/// same space (the three needles of one prism) makes the cell lists shorter by the group's size,
/// and the reads of a query, which grow with the square of the lists' lengths, fewer by its square.
///
/// Inside, the phase numbers the groups its own way: slots, in the order of a Z-order curve
/// through the centres of the constructor's geometry, so that groups near each other have near
/// slots and a query's reads of cell lists, marks and geometry stay in few cache lines whatever
/// order the caller's keys are in (a mesh with shuffled faces is checked as fast as a coherent
/// one). Tet j of the group in slot s is at *index* s * group_size() + j. The queries below take
/// and visit slots; cell lists are kept in increasing slot order.
class BroadPhase {
 public:
  /// A grid over `box` with cells of side `cell_size` (world units) for the tets of keys
  /// [0, geometry.size()) in groups of `group_size` (>= 1), none entered yet; tet k has the
  /// geometry geometry[k] until set_geometry() changes it (the slots stay those of this first
  /// geometry). With `enter_triangles`, every triangle of `surface` whose box meets `box` is
  /// entered in the cells of TetGrid::cells_of_triangle(). `surface` must outlive the object.
  BroadPhase(const SurfaceMesh& surface, const BBox& box, double cell_size, TetGeometries geometry,
             bool enter_triangles, std::uint32_t group_size = 1);

  /// Gives tet `key` the geometry `g`; calls for distinct keys may run concurrently.
  /// \pre !contains(key)
  void set_geometry(std::uint32_t key, const TetGeometry& g);
  /// Enters the tets `keys` (distinct, absent) at their geometry. Their groups' cells are found
  /// in parallel; into an empty phase the cell lists are built in one pass.
  void insert(const std::vector<std::uint32_t>& keys);
  /// Removes the tets `keys` (distinct); does nothing for those absent. Each cell's list is
  /// edited once, however many of them it held.
  void remove(const std::vector<std::uint32_t>& keys);

  const SurfaceMesh& surface() const { return surface_; }
  std::size_t key_count() const { return key_count_; }
  std::uint32_t group_size() const { return group_; }
  /// How many slots (groups) there are.
  std::size_t slot_count() const { return key_.size(); }
  /// How many keys are present.
  std::size_t size() const { return size_; }
  bool contains(std::uint32_t key) const { return present_[index(key)] != 0; }
  const TetGeometry& geometry(std::uint32_t key) const { return geo_[index(key)]; }

  /// The index of `key` (slot of its group times group_size() plus its place in the group), and
  /// the key at `index`.
  std::uint32_t index(std::uint32_t key) const {
    return slot_[key / group_] * group_ + key % group_;
  }
  std::uint32_t key_at(std::uint32_t index) const {
    return key_[index / group_] * group_ + index % group_;
  }
  /// Whether the tet at `index` is present, its geometry, and its box (kept apart from the
  /// geometry, so that the candidates' boxes are read compactly).
  bool present_at(std::uint32_t index) const { return present_[index] != 0; }
  const TetGeometry& geometry_at(std::uint32_t index) const { return geo_[index]; }
  const BBox& box_at(std::uint32_t index) const { return box_[index]; }
  /// The bounds of the present tets of the group in `slot`: their box and their extents along
  /// the body diagonals (1, 1, 1), (1, 1, -1), (1, -1, 1) and (-1, 1, 1), a 14-sided hull far
  /// tighter than the box around a slanted prism. Relative to the grid's corner, as floats
  /// rounded outwards (the diagonals widened by more than their sums' rounding): one cache line
  /// per group, and groups they find apart are apart (slot_bounds_overlap()).
  struct alignas(64) SlotBounds {
    float lo[8], hi[8];  // x, y, z, the four diagonals, and an entry that always overlaps
  };
  const SlotBounds& slot_bounds(std::uint32_t slot) const { return slot_bounds_[slot]; }
  /// The distinct corners of the present tets of the group in `slot`, side by side.
  const Vec3d* slot_corners(std::uint32_t slot) const {
    return corners_.data() + std::size_t{4} * group_ * slot;
  }
  std::uint32_t slot_corner_count(std::uint32_t slot) const { return corner_count_[slot]; }

  /// Calls visit(other) once for every slot `other` whose group shares a cell with that of `slot`
  /// (`slot` itself included), every stray group's slot, and, when `slot` is stray, every slot
  /// with a present tet. With `only_greater` the slots below `slot` in its cells are skipped.
  /// `mark` has one entry per slot, none equal to `stamp` before the call; it marks the slots
  /// visited.
  template <class Visit>
  void for_each_group_near(std::uint32_t slot, bool only_greater, std::vector<std::uint32_t>& mark,
                           std::uint32_t stamp, const Visit& visit) const;

  /// Calls visit(f) once for every surface triangle f that shares a cell with the group of
  /// `slot`, or for every triangle when it is stray; for none unless the triangles were entered.
  /// `mark`: one entry per triangle, as above.
  template <class Visit>
  void for_each_triangle_near(std::uint32_t slot, std::vector<std::uint32_t>& mark,
                              std::uint32_t stamp, const Visit& visit) const;

 private:
  enum State : std::uint8_t { kAbsent, kInGrid, kStray };

  void enter_triangles();

  // The slots of the groups of `keys`, ascending, each once.
  std::vector<std::uint32_t> slots_of(const std::vector<std::uint32_t>& keys) const;
  // Takes the groups in `slots` (ascending, distinct) out of the grid and enters each again with
  // its present tets, if it has any. `was_empty`: no group was in the grid (every list is built
  // in one pass).
  void reenter(const std::vector<std::uint32_t>& slots, bool was_empty);
  // Builds every cell's list of slots again from the slots' lists of cells.
  void rebuild_cell_slots();
  // reenter() rebuilds every cell's list when at least 1 / kRebuildShare of the slots move.
  static constexpr std::size_t kRebuildShare = 6;

  const SurfaceMesh& surface_;
  TetGrid grid_;
  std::uint32_t group_ = 1;
  std::size_t key_count_ = 0;
  std::vector<std::uint32_t> slot_, key_;    // per group its slot, per slot its group
  TetGeometries geo_;                        // per index
  std::vector<BBox> box_;                    // per index: the tet's box while it is present
  std::vector<std::uint8_t> present_;        // per index
  std::vector<BBox> slot_box_;               // per slot, world units
  std::vector<Vec3d> corners_;               // per slot 4 group_ entries, the first corner_count_
  std::vector<std::uint32_t> corner_count_;  // per slot
  std::vector<State> state_;                 // per slot
  std::vector<SlotBounds> slot_bounds_;      // per slot
  std::size_t size_ = 0;
  PooledLists slot_cells_;                  // per slot: its cells, ascending (none when stray)
  PooledLists cell_slots_;                  // per cell: its slots, ascending
  std::vector<std::uint32_t> stray_slots_;  // in no particular order
  std::vector<std::uint32_t> triangle_start_, triangle_items_;  // per cell: its triangles
};

/// Whether two groups' bounds (closed) overlap: when they do not, neither do the groups' hulls.
inline bool slot_bounds_overlap(const BroadPhase::SlotBounds& a, const BroadPhase::SlotBounds& b) {
#if defined(__SSE2__)
  // Four lanes at a time: the 16 comparisons in 4 instructions, one branch.
  const __m128 below = _mm_and_ps(_mm_cmple_ps(_mm_load_ps(a.lo), _mm_load_ps(b.hi)),
                                  _mm_cmple_ps(_mm_load_ps(a.lo + 4), _mm_load_ps(b.hi + 4)));
  const __m128 above = _mm_and_ps(_mm_cmple_ps(_mm_load_ps(b.lo), _mm_load_ps(a.hi)),
                                  _mm_cmple_ps(_mm_load_ps(b.lo + 4), _mm_load_ps(a.hi + 4)));
  return _mm_movemask_ps(_mm_and_ps(below, above)) == 0xf;
#else
  for (int k = 0; k < 8; ++k)
    if (a.lo[k] > b.hi[k] || b.lo[k] > a.hi[k]) return false;
  return true;
#endif
}

template <class Visit>
void BroadPhase::for_each_group_near(std::uint32_t slot, bool only_greater,
                                     std::vector<std::uint32_t>& mark, std::uint32_t stamp,
                                     const Visit& visit) const {
  std::uint32_t* const marks = mark.data();
  const auto once = [&](std::uint32_t other) {
    if (marks[other] == stamp) return;
    marks[other] = stamp;
    visit(other);
  };
  if (state_[slot] == kStray) {
    for (std::uint32_t other = 0; other < state_.size(); ++other)
      if (state_[other] != kAbsent) once(other);
    return;
  }
  for (const std::uint32_t* c = slot_cells_.begin(slot); c != slot_cells_.end(slot); ++c) {
    const std::uint32_t* first = cell_slots_.begin(*c);
    const std::uint32_t* last = cell_slots_.end(*c);
    for (const std::uint32_t* it = only_greater ? std::lower_bound(first, last, slot) : first;
         it != last; ++it)
      once(*it);
  }
  for (const std::uint32_t other : stray_slots_) once(other);
}

template <class Visit>
void BroadPhase::for_each_triangle_near(std::uint32_t slot, std::vector<std::uint32_t>& mark,
                                        std::uint32_t stamp, const Visit& visit) const {
  if (triangle_start_.empty()) return;
  if (state_[slot] == kStray) {
    for (std::uint32_t f = 0; f < surface_.triangles.size(); ++f) visit(f);
    return;
  }
  for (const std::uint32_t* c = slot_cells_.begin(slot); c != slot_cells_.end(slot); ++c)
    for (std::uint32_t i = triangle_start_[*c]; i < triangle_start_[*c + 1]; ++i) {
      const std::uint32_t f = triangle_items_[i];
      if (mark[f] == stamp) continue;
      mark[f] = stamp;
      visit(f);
    }
}

}  // namespace vdb_shell
