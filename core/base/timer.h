// timer.h — wall-clock seconds for the timings every stage reports.
#pragma once

#include <chrono>

namespace vdb_shell {

using Clock = std::chrono::steady_clock;

/// Seconds from `start` to now (steady clock).
inline double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

}  // namespace vdb_shell
