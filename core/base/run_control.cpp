// run_control.cpp — StageMonitor: rate-limited, serialised progress reports and cancel checks.
#include "core/base/run_control.h"

#include <algorithm>
#include <utility>

#include "core/base/errors.h"

namespace vdb_shell {
namespace {

thread_local const StageMonitor* active_monitor = nullptr;
constexpr std::chrono::milliseconds kReportInterval{50};

}  // namespace

StageMonitor::StageMonitor(const RunControl& control, std::string stage)
    : progress_(control.progress), cancel_(control.cancel), stage_(std::move(stage)) {
  check();
  emit(0.0, true);
}

void StageMonitor::check() const {
  if (cancel_ && cancel_->load(std::memory_order_relaxed))
    throw CancelledError("cancelled during the " + stage_ + " stage; nothing was written");
}

void StageMonitor::alive() const {
  check();
  if (progress_ && (alive_calls_.fetch_add(1, std::memory_order_relaxed) & 63) == 63)
    emit(0.0, false);  // clamped up to the last fraction reported
}

void StageMonitor::report(double fraction) const {
  check();
  if (progress_) emit(fraction, false);
}

void StageMonitor::milestone(double fraction) const {
  check();
  emit(fraction, true);
}

void StageMonitor::begin_part(double lo, double hi, std::size_t items) const {
  std::lock_guard<std::mutex> lock(mutex_);
  part_lo_ = lo;
  part_hi_ = hi;
  part_items_ = items;
  done_.store(0, std::memory_order_relaxed);
}

void StageMonitor::advance(std::size_t n) const {
  check();
  if (!progress_) return;
  const std::size_t done = done_.fetch_add(n, std::memory_order_relaxed) + n;
  // Reading the clock costs ~20 ns: look at it once every 64 items.
  if ((done & 63) >= n && done < part_items_) return;
  const double f = part_items_ ? std::min(1.0, double(done) / double(part_items_)) : 1.0;
  emit(part_lo_ + (part_hi_ - part_lo_) * f, false);
}

void StageMonitor::finish() const {
  check();
  emit(1.0, true);
}

void StageMonitor::emit(double fraction, bool force) const {
  if (!progress_) return;
  std::lock_guard<std::mutex> lock(mutex_);
  // Once 1 is reported (by finish() or a worker's last advance()), the stage is over: another
  // report would reopen it.
  if (finished_) return;
  fraction = std::clamp(fraction, reported_, 1.0);
  const auto now = std::chrono::steady_clock::now();
  if (!force && now - last_ < kReportInterval) return;
  last_ = now;
  reported_ = fraction;
  finished_ = fraction >= 1.0;
  progress_(stage_, fraction);
}

const StageMonitor* StageMonitor::active() { return active_monitor; }

ActiveStage::ActiveStage(const StageMonitor& monitor) : previous_(active_monitor) {
  active_monitor = &monitor;
}

ActiveStage::~ActiveStage() { active_monitor = previous_; }

}  // namespace vdb_shell
