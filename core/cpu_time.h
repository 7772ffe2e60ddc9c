#pragma once
/// CPU time of the whole process, to set beside wall-clock time: their
/// ratio over a stage is the number of cores it kept busy.

namespace csgvox {

/// User plus system CPU seconds of this process so far, all threads.
double processCpuSeconds();

}  // namespace csgvox
