#pragma once
/// Progress and timing lines on stderr for the command-line tool and the job.

#include <chrono>
#include <cstdio>
#include <memory>
#include <string>

#include "core/cpu_time.h"
#include "core/progress.h"

namespace csgvox {

/// Prints "[  1.23 s] message" lines on stderr unless quiet.
class Console {
 public:
  explicit Console(bool quiet) : quiet_(quiet), start_(std::chrono::steady_clock::now()) {}
  /// Seconds since the console was created.
  double elapsed() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }
  void info(const std::string& message) const {
    if (!quiet_) std::fprintf(stderr, "[%7.2f s] %s\n", elapsed(), message.c_str());
  }
  bool quiet() const { return quiet_; }
  /// A progress callback for a long step: a line "  STEP NN %" every
  /// `everySeconds` while the step runs. Never cancels.
  ProgressCallback progress(double everySeconds = 3.0) const {
    auto last = std::make_shared<double>(elapsed());
    return [this, last, everySeconds](double fraction, std::string_view step) {
      if (elapsed() - *last >= everySeconds) {
        *last = elapsed();
        info("  " + std::string(step) + " " + std::to_string(int(100.0 * fraction)) + " %");
      }
      return true;
    };
  }

 private:
  bool quiet_;
  std::chrono::steady_clock::time_point start_;
};

/// Stopwatch for per-stage timings: wall-clock and process CPU seconds.
class Stopwatch {
 public:
  Stopwatch() : start_(std::chrono::steady_clock::now()), cpuStart_(processCpuSeconds()) {}
  /// Wall-clock seconds since construction.
  double seconds() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }
  /// CPU seconds of the process (all threads) since construction.
  double cpuSeconds() const { return processCpuSeconds() - cpuStart_; }

 private:
  std::chrono::steady_clock::time_point start_;
  double cpuStart_;
};

}  // namespace csgvox
