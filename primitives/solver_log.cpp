// The solver's log level: Ceres logs through glog, which only this module sees.

#include "primitives/solver_log.h"

#include <glog/logging.h>

namespace csgvox {

void setSolverLog(SolverLog level) {
  FLAGS_minloglevel = level == SolverLog::None ? google::GLOG_FATAL : google::GLOG_ERROR;
}

}  // namespace csgvox
