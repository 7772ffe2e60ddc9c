#pragma once
/// Wall-clock and peak-memory readings shared by the benchmark executables.

#include <sys/resource.h>

#include <chrono>

namespace csgvox::bench {

/// Seconds since `since`.
inline double seconds(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

/// Peak resident memory of this process so far, MiB.
inline double peakMiB() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_maxrss) / 1024.0;  // Linux reports KiB
}

}  // namespace csgvox::bench
