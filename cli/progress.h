// progress.h — the vdb_shell command's progress output on stderr: one line per stage, or a bar
// redrawn in place on a terminal, fed by the CLI's own stages (read, write) and by
// build_shell()'s RunControl::progress reports.
#pragma once

#include <cstdio>
#include <ostream>
#include <string>
#include <utility>
#include <vector>

#include "core/base/timer.h"

namespace vdb_shell {

enum class ProgressMode { kNone, kLines, kBar };

/// "0.42": seconds as the progress lines and the batch table print them.
inline std::string fmt_seconds(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.2f", v);
  return buf;
}

/// Stage timer and progress printer on stderr. Lines: "[2/6] fields ... 0.42 s", one per
/// stage. Bar: the current stage redrawn in place, "[3/6] trace  42%  1.2 s", then the same
/// line as Lines mode once the stage ends.
class Progress {
 public:
  Progress(std::ostream& err, ProgressMode mode, int total, std::string prefix)
      : err_(err), mode_(mode), total_(total), prefix_(std::move(prefix)) {}
  ~Progress() {
    if (open_ && mode_ != ProgressMode::kNone) err_ << " failed\n" << std::flush;
  }
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  void start(const std::string& name) {
    name_ = name;
    ++index_;
    open_ = true;
    t0_ = Clock::now();
    if (mode_ != ProgressMode::kNone) err_ << head() << " ..." << std::flush;
  }
  /// Ends the current stage; returns its seconds.
  double stop() {
    const double s = seconds_since(t0_);
    open_ = false;
    if (mode_ == ProgressMode::kBar) err_ << "\r\033[K" << head() << " ...";
    if (mode_ != ProgressMode::kNone) err_ << " " << fmt_seconds(s) << " s\n" << std::flush;
    timings_.emplace_back(name_, s);
    return s;
  }
  /// A library stage's report (RunControl::progress): 0 starts it, 1 ends it.
  void update(const std::string& stage, double fraction) {
    if (!open_ && stage == name_) return;  // late news of the stage that just ended
    if (!open_ || stage != name_) {
      start(stage);
      return;
    }
    if (fraction >= 1.0) {
      stop();
      return;
    }
    if (mode_ != ProgressMode::kBar) return;
    char line[64];
    std::snprintf(line, sizeof line, " %3d%%  %s s", static_cast<int>(100 * fraction),
                  fmt_seconds(seconds_since(t0_)).c_str());
    err_ << "\r\033[K" << head() << line << std::flush;
  }
  /// "read 0.01 s, fields 0.42 s, ..."
  std::string timings() const {
    std::string s;
    for (const auto& [name, t] : timings_)
      s += (s.empty() ? "" : ", ") + name + " " + fmt_seconds(t) + " s";
    return s;
  }

 private:
  std::string head() const {
    return prefix_ + "[" + std::to_string(index_) + "/" + std::to_string(total_) + "] " + name_;
  }

  std::ostream& err_;
  ProgressMode mode_;
  int total_;
  std::string prefix_;
  std::string name_;
  int index_ = 0;
  bool open_ = false;
  Clock::time_point t0_;
  std::vector<std::pair<std::string, double>> timings_;
};

}  // namespace vdb_shell
