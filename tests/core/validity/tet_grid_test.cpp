// tet_grid_test.cpp — PooledLists, the cell lists of the broad phase (tet_grid.h): edits of many
// values at once keep every list ascending and leave the other lists alone.
#include "core/validity/tet_grid.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

namespace vdb_shell {
namespace {

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

}  // namespace
}  // namespace vdb_shell
