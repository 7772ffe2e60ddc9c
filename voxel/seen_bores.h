#pragma once
/// Labels completed by the bores the detection saw. A scanner sees a bore's
/// wall near its ends and little of the inside: the winding number of the
/// points then reads 0.5 to 0.85 along the unseen middle, and the labels fill
/// the bore. A concave cylinder whose inliers lie all around its axis is a
/// bore or a hole: along the stretch its inliers span, its inside is air
/// wherever its wall was not seen all around (where it was, the winding
/// number is reliable and the labels stay) and no points show material
/// across it (a floor, a boss standing in a round pocket). Past either end
/// it is extended through a plug of inside labels that no floor closes, when
/// the extension reaches air: a branch's bore into the run's, seen only near
/// its mouth, or a bore into the outside through a face no view saw, which
/// the labels close only where it is material (primitives/unseen_faces.h).
/// Otherwise it ends where it was seen, so a hole whose floor would show,
/// or whose far end the scan shows closed, invents no depth.

#include <cstddef>
#include <span>

#include "core/point_cloud.h"
#include "core/surface.h"
#include "voxel/voxel_grid.h"
#include "voxel/voxel_set.h"

namespace csgvox {

/// Options of openSeenBores.
struct BoreOpeningOptions {
  bool enabled = true;  ///< false leaves the labels as the points give them
  /// Of 12 sectors around the axis, those that must hold inliers for a bore,
  /// and in a slab one voxel thick for its wall to count as seen there (count).
  int minSectors = 10;
  /// Smallest bore radius, in voxels (ratio): a hole 3 voxels wide holds
  /// about 7 voxel centres in each slab across it.
  double minRadiusVoxels = 1.5;
  /// A slab of the bore, one voxel thick, is closed (material across it)
  /// when the points inside its disc number at least this share of the bore
  /// wall's own points in a slab (ratio) ...
  double materialShare = 0.25;
  std::size_t minMaterialPoints = 4;  ///< ... and at least this many (count): strays are none
  /// An extension past an end reaches a bore's air at a disc with at least
  /// this share of its voxels opened in a bore's seen stretch (ratio).
  double airShare = 0.25;
};

/// What openSeenBores did.
struct BoreOpening {
  std::size_t bores = 0;     ///< concave cylinders seen all around their axis (count)
  std::size_t extended = 0;  ///< ends extended through an unseen plug into air (count)
  std::size_t voxels = 0;    ///< voxels turned from inside to outside (count)
};

/// Turns to outside the inside voxels of `inside` whose centres lie in the
/// bores among `surfaces` (fitted, with their inliers, indices into `scan`),
/// as the header comment says. Deterministic; `inside` must be over `grid`.
BoreOpening openSeenBores(const VoxelGrid& grid, const PointCloud& scan,
                          std::span<const Surface> surfaces, VoxelSet& inside,
                          const BoreOpeningOptions& options = {});

}  // namespace csgvox
