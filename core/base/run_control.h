// run_control.h — progress reports and cancellation of a pipeline run.
//
// A caller hands build_shell() (vdb_shell/vdb_shell.h) a RunControl: a progress callback and a
// cancel flag. Each stage wraps it in a StageMonitor, which reports the fraction of the stage
// done and checks the flag. The long stages report at least every ~0.1 s of work and check the
// flag at least as often (every parallel loop of core/ checks it per chunk through
// parallel.h); a set flag makes the run throw CancelledError (errors.h) from the next check, and
// nothing is written.
//
// Threads: the callback may be called from any of the run's threads, but never by two at once,
// and for one stage its fractions never decrease. A stage reports 0 when it starts and 1 when it
// ends; between them, at most one report every 50 ms.
#pragma once

#include <atomic>
#include <chrono>
#include <cstddef>
#include <functional>
#include <mutex>
#include <string>

namespace vdb_shell {

/// Called with the name of a stage ("fields", "trace", "inner", "validity") and the fraction of
/// that stage done, in [0, 1].
using ProgressCallback = std::function<void(const std::string& stage, double fraction)>;

/// What a caller hands a run: both members optional.
struct RunControl {
  ProgressCallback progress;                  ///< empty: no reports
  const std::atomic<bool>* cancel = nullptr;  ///< set to true (from any thread) to cancel
};

/// One stage's view of a RunControl. A default-constructed monitor reports nothing and is never
/// cancelled (a stage function called on its own).
class StageMonitor {
 public:
  StageMonitor() = default;
  /// Reports (stage, 0) and checks the flag.
  StageMonitor(const RunControl& control, std::string stage);
  StageMonitor(const StageMonitor&) = delete;
  StageMonitor& operator=(const StageMonitor&) = delete;

  /// \throw CancelledError if cancellation was asked for. One atomic load: call it anywhere.
  void check() const;
  /// check(), and every 64th call a report of the fraction reached so far: long loops that do
  /// not know their share of the stage keep the caller's display alive. Thread-safe.
  void alive() const;
  /// Reports `fraction` of the stage done (clamped to [0, 1], never below an earlier report),
  /// at most every 50 ms; checks the flag. Thread-safe.
  void report(double fraction) const;
  /// report(), but always passed on: a milestone of the stage (a part of it done), which the
  /// progress callback then sees however short the stage was.
  void milestone(double fraction) const;
  /// Work counted in items: the stage's fractions [lo, hi] are spent on `items` items, which
  /// advance() then counts. Call from one thread between parallel phases.
  void begin_part(double lo, double hi, std::size_t items) const;
  /// Counts `n` items of the current part done; reports and checks. Thread-safe.
  void advance(std::size_t n = 1) const;
  /// Reports (stage, 1): the stage is done.
  void finish() const;

  /// The monitor of the stage running on the calling thread (set by ActiveStage), or nullptr.
  static const StageMonitor* active();

 private:
  void emit(double fraction, bool force) const;

  ProgressCallback progress_;
  const std::atomic<bool>* cancel_ = nullptr;
  std::string stage_;
  mutable std::mutex mutex_;
  mutable double reported_ = 0.0;
  mutable bool finished_ = false;  ///< finish() reported 1: later reports are dropped
  mutable std::chrono::steady_clock::time_point last_{};
  mutable std::atomic<std::size_t> done_{0};
  mutable std::atomic<std::size_t> alive_calls_{0};
  mutable double part_lo_ = 0.0, part_hi_ = 0.0;
  mutable std::size_t part_items_ = 0;
};

/// Makes `monitor` the calling thread's active monitor (StageMonitor::active()) for the scope,
/// so that the parallel loops of core/ (parallel.h) check its flag per chunk.
class ActiveStage {
 public:
  explicit ActiveStage(const StageMonitor& monitor);
  ~ActiveStage();
  ActiveStage(const ActiveStage&) = delete;
  ActiveStage& operator=(const ActiveStage&) = delete;

 private:
  const StageMonitor* previous_;
};

}  // namespace vdb_shell
