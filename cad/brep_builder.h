#pragma once
// Internal to cad/: the tree as an OpenCASCADE shape. OpenCASCADE types
// appear here and must not reach any header outside this folder.

#include <Message_ProgressIndicator.hxx>
#include <TopoDS_Shape.hxx>
#include <string>
#include <utility>
#include <vector>

#include "cad/step_export.h"

namespace csgvox::cad {

/// The tree's solid (one solid, or a compound of several) and the name of
/// the primitive each face lies on (faces of no primitive are left out).
struct BrepResult {
  TopoDS_Shape shape;                                           // the solid
  std::vector<std::pair<TopoDS_Shape, std::string>> faceNames;  // face, primitive name
};

/// Builds and checks the solid. @throw as writeStep().
BrepResult buildBrep(const CsgTree& tree, const StepOptions& options);

/// Measures a shape (see BrepSummary).
BrepSummary summarize(const TopoDS_Shape& shape);

// A progress indicator whose user break is `control`'s cancel request, for
// OpenCASCADE's algorithms that take a Message_ProgressRange.
Handle(Message_ProgressIndicator) cancelIndicator(const RunControl& control);

}  // namespace csgvox::cad
