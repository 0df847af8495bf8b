// index_lists_test.cpp — IndexLists (index_lists.h): lists built in parallel blocks, and
// invert_lists(), equal to a serial computation of the same lists for any thread count.
#include "core/base/index_lists.h"

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <utility>
#include <vector>

namespace vdb_shell {
namespace {

TEST(IndexLists, InvertedListsHoldEveryItemAscendingForAnyThreadCount) {
  // 30,000 items (8 blocks) with 0-6 keys each, in any order, over 5,000 keys (5 ranges):
  // against a serial count of every (key, item) pair.
  const std::size_t n = 30000, num_keys = 5000;
  std::mt19937 rng(3);
  std::vector<std::vector<std::uint32_t>> lists(n);
  for (auto& l : lists) {
    std::uniform_int_distribution<std::uint32_t> key(0, num_keys - 1);
    for (std::size_t k = rng() % 7; k > 0; --k) l.push_back(key(rng));
    std::sort(l.begin(), l.end());
    l.erase(std::unique(l.begin(), l.end()), l.end());
    std::shuffle(l.begin(), l.end(), rng);
  }
  std::vector<std::vector<std::uint32_t>> expected(num_keys);
  for (std::uint32_t i = 0; i < n; ++i)
    for (const std::uint32_t c : lists[i]) expected[c].push_back(i);
  for (const int threads : {1, 4}) {
    SCOPED_TRACE(threads);
    std::vector<std::uint64_t> start;
    std::vector<std::uint32_t> items;
    tbb::task_arena(threads).execute([&] {
      invert_lists(
          n,
          [&](std::size_t i) {
            return std::pair{lists[i].data(), lists[i].data() + lists[i].size()};
          },
          num_keys, start, items);
    });
    ASSERT_EQ(start.size(), num_keys + 1);
    ASSERT_EQ(start.back(), items.size());
    for (std::size_t c = 0; c < num_keys; ++c)
      ASSERT_EQ(
          std::vector<std::uint32_t>(items.begin() + static_cast<std::ptrdiff_t>(start[c]),
                                     items.begin() + static_cast<std::ptrdiff_t>(start[c + 1])),
          expected[c])
          << "key " << c;
  }
}

TEST(IndexLists, ListsBuiltEachInBlocksAreThoseOfEveryKeyInTurn) {
  // 5,000 keys (5 blocks of 1,024), key k listing k % 7 items of its own: against build().
  const std::size_t keys = 5000;
  const auto list = [](std::size_t k, std::vector<std::uint32_t>& out) {
    for (std::size_t j = 0; j < k % 7; ++j) out.push_back(static_cast<std::uint32_t>(31 * k + j));
  };
  IndexLists expected;
  expected.build(keys, [&](const auto& emit) {
    std::vector<std::uint32_t> items;
    for (std::size_t k = 0; k < keys; ++k) {
      items.clear();
      list(k, items);
      for (const std::uint32_t item : items) emit(static_cast<std::uint32_t>(k), item);
    }
  });
  for (const int threads : {1, 4}) {
    SCOPED_TRACE(threads);
    IndexLists lists;
    tbb::task_arena(threads).execute([&] { lists.build_each(keys, list); });
    EXPECT_EQ(lists.start, expected.start);
    EXPECT_EQ(lists.items, expected.items);
  }
}

}  // namespace
}  // namespace vdb_shell
