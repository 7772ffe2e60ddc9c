#include "core/run_control.h"

#include <algorithm>

namespace csgvox {

RunControl::RunControl() : state_(std::make_shared<State>()) {}

RunControl::RunControl(double timeLimit, ProgressCallback progress)
    : state_(std::make_shared<State>()) {
  state_->progress = std::move(progress);
  if (timeLimit > 0.0) {
    deadline_ = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                   std::chrono::duration<double>(timeLimit));
  }
}

bool RunControl::report(double fraction, std::string_view stage) const {
  if (state_->progress && !state_->progress(fraction, stage)) cancel();
  return !cancelled();
}

RunControl RunControl::until(Clock::time_point deadline) const {
  RunControl copy = *this;
  copy.deadline_ = std::min(copy.deadline_, deadline);
  return copy;
}

ProgressCallback RunControl::asProgress() const {
  return [control = *this](double fraction, std::string_view stage) {
    return control.report(fraction, stage);
  };
}

}  // namespace csgvox
