#pragma once
/// The least-squares solver's own log (Ceres writes through glog).

namespace csgvox {

/// How much of the solver's log reaches stderr.
enum class SolverLog {
  Errors,  ///< errors only: the per-step warnings of a fit that recovers are dropped
  None,    ///< nothing
};

/// Sets the level of the solver's log for the whole process.
void setSolverLog(SolverLog level);

}  // namespace csgvox
