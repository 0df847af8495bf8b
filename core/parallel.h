// parallel.h — the one place core/ touches TBB. Every parallel loop goes through for_each_index:
// each index writes only its own output slot, so results never depend on scheduling.
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cstddef>

namespace vdb_shell {

/// Calls body(i) for every i in [0, n), in parallel above `serial_below` items.
template <class Body>
void for_each_index(std::size_t n, const Body& body, std::size_t serial_below = 64) {
  if (n < serial_below) {
    for (std::size_t i = 0; i < n; ++i) body(i);
    return;
  }
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 16),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t i = r.begin(); i != r.end(); ++i) body(i);
                    });
}

/// Calls body(begin, end) over chunks of [0, n) in parallel, for loops that keep per-chunk state
/// (a FieldProbe, scratch buffers).
template <class Body>
void for_each_chunk(std::size_t n, const Body& body, std::size_t grain = 32) {
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, grain),
                    [&](const tbb::blocked_range<std::size_t>& r) { body(r.begin(), r.end()); });
}

}  // namespace vdb_shell
