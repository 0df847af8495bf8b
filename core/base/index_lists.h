// index_lists.h — lists of indices per key in one array (compressed rows): key k's items are
// items[start[k] .. start[k + 1]). Built in two passes (count, then fill) from any enumeration of
// (key, item) pairs, keeping the order in which each key's items are enumerated.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace vdb_shell {

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
};

}  // namespace vdb_shell
