// index_lists.h — lists of indices per key in one array (compressed rows): key k's items are
// items[start[k] .. start[k + 1]). IndexLists is built in two passes (count, then fill) from any
// enumeration of (key, item) pairs, keeping the order in which each key's items are enumerated,
// or per key in parallel blocks (lists_in_blocks()); invert_lists() turns lists of keys per item
// into lists of items per key, in parallel.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

#include "core/base/parallel.h"

namespace vdb_shell {

/// The inverse of lists of keys: per key c, items[key_start[c], key_start[c + 1]) are the items
/// i in [0, n) whose list keys_of(i) (a [begin, end) pair of pointers to keys below num_keys)
/// holds c, ascending. In parallel over blocks of items and ranges of keys; the same lists for
/// any thread count.
template <class Index, class KeysOf>
void invert_lists(std::size_t n, const KeysOf& keys_of, std::size_t num_keys,
                  std::vector<Index>& key_start, std::vector<std::uint32_t>& items) {
  // At most 256 blocks and 1024 ranges: the counts per block and range stay small.
  const std::size_t block = std::max<std::size_t>(4096, (n + 255) / 256);
  const std::size_t span = std::max<std::size_t>(1024, (num_keys + 1023) / 1024);
  const std::size_t n_blocks = (n + block - 1) / block;
  const std::size_t n_ranges = std::max<std::size_t>(1, (num_keys + span - 1) / span);
  const auto for_each_block = [&](const auto& body) {
    for_each_index(
        n_blocks,
        [&](std::size_t b) {
          for (std::size_t i = b * block; i < std::min(n, (b + 1) * block); ++i)
            for (auto [c, end] = keys_of(i); c != end; ++c) body(b, i, *c);
        },
        2);
  };
  // Each block counts its entries per range of keys; the counts become its first place in
  // each range (ranges in order, within a range the blocks in order: items ascending).
  std::vector<std::size_t> place(n_blocks * n_ranges, 0);
  for_each_block(
      [&](std::size_t b, std::size_t, std::uint32_t c) { ++place[b * n_ranges + c / span]; });
  std::vector<std::size_t> range_start(n_ranges + 1, 0);
  for (std::size_t r = 0, at = 0; r < n_ranges; ++r) {
    for (std::size_t b = 0; b < n_blocks; ++b) at += std::exchange(place[b * n_ranges + r], at);
    range_start[r + 1] = at;
  }
  // The entries (key, item) by range, then each range's by key, keeping the items' order.
  std::vector<std::pair<std::uint32_t, std::uint32_t>> by_range(range_start[n_ranges]);
  for_each_block([&](std::size_t b, std::size_t i, std::uint32_t c) {
    by_range[place[b * n_ranges + c / span]++] = {c, static_cast<std::uint32_t>(i)};
  });
  key_start.assign(num_keys + 1, 0);
  items.resize(by_range.size());
  for_each_index(
      n_ranges,
      [&](std::size_t r) {
        const std::size_t first = r * span, keys = std::min(num_keys, first + span) - first;
        std::vector<Index> fill(keys + 1, 0);  // the range's keys' starts, then fill places
        fill[0] = range_start[r];
        for (std::size_t e = range_start[r]; e < range_start[r + 1]; ++e)
          ++fill[by_range[e].first - first + 1];
        for (std::size_t c = 0; c < keys; ++c) fill[c + 1] += fill[c];
        std::copy(fill.begin(), fill.end() - 1, key_start.begin() + first);
        for (std::size_t e = range_start[r]; e < range_start[r + 1]; ++e)
          items[fill[by_range[e].first - first]++] = by_range[e].second;
      },
      2);
  key_start[num_keys] = range_start[n_ranges];
}

/// Lists computed per key: key k's items are items[start[k], start[k + 1]), those list(k, out)
/// appends to `out` (which it leaves alone otherwise). In parallel over blocks of `block` keys,
/// each into a buffer of its own, joined in key order: the same lists for any thread count.
template <class Index, class List>
void lists_in_blocks(std::size_t keys, std::size_t block, const List& list,
                     std::vector<Index>& start, std::vector<std::uint32_t>& items) {
  std::vector<std::vector<std::uint32_t>> found((keys + block - 1) / block);
  start.assign(keys + 1, 0);
  for_each_index(
      found.size(),
      [&](std::size_t b) {
        std::vector<std::uint32_t>& out = found[b];
        for (std::size_t k = b * block; k < std::min(keys, (b + 1) * block); ++k) {
          const std::size_t at = out.size();
          list(k, out);
          start[k + 1] = static_cast<Index>(out.size() - at);
        }
      },
      2);
  for (std::size_t k = 0; k < keys; ++k) start[k + 1] += start[k];
  items.resize(start[keys]);
  for_each_index(
      found.size(),
      [&](std::size_t b) {
        std::copy(found[b].begin(), found[b].end(),
                  items.begin() + static_cast<std::ptrdiff_t>(start[b * block]));
      },
      2);
}

struct IndexLists {
  std::vector<std::uint32_t> start, items;

  struct Range {
    const std::uint32_t *b, *e;
    const std::uint32_t* begin() const { return b; }
    const std::uint32_t* end() const { return e; }
    std::size_t size() const { return static_cast<std::size_t>(e - b); }
  };
  Range operator[](std::size_t k) const {
    return {items.data() + start[k], items.data() + start[k + 1]};
  }
  std::size_t keys() const { return start.empty() ? 0 : start.size() - 1; }

  /// Builds the lists of `keys` keys from pairs(emit), which calls emit(key, item) for every
  /// item (key < keys), the same pairs in the same order each time it is called (twice).
  template <class Pairs>
  void build(std::size_t keys, const Pairs& pairs) {
    start.assign(keys + 1, 0);
    pairs([&](std::uint32_t k, std::uint32_t) { ++start[k + 1]; });
    for (std::size_t k = 0; k < keys; ++k) start[k + 1] += start[k];
    items.resize(start.back());
    std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
    pairs([&](std::uint32_t k, std::uint32_t item) { items[fill[k]++] = item; });
  }

  /// Builds the lists of `keys` keys, key k's items those list(k, out) appends to `out`, with
  /// lists_in_blocks().
  template <class List>
  void build_each(std::size_t keys, const List& list) {
    lists_in_blocks(keys, 1024, list, start, items);
  }
};

}  // namespace vdb_shell
