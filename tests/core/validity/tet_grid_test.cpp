// tet_grid_test.cpp — the broad phase (tet_grid.h): the cells TetGrid gives a tet hold every
// point of it and are those of a test of every cell of its box; PooledLists, the cell lists:
// edits of many values at once keep every list ascending and leave the other lists alone;
// BroadPhase: tets moved, few or many, meet the groups that tets entered afresh meet.
#include "core/validity/tet_grid.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <random>
#include <vector>

namespace vdb_shell {
namespace {

// Random tets over a 20^3 grid whose corner is `offset` from the origin: small ones, large ones,
// and needles in every direction (whose cells are found column by column); each tet's cells must
// hold 2,000 points sampled in it and, with `exact`, equal the cells of its box that pass the
// plane test one by one.
void check_cells_of_random_tets(const Vec3d& offset, bool exact) {
  const BBox box{Vec3d{-1, -2, -1.5} + offset, Vec3d{1, 0, 0.5} + offset};
  const double h = 0.1;
  const TetGrid grid(box, h);
  ASSERT_EQ(grid.num_cells(), 8000u);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const auto in_box = [&] {
    return Vec3d{box.lo.x + 2 * u(rng), box.lo.y + 2 * u(rng), box.lo.z + 2 * u(rng)};
  };
  const auto cell_at = [&](const Vec3d& p) {
    const auto index = [&](double x, double lo) {
      return std::clamp(static_cast<long>(std::floor((x - lo) / h)), 0L, 19L);
    };
    return static_cast<std::uint32_t>((index(p.x, box.lo.x) * 20 + index(p.y, box.lo.y)) * 20 +
                                      index(p.z, box.lo.z));
  };
  for (int t = 0; t < 300; ++t) {
    SCOPED_TRACE("tet " + std::to_string(t));
    std::array<Vec3d, 4> p;
    p[0] = in_box();
    const double size = t % 3 == 1 ? 0.4 : 0.05;
    for (int k = 1; k < 4; ++k)
      p[k] = p[0] + Vec3d{size * (u(rng) - 0.5), size * (u(rng) - 0.5), size * (u(rng) - 0.5)};
    if (t % 3 == 2) p[3] = in_box();  // a needle: one corner far away
    for (Vec3d& q : p)
      for (int a = 0; a < 3; ++a) q[a] = std::clamp(q[a], box.lo[a], box.hi[a]);
    const TetGeometry g = tet_geometry(p);
    std::vector<std::uint32_t> cells(grid.box_cells(g.box));
    cells.resize(grid.cells_of(g, cells.data()));
    ASSERT_TRUE(std::is_sorted(cells.begin(), cells.end()));
    for (int s = 0; s < 2000; ++s) {
      double w[4], sum = 0;
      for (double& x : w) sum += x = -std::log(u(rng) + 1e-300);
      Vec3d q{};
      for (int k = 0; k < 4; ++k) q = q + p[k] * (w[k] / sum);
      ASSERT_TRUE(std::binary_search(cells.begin(), cells.end(), cell_at(q)));
    }
    if (!exact) continue;
    std::vector<std::uint32_t> tested;
    const auto lo = cell_at(g.box.lo), hi = cell_at(g.box.hi);
    for (std::uint32_t i = lo / 400; i <= hi / 400; ++i)
      for (std::uint32_t j = lo / 20 % 20; j <= hi / 20 % 20; ++j)
        for (std::uint32_t k = lo % 20; k <= hi % 20; ++k) {
          const Vec3d c = box.lo + Vec3d{(i + 0.5) * h, (j + 0.5) * h, (k + 0.5) * h};
          bool kept = true;
          for (int f = 0; f < 4; ++f) {
            const Vec3d& n = g.n[f];
            const double d = dot(n, c - g.p[0]),  // g's extents are relative to p[0]
                reach = 0.5 * h * (std::abs(n.x) + std::abs(n.y) + std::abs(n.z));
            if (d - reach > g.hi[f] || d + reach < g.lo[f]) kept = false;
          }
          if (kept) tested.push_back((i * 20 + j) * 20 + k);
        }
    EXPECT_EQ(cells, tested);
  }
}

TEST(TetGrid, CellsOfATetHoldItAndAreThoseNoFacePlaneSeparates) {
  check_cells_of_random_tets(Vec3d{}, true);
}

TEST(TetGrid, CellsOfATetFarFromTheOriginHoldIt) {
  // At 1e6 the coordinates round at 1e-10: the runs of cells must still hold every tet.
  check_cells_of_random_tets(Vec3d{1e6, -3e6, 2e6}, false);
}

std::vector<std::uint32_t> list_of(const PooledLists& lists, std::size_t s) {
  return {lists.begin(s), lists.end(s)};
}

TEST(PooledLists, MergeSortedKeepsTheListAscending) {
  PooledLists lists(3);
  lists.assign({0, 3, 3, 5}, {2, 5, 9, 1, 4});
  const std::vector<std::uint32_t> add = {0, 3, 6, 10};
  lists.merge_sorted(0, add.data(), add.size());
  EXPECT_EQ(list_of(lists, 0), (std::vector<std::uint32_t>{0, 2, 3, 5, 6, 9, 10}));
  lists.merge_sorted(1, add.data(), 2);  // into an empty list
  EXPECT_EQ(list_of(lists, 1), (std::vector<std::uint32_t>{0, 3}));
  lists.merge_sorted(2, add.data(), 0);  // nothing
  EXPECT_EQ(list_of(lists, 2), (std::vector<std::uint32_t>{1, 4}));
}

TEST(PooledLists, EraseFlaggedRemovesOnlyTheFlaggedValues) {
  PooledLists lists(2);
  lists.assign({0, 4, 6}, {1, 2, 5, 7, 2, 5});
  std::vector<std::uint8_t> drop(8, 0);
  drop[2] = drop[7] = 1;
  lists.erase_flagged(0, drop);
  EXPECT_EQ(list_of(lists, 0), (std::vector<std::uint32_t>{1, 5}));
  EXPECT_EQ(list_of(lists, 1), (std::vector<std::uint32_t>{2, 5}));  // untouched
}

TEST(PooledLists, ManyMergesSurviveCompaction) {
  PooledLists lists(4);
  lists.assign({0, 0, 0, 0, 0}, {});
  std::vector<std::vector<std::uint32_t>> expected(4);
  for (std::uint32_t v = 0; v < 3000; ++v) {
    const std::size_t s = v % 4;
    lists.merge_sorted(s, &v, 1);
    expected[s].push_back(v);
  }
  for (std::size_t s = 0; s < 4; ++s) EXPECT_EQ(list_of(lists, s), expected[s]);
}

// Removing tets, giving them new places and entering them again edits the cell lists of the
// cells concerned when few move, and builds every list again when many do: either way each
// group must meet exactly the groups it meets in a phase that enters every tet at its new place.
TEST(BroadPhase, MovedTetsMeetTheGroupsOfTetsEnteredAfresh) {
  const SurfaceMesh surface;
  const BBox box{{0, 0, 0}, {1, 1, 1}};
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const auto random_tet = [&] {
    std::array<Vec3d, 4> p;
    p[0] = Vec3d{0.05 + 0.9 * u(rng), 0.05 + 0.9 * u(rng), 0.05 + 0.9 * u(rng)};
    for (int k = 1; k < 4; ++k)
      p[k] = p[0] + Vec3d{0.08 * (u(rng) - 0.5), 0.08 * (u(rng) - 0.5), 0.08 * (u(rng) - 0.5)};
    return tet_geometry(p);
  };
  const std::uint32_t n = 600;
  TetGeometries start(n);
  for (TetGeometry& g : start) g = random_tet();
  std::vector<std::uint32_t> all(n);
  std::iota(all.begin(), all.end(), 0u);
  const auto met = [&](const BroadPhase& phase, std::uint32_t slot) {
    std::vector<std::uint32_t> mark(phase.slot_count(), 0), out;
    phase.for_each_group_near(slot, false, mark, 1, [&](std::uint32_t s) { out.push_back(s); });
    std::sort(out.begin(), out.end());
    return out;
  };
  for (const std::uint32_t moved : {10u, 20u, n / 2, n}) {
    SCOPED_TRACE(std::to_string(moved) + " tets moved");
    BroadPhase edited(surface, box, 0.05, start, false);
    edited.insert(all);
    TetGeometries now = start;
    std::vector<std::uint32_t> keys;
    for (std::uint32_t k = 0; k < moved; ++k) keys.push_back(k * (n / moved));
    for (const std::uint32_t k : keys) now[k] = random_tet();
    edited.remove(keys);
    for (const std::uint32_t k : keys) edited.set_geometry(k, now[k]);
    edited.insert(keys);
    BroadPhase fresh(surface, box, 0.05, start, false);  // the same slots
    for (std::uint32_t k = 0; k < n; ++k) fresh.set_geometry(k, now[k]);
    fresh.insert(all);
    std::size_t pairs = 0;
    for (std::uint32_t slot = 0; slot < n; ++slot) {
      const std::vector<std::uint32_t> expected = met(fresh, slot);
      ASSERT_EQ(met(edited, slot), expected) << "slot " << slot;
      pairs += expected.size();
    }
    EXPECT_GT(pairs, 2 * std::size_t{n});  // the tets do meet others
  }
}

}  // namespace
}  // namespace vdb_shell
