// The STEP export of a build without OpenCASCADE (CSGVOX_WITH_OCCT=OFF).

#include "cad/step_export.h"
#include "io/errors.h"

namespace csgvox {

bool stepExportAvailable() { return false; }

BrepSummary writeStep(const std::filesystem::path& path, const CsgTree&, const StepOptions&) {
  throw IoError(path.string() +
                ": this build of csgvox has no STEP export (built without "
                "OpenCASCADE)");
}

BrepSummary readStepSummary(const std::filesystem::path& path) {
  throw IoError(path.string() +
                ": this build of csgvox cannot read STEP (built without "
                "OpenCASCADE)");
}

}  // namespace csgvox
