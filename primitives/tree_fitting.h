#pragma once
/// Least-squares refinement of every primitive parameter of a CSG tree on
/// scan points, with the parameters moving as shared blocks
/// (primitives/tree_parameters.h), so parallel and orthogonal directions,
/// same-facing coplanar faces, coaxial axes and equal radii stay exactly so.
///
/// The tree's field decides which points drive the fit and what they pull
/// on: a point within nearDistance of the tree's surface is tied to the
/// exposed face it was scanned on — a face of a leaf (a box face, a
/// cylinder's or cone's lateral surface or cap, a plane, a sphere, a torus)
/// within the band, whose normal as the solid sees it (flipped for a cutter)
/// agrees best with the point's normal (within nearAngle), and on which the
/// tree's field vanishes at the point's foot. Its residual is its signed
/// distance to that face's whole surface (plane, infinite cylinder or cone),
/// in units of εd, under a Huber loss. This is the tree's field wherever
/// the point lies in its face's region; it differs near edges and across
/// thin walls, where the field (min/max or SARDF) reads a noisy point on the
/// other face: fitting the field itself (throughField) dropped or misread
/// those points and moved faces outwards on noisy scans (a 1 mm tray's walls
/// grew 13 %). `operations` is the field of that selection; min/max by
/// default (SARDF's arcs read points near edges deeper than they are, up to
/// 17–23 %, core/sardf.h). Derivatives of a face's distance with respect to
/// its parameters are central differences.

#include <cstddef>
#include <cstdint>
#include <span>

#include "core/csg_tree.h"
#include "core/point_cloud.h"
#include "core/run_control.h"
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
  bool throughField = false;  ///< residual: the tree's field with each leaf read on the point's
                              ///< face (true), or the signed distance to the exposed face of the
                              ///< tree the point was scanned on (false; see above)
  double priorWeight = 1.0;   ///< each parameter block is held to its start as strongly as this
                              ///< many points would hold it (so what no point sees stays put)
  int maxIterations = 25;     ///< Levenberg-Marquardt iterations at most (count)
  std::size_t maxPoints = 20000;    ///< more points than this are thinned to an even subset (count)
  TreeParameterOptions parameters;  ///< which relations are shared parameters
  /// Checked every iteration: past its deadline the fit stops with the
  /// parameters it has; cancelled, it stops and fits nothing.
  RunControl control;
};

/// What fitTreeParameters did.
struct TreeFitResult {
  CsgTree tree;                  ///< the tree with fitted parameters (the input if none fitted)
  std::size_t points = 0;        ///< points that drove the fit
  double rmsBefore = 0.0;        ///< RMS field value at those points on the input tree, units
  double rmsAfter = 0.0;         ///< the same on the fitted tree
  std::size_t parameters = 0;    ///< free parameters after sharing
  std::size_t sharedBlocks = 0;  ///< parameter blocks several leaves share (relations kept)
  std::size_t primitivesChanged = 0;  ///< distinct leaves with a parameter moved by > 1e-6·D
  int iterations = 0;                 ///< solver iterations
  bool converged = false;             ///< the solver met its tolerances
  bool cancelled = false;             ///< options.control was cancelled: nothing fitted
};

/// Fits the parameters of `tree` to the points of `scan` (its diagonal D
/// scales εd, R and the tolerances; its normals, when it has them, select
/// the points whose normal agrees with the tree's). With fewer than 10 points
/// near the surface nothing is fitted (the result's tree is the input).
/// @throw std::invalid_argument for an empty tree or scan.
TreeFitResult fitTreeParameters(const PointCloud& scan, const CsgTree& tree,
                                const TreeFitOptions& options = {});

}  // namespace csgvox
