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

/// Sorts [begin, end) by operator< in parallel. Deterministic only for a strict total order
/// (no two elements equivalent): the order of equivalent elements is not kept.
template <class Iterator>
void parallel_sort(Iterator begin, Iterator end) {
  tbb::parallel_sort(begin, end);
}

}  // namespace vdb_shell
