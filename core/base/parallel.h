// parallel.h — the one place core/ touches TBB. Every parallel loop goes through for_each_index:
// each index writes only its own output slot, so results never depend on scheduling. Each chunk
// first checks the cancel flag of the calling thread's active stage (run_control.h), so a
// cancelled run stops within one chunk of work and throws CancelledError to the caller; every
// 64th chunk also refreshes the stage's last progress report (StageMonitor::alive()).
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <cstddef>
#include <vector>

#include "core/base/run_control.h"

namespace vdb_shell {

/// Calls body(i) for every i in [0, n), in parallel above `serial_below` items.
template <class Body>
void for_each_index(std::size_t n, const Body& body, std::size_t serial_below = 64) {
  const StageMonitor* monitor = StageMonitor::active();
  if (n < serial_below) {
    if (monitor) monitor->alive();
    for (std::size_t i = 0; i < n; ++i) body(i);
    return;
  }
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 16),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      if (monitor) monitor->alive();
                      for (std::size_t i = r.begin(); i != r.end(); ++i) body(i);
                    });
}

/// Calls body(begin, end) over chunks of [0, n) in parallel, for loops that keep per-chunk state
/// (a FieldProbe, scratch buffers).
template <class Body>
void for_each_chunk(std::size_t n, const Body& body, std::size_t grain = 32) {
  const StageMonitor* monitor = StageMonitor::active();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, grain),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      if (monitor) monitor->alive();
                      body(r.begin(), r.end());
                    });
}

/// combine() of item(i) over [0, n), starting from `zero`: blocks of 4096 items in parallel, each
/// combined in index order, then the blocks in block order. The result depends only on n, not on
/// the thread count, even where combine() is not associative (floating-point sums).
template <class T, class Item, class Combine>
T reduce_in_blocks(std::size_t n, const T& zero, const Item& item, const Combine& combine) {
  constexpr std::size_t kBlock = 4096;
  std::vector<T> part((n + kBlock - 1) / kBlock, zero);
  for_each_index(
      part.size(),
      [&](std::size_t b) {
        const std::size_t end = n < (b + 1) * kBlock ? n : (b + 1) * kBlock;
        for (std::size_t i = b * kBlock; i < end; ++i) part[b] = combine(part[b], item(i));
      },
      2);
  T all = zero;
  for (const T& p : part) all = combine(all, p);
  return all;
}

/// Sorts [begin, end) by operator< in parallel. Deterministic only for a strict total order
/// (no two elements equivalent): the order of equivalent elements is not kept.
template <class Iterator>
void parallel_sort(Iterator begin, Iterator end) {
  tbb::parallel_sort(begin, end);
}

}  // namespace vdb_shell
