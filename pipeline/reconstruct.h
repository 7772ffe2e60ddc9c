#pragma once
/// The main job as one call: an oriented scan in, a CSG tree out, with
/// every intermediate result and per-stage timings.
///
/// Stages: detect surfaces (RANSAC) → refine (Ceres) → regularise → voxel
/// grid over the minimal oriented box → bounded hypotheses → voxel labels →
/// description sets → Wu's two optimisations and the simplified tree → (hybrid)
/// the genetic search repairs the tree where the points disagree with it.

#include <functional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "core/point_cloud.h"
#include "core/progress.h"
#include "optimize/csg_construction.h"
#include "pipeline/detect_and_fit.h"
#include "pipeline/finish.h"
#include "pipeline/gp_method.h"
#include "pipeline/hybrid_method.h"
#include "primitives/hypotheses.h"
#include "primitives/surface_detection.h"
#include "voxel/description_sets.h"
#include "voxel/labeling.h"
#include "voxel/voxel_grid.h"

namespace csgvox {

/// How the tree is built from the detected surfaces.
enum class Method {
  Hybrid,    ///< the voxel method, then the genetic search repairs its tree where the points
             ///< disagree (pipeline/hybrid_method.h)
  Voxel,     ///< Wu et al.'s bounded hypotheses and two binary optimisations over voxels
  Gp,        ///< the genetic-programming baseline (Fayolle & Pasko 2016) on the points
  Imported,  ///< not built here: a tree read from a file (`compare --import-gp`)
};

/// "hybrid", "voxel", "gp" or "import-gp".
std::string_view methodName(Method method);
/// Inverse of methodName for the methods that build trees ("hybrid", "voxel", "gp").
/// @throw std::invalid_argument for other names.
Method methodFromName(std::string_view name);

/// Options of reconstruct().
struct ReconstructOptions {
  Method method = Method::Hybrid;  ///< how the tree is built
  int resolution = 64;             ///< voxels along the longest side of the part's oriented box
  /// Up to twice the resolution when the surfaces show a feature thinner
  /// than two voxels (DetectAndFitOptions::refineThin).
  bool refineThin = true;
  std::uint64_t seed = 1;          ///< seeds detection and hypotheses; same seed, same tree
  DetectOptions detect;            ///< surface detection (its seed is replaced by `seed`)
  LabelOptions labels;             ///< voxel labelling
  ConstructOptions construct;  ///< voxel method: the two optimisations (snapDistance 0: one voxel)
  HybridOptions hybrid;        ///< hybrid method: the refinement (its seed is set from `seed`)
  FinishOptions finish;        ///< hybrid method: the parameter fit last (its fitness is set from
                               ///< hybrid.fitness)
  GpOptions gp;                ///< gp method: the search (its seed and time limit are set from
                               ///< `seed` and `timeLimit`)
  /// Wall-clock seconds for the whole call (0: none). Detection past the
  /// limit fails (status TimedOut); after detection a limit never costs the
  /// tree: labels and description sets run to their end, and the
  /// optimisations stop searching and keep the best solution their local
  /// search found, so the tree is still valid but may not be the proved
  /// optimum (stats.provedOptimal is then false). A limit that is hit makes
  /// the result depend on the machine's speed.
  double timeLimit = 0.0;
  /// Bytes the voxel stage may use (0: no limit). The description sets take
  /// about candidates × voxels / 8 bytes and the optimisation up to twice
  /// that again; a resolution that would need more fails before labelling
  /// with a message naming the largest resolution that fits.
  std::size_t memoryLimit = std::size_t(4) << 30;
};

/// Seconds spent in one stage.
struct StageTime {
  std::string stage;
  double seconds = 0.0;
};

/// Everything reconstruct() produced.
struct Reconstruction {
  enum class Status {
    Ok,             ///< `tree` holds the result
    NoSurfaces,     ///< detection found nothing usable (see message)
    NoCombination,  ///< no combination of the hypotheses explains the labelled voxels
    TimedOut,       ///< the time limit ran out before a tree existed
    TooLarge,       ///< the voxel stage would need more than memoryLimit
  };
  Status status = Status::NoSurfaces;
  std::string message;  ///< one line: what was built, or why nothing was
  CsgTree tree;         ///< the result (empty unless Ok)
  DetectionResult detection;
  HypothesisSet hypotheses;
  VoxelGrid grid;
  int resolution = 0;              ///< the grid's (finer than asked when the part is thin)
  std::vector<ThinFeature> thin;   ///< features thinner than two voxels at the asked resolution
  VoxelLabels labels;
  Method method = Method::Voxel;   ///< the method that built `tree`
  Construction construction;       ///< voxel method: the optimisations' result
  GpResult gp;                     ///< gp method: the search's result
  HybridResult hybrid;             ///< hybrid method: what the refinement changed
  FinishResult finish;             ///< hybrid method: what the parameter fit did
  CsgTree voxelTree;               ///< hybrid method: the voxel stage's tree it refined
  VoxelSet voxels;                 ///< voxels whose centre `tree` holds
  std::vector<StageTime> timings;  ///< in pipeline order
  bool timeLimitHit = false;       ///< the limit stopped a search early

  bool ok() const { return status == Status::Ok; }
  /// Voxel IoU of the tree's voxels against the inside labels.
  double voxelIou() const;
};

/// Runs the whole reconstruction on an oriented scan. `progress`, when
/// given, is called now and then inside the long stages (detection and the
/// optimisation) with the fraction of the stage done and a short name of its
/// current step. Its return value is ignored: timeLimit bounds a run.
/// @throw std::invalid_argument when the scan has no normals or is empty.
Reconstruction reconstruct(const PointCloud& scan, const ReconstructOptions& options = {},
                           const StageCallback& onStage = {},
                           const ProgressCallback& progress = {});

/// The stages after detection (labels, then the method's own), on surfaces
/// and candidates detectAndFit() already made for this scan with the same
/// resolution and seed: what `csgvox compare` runs once per method. The time
/// limit counts from this call. `found` must be ok().
/// @throw std::invalid_argument when `found` is not ok() or the scan has no normals.
Reconstruction reconstructDetected(const PointCloud& scan, const SurfacesAndCandidates& found,
                                   const ReconstructOptions& options = {},
                                   const StageCallback& onStage = {},
                                   const ProgressCallback& progress = {});

}  // namespace csgvox
