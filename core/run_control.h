#pragma once
/// One control for every long step: a deadline, a progress report and a
/// cancel request (OpenVDB's interrupter, in csgvox's words). A step calls
/// report() now and then; when it returns false the step stops as soon as
/// it can. Past the deadline a search keeps the best result it has; a
/// cancelled step gives up its result. Copies share the cancel request.

#include <atomic>
#include <chrono>
#include <memory>
#include <stdexcept>
#include <string_view>

#include "core/progress.h"

namespace csgvox {

/// Thrown by a step that cannot give a partial result (meshing, the STEP
/// export) when its RunControl is cancelled.
class CancelledError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class RunControl {
 public:
  using Clock = std::chrono::steady_clock;

  /// No deadline, no progress: runs to the end unless cancel() is called.
  RunControl();
  /// Stops `timeLimit` seconds from now (0: no deadline). `progress`, when
  /// given, hears the fraction of the step done and its current stage; its
  /// returning false is a cancel request.
  explicit RunControl(double timeLimit, ProgressCallback progress = {});

  /// When the work must stop (time_point::max() without a limit).
  Clock::time_point deadline() const { return deadline_; }
  /// The deadline has passed.
  bool pastDeadline() const { return Clock::now() > deadline_; }
  /// Asks every step under this control (and its copies) to stop; any thread.
  void cancel() const { state_->cancelled.store(true, std::memory_order_relaxed); }
  /// cancel() was called, or the progress callback returned false.
  bool cancelled() const { return state_->cancelled.load(std::memory_order_relaxed); }
  /// Cancelled or past the deadline: the step should stop now.
  bool shouldStop() const { return cancelled() || pastDeadline(); }
  /// Tells the progress callback; false once the work is cancelled (what
  /// the deadline means is the step's own: a search keeps its best result).
  bool report(double fraction, std::string_view stage) const;
  /// As a ProgressCallback, for steps that take one.
  ProgressCallback asProgress() const;
  /// A copy that must stop by `deadline` too (the earlier of the two
  /// deadlines); it shares the cancel request and the progress callback.
  RunControl until(Clock::time_point deadline) const;

 private:
  struct State {
    std::atomic<bool> cancelled{false};
    ProgressCallback progress;
  };
  std::shared_ptr<State> state_;
  Clock::time_point deadline_ = Clock::time_point::max();
};

}  // namespace csgvox
