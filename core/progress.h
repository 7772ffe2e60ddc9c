#pragma once
/// Progress reporting and cancellation for long computations.

#include <functional>
#include <string_view>

namespace csgvox {

/// Called now and then by long steps (detection, optimisation, evolution)
/// with the fraction of the step done, in [0, 1], and a short name of the
/// current stage ("noise", "ransac", ...). Returning false asks the step to
/// stop as soon as it can; the step then reports that it was cancelled. An
/// empty callback is never called.
using ProgressCallback = std::function<bool(double fraction, std::string_view stage)>;

}  // namespace csgvox
