#pragma once
/// tree.step: the tree as an exact boundary representation (B-rep), the file
/// any CAD program opens. Boxes, cylinders, cone frustums, spheres and tori
/// become exact solids (planes, cylinders, cones, spheres and tori, not
/// facets); half-spaces and complements become cubes much larger than the
/// part that clip it as they do (as in tree.scad); operations are
/// OpenCASCADE's boolean operations. The result is checked valid and written
/// as STEP AP214 in the scan's units (declared as millimetres), each face
/// named after the primitive whose surface it lies on.

#include <cstddef>
#include <filesystem>
#include <stdexcept>
#include <string>

#include "core/csg_tree.h"
#include "core/run_control.h"

namespace csgvox {

/// Options of the STEP export.
struct StepOptions {
  double halfSpaceScale = 2.0;  ///< edge of the half-space cubes, multiple of the part's diagonal
  bool unifyFaces = true;       ///< merge the pieces of one surface that the booleans split
  bool nameFaces = true;        ///< name each face after the primitive it lies on
  double fuzzy =
      0.0;  ///< boolean tolerance (OpenCASCADE's fuzzy value), fraction of the part's diagonal
  double snapTolerance = 0.00125;  ///< when the tree as it is does not give one solid of its
                                   ///< volume, caps this close are snapped (snapFaces), fraction
                                   ///< of the diagonal (a quarter of the inlier distance); 0: never
  double snapAngle = 1e-6;         ///< directions this close are snapped with them, radians
  double retryFuzzy = 1e-4;        ///< fuzzy value of the retry with fuzzy booleans, fraction of
                                   ///< the diagonal; 0: no such retry
  double volumeTolerance = 0.01;   ///< refuse a solid whose volume differs more from the tree's
                                   ///< (sampled), fraction; 0: no check
  std::string productName = "csgvox part";  ///< name of the solid's product in the file
  /// A cancel request stops the export (between and inside OpenCASCADE's
  /// boolean operations and its STEP translation) with CancelledError; the
  /// export has no deadline.
  RunControl control;
};

/// The tree cannot be built as a valid solid: a boolean operation failed,
/// gave an invalid shape, or the solid is empty. The message names the node.
class CadError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// What a B-rep holds, measured by OpenCASCADE.
struct BrepSummary {
  std::size_t solids = 0;      ///< number of solids
  std::size_t faces = 0;       ///< number of faces
  bool valid = false;          ///< BRepCheck_Analyzer finds no fault
  bool closed = false;         ///< every shell of every solid is closed
  double volume = 0.0;         ///< enclosed volume, scan units cubed
  Aabb bounds;                 ///< tight axis-aligned bounds
  std::size_t namedFaces = 0;  ///< faces named after a primitive (writeStep() only)
};

/// True when this build writes STEP (it was built with OpenCASCADE).
bool stepExportAvailable();

/// Builds the tree's B-rep and writes it as STEP AP214 (replacing `path`
/// only once the file is complete). Returns the written solid's summary.
/// When the tree as it is does not come out as one valid solid of the
/// tree's volume, it is built again with its near-coincident caps snapped
/// (snapFaces(), options.snapTolerance), then with fuzzy booleans
/// (options.retryFuzzy), then with the caps also snapped to the planes
/// tangent to its tori; the first that is one valid solid of the tree's
/// volume is written (else the first valid one of the tree's volume, in
/// several solids).
/// @throw std::invalid_argument for an empty tree or one without a bounded
///        primitive; CadError naming the node whose boolean operation
///        failed or gave a solid whose volume is not the tree's, or when the
///        solid is empty or invalid; IoError when the
///        file cannot be written or the build has no OpenCASCADE.
BrepSummary writeStep(const std::filesystem::path& path, const CsgTree& tree,
                      const StepOptions& options = {});

/// Reads a STEP file with OpenCASCADE's reader and measures its shape.
/// @throw IoError when the file cannot be read or the build has no
///        OpenCASCADE; ParseError when it holds no shape.
BrepSummary readStepSummary(const std::filesystem::path& path);

}  // namespace csgvox
