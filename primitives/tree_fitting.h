#pragma once
/// Least-squares refinement of every primitive parameter of a CSG tree on
/// scan points, through the tree's field: each point near the tree's surface
/// contributes the field value there (a signed distance, in units of εd)
/// under a robust loss, and the parameters move as shared blocks
/// (primitives/tree_parameters.h), so parallel and orthogonal directions,
/// coplanar faces, coaxial axes and equal radii stay exactly so.
///
/// Each point is tied to the face of its leaf it was scanned on (the face
/// whose normal agrees with the point's): that leaf's value at the point is
/// the signed distance to the face's whole surface (plane, infinite cylinder
/// or cone), so a noisy point just inside an edge is not read on the other
/// face, which would push every face outwards. The field is min/max by
/// default: SARDF's arcs read a point inside (or outside) both operands near
/// an edge as deeper than it is (up to 17-23 %, core/sardf.h), which on the
/// bundled noisy scans moved faces and lowered the IoU against the true part
/// more than min/max did. Derivatives of a leaf's value with respect to its
/// parameters are central differences; those of the tree with respect to
/// its leaves are exact (chain rule through the operations).

#include <cstddef>
#include <cstdint>
#include <span>

#include "core/csg_tree.h"
#include "core/point_cloud.h"
#include "core/sardf.h"
#include "core/set_operations.h"
#include "primitives/tree_parameters.h"

namespace csgvox {

/// Options of fitTreeParameters.
struct TreeFitOptions {
  SetOperationKind operations =
      SetOperationKind::MinMax;               ///< field the residuals are taken through
  double sardfRadius = kSardfRadiusFraction;  ///< SARDF blending radius R, fraction of D
  double distanceTolerance = 0.01;            ///< εd, fraction of D: the unit of the residuals
  double lossScale = 1.0;                     ///< Huber scale of the residuals, in εd
  double nearDistance = 3.0;  ///< only points this close to the tree's surface drive the fit, in εd
  double nearAngle = 30.0;    ///< ... and whose normal is this close to the tree's there, degrees
  double priorWeight = 1.0;   ///< each parameter block is held to its start as strongly as this
                              ///< many points would hold it (so what no point sees stays put)
  int maxIterations = 25;     ///< Levenberg-Marquardt iterations at most (count)
  std::size_t maxPoints = 20000;    ///< more points than this are thinned to an even subset (count)
  TreeParameterOptions parameters;  ///< which relations are shared parameters
};

/// What fitTreeParameters did.
struct TreeFitResult {
  CsgTree tree;                  ///< the tree with fitted parameters (the input if none fitted)
  std::size_t points = 0;        ///< points that drove the fit
  double rmsBefore = 0.0;        ///< RMS field value at those points on the input tree, units
  double rmsAfter = 0.0;         ///< the same on the fitted tree
  std::size_t parameters = 0;    ///< free parameters after sharing
  std::size_t sharedBlocks = 0;  ///< parameter blocks several leaves share (relations kept)
  std::size_t primitivesChanged = 0;  ///< distinct leaves whose primitive moved
  int iterations = 0;                 ///< solver iterations
  bool converged = false;             ///< the solver met its tolerances
};

/// Fits the parameters of `tree` to the points of `scan` (its diagonal D
/// scales εd, R and the tolerances; its normals, when it has them, select
/// the points whose normal agrees with the tree's). With fewer than 10 points
/// near the surface nothing is fitted (the result's tree is the input).
/// @throw std::invalid_argument for an empty tree or scan.
TreeFitResult fitTreeParameters(const PointCloud& scan, const CsgTree& tree,
                                const TreeFitOptions& options = {});

}  // namespace csgvox
