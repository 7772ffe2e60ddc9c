#pragma once
/// Least-squares refinement of every primitive parameter of a CSG tree on
/// scan points, through the tree's field: each point near the tree's surface
/// contributes the field value there (a signed distance, in units of εd)
/// under a robust loss, and the parameters move as shared blocks
/// (primitives/tree_parameters.h), so parallel and orthogonal directions,
/// coplanar faces, coaxial axes and equal radii stay exactly so.
///
/// The field is the set operations' (SARDF by default): its value is C¹
/// away from sharp edges, so a point near an edge pulls on both faces that
/// meet there, weighted by the operations' partial derivatives, instead of
/// on one face that min/max picks. Derivatives of each primitive's distance
/// with respect to its parameters are central differences; those of the
/// tree with respect to its leaves are exact (chain rule through the
/// operations).

#include <cstddef>
#include <cstdint>
#include <span>

#include "core/csg_tree.h"
#include "core/sardf.h"
#include "core/set_operations.h"
#include "primitives/tree_parameters.h"

namespace csgvox {

/// Options of fitTreeParameters.
struct TreeFitOptions {
  SetOperationKind operations = SetOperationKind::Sardf;  ///< field the residuals are taken through
  double sardfRadius = kSardfRadiusFraction;  ///< SARDF blending radius R, fraction of D
  double distanceTolerance = 0.01;  ///< εd, fraction of D: the unit of the residuals
  double lossScale = 1.0;           ///< Huber scale of the residuals, in εd
  double nearDistance = 3.0;  ///< only points this close to the tree's surface drive the fit, in εd
  int maxIterations = 25;     ///< Levenberg-Marquardt iterations at most (count)
  std::size_t maxPoints = 20000;  ///< more points than this are thinned to an even subset (count)
  TreeParameterOptions parameters;  ///< which relations are shared parameters
};

/// What fitTreeParameters did.
struct TreeFitResult {
  CsgTree tree;                       ///< the tree with fitted parameters (the input if none fitted)
  std::size_t points = 0;             ///< points that drove the fit
  double rmsBefore = 0.0;             ///< RMS field value at those points on the input tree, units
  double rmsAfter = 0.0;              ///< the same on the fitted tree
  std::size_t parameters = 0;         ///< free parameters after sharing
  std::size_t sharedBlocks = 0;       ///< parameter blocks several leaves share (relations kept)
  std::size_t primitivesChanged = 0;  ///< distinct leaves whose primitive moved
  int iterations = 0;                 ///< solver iterations
  bool converged = false;             ///< the solver met its tolerances
};

/// Fits the parameters of `tree` to `points`. `diagonal` is the scan's D,
/// which scales εd, R and the tolerances. With fewer than 10 points near the
/// surface nothing is fitted (the result's tree is the input).
/// @throw std::invalid_argument for an empty tree, no points, or D not > 0.
TreeFitResult fitTreeParameters(std::span<const Vec3> points, double diagonal,
                                const CsgTree& tree, const TreeFitOptions& options = {});

}  // namespace csgvox
