#pragma once
/// The main job as one call: an oriented scan in, a CSG tree out, with
/// every intermediate result and per-stage timings.
///
/// Stages: detect surfaces (RANSAC) → refine (Ceres) → regularise → voxel
/// grid over the minimal oriented box → bounded hypotheses → voxel labels →
/// description sets → Wu's two optimisations and the simplified tree → (hybrid)
/// the genetic search repairs the tree where the points disagree with it.

#include <array>
#include <functional>
#include <span>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "core/named_values.h"
#include "core/point_cloud.h"
#include "core/progress.h"
#include "core/run_control.h"
#include "optimize/csg_construction.h"
#include "pipeline/detect_and_fit.h"
#include "pipeline/finish.h"
#include "pipeline/gp_method.h"
#include "pipeline/hybrid_method.h"
#include "primitives/hypotheses.h"
#include "primitives/surface_detection.h"
#include "primitives/unseen_faces.h"
#include "voxel/description_sets.h"
#include "voxel/labeling.h"
#include "voxel/seen_bores.h"
#include "voxel/voxel_grid.h"

namespace csgvox {

/// How the tree is built from the detected surfaces.
enum class Method {
  Hybrid,  ///< the voxel method, then the genetic search repairs its tree where the points
           ///< disagree (pipeline/hybrid_method.h)
  Voxel,   ///< Wu et al.'s bounded hypotheses and two binary optimisations over voxels
  Gp,      ///< the genetic-programming baseline (Fayolle & Pasko 2016) on the points
};

/// The names of the methods ("hybrid", "voxel", "gp"), as users give them.
inline constexpr std::array<NamedValue<Method>, 3> kMethodNames = {{
    {"hybrid", Method::Hybrid},
    {"voxel", Method::Voxel},
    {"gp", Method::Gp},
}};

/// "hybrid", "voxel" or "gp".
std::string_view methodName(Method method);
/// Inverse of methodName.
/// @throw std::invalid_argument for other names.
Method methodFromName(std::string_view name);

/// Options of reconstruct().
struct ReconstructOptions {
  Method method = Method::Hybrid;  ///< how the tree is built
  int resolution = 64;             ///< voxels along the longest side of the part's oriented box
  /// Up to twice the resolution when the surfaces show a feature thinner
  /// than two voxels (DetectAndFitOptions::finerGrid).
  bool finerGrid = true;
  std::uint64_t seed = 1;      ///< seeds detection and hypotheses; same seed, same tree
  DetectOptions detect;        ///< surface detection (its seed is replaced by `seed`)
  LabelOptions labels;         ///< voxel labelling
  UnseenFaceOptions unseen;    ///< labels closed over faces never seen (primitives/unseen_faces.h)
  BoreOpeningOptions bores;    ///< labels completed by the bores seen (voxel/seen_bores.h)
  RimHoleOptions rims;         ///< holes and windows found from their rims (raw scans)
  bool sheetRounds = true;     ///< a thin sheet's edges read as rounds made edges (raw scans)
  ConstructOptions construct;  ///< voxel method: the two optimisations (snapDistance 0: one voxel)
  HybridOptions hybrid;        ///< hybrid method: the repair search (its seed is set from `seed`)
  FinishOptions finish;        ///< hybrid method: the parameter fit last (its fitness is set from
                               ///< hybrid.fitness)
  GpOptions gp;                ///< gp method: the search (its seed and control are set from
                               ///< `seed` and the call's RunControl)
  /// Bytes the voxel stage may use (0: no limit). The description sets take
  /// about candidates × voxels / 8 bytes and the optimisation up to twice
  /// that again; a resolution that would need more fails before labelling
  /// with a message naming the largest resolution that fits.
  std::size_t memoryLimit = std::size_t(4) << 30;
};

/// The accepted range of every numeric option a user sets (command line,
/// Python): validate() checks them, and the command line shows the same.
namespace option_ranges {
inline constexpr OptionRange resolution{8, 1024};      ///< voxels along the longest side
inline constexpr OptionRange meshResolution{8, 2048};  ///< mesh.ply's grid
inline constexpr OptionRange timeLimit{0.0, 1e6};      ///< seconds (a RunControl's)
inline constexpr OptionRange neighbors{1, 1000};       ///< vote: K
inline constexpr OptionRange voteEpsilon{0.0, 1.0};    ///< vote: facing fraction
inline constexpr OptionRange fitWeight{0.0, 100.0};    ///< voxel: alpha, beta of Wu Eq. 4, 6
inline constexpr OptionRange generations{0, 1e7};      ///< most generations, or stall length
inline constexpr OptionRange searches{1, 64};          ///< hybrid: searches per region
inline constexpr OptionRange population{3, 100000};    ///< creatures per generation
inline constexpr OptionRange angle{0.1, 180.0};        ///< degrees
inline constexpr OptionRange probability{0.0, 1.0};    ///< crossover, mutation
inline constexpr OptionRange maxDepth{2, 1000};        ///< gp: levels
inline constexpr OptionRange distance{1e-6, 1.0};      ///< gp: fraction of the diagonal
inline constexpr OptionRange voxelWeight{0.0, 1e6};    ///< gp: weight of the volumetric term
inline constexpr OptionRange roughPoints{0, 1e9};      ///< gp: points per rough generation
}  // namespace option_ranges

/// Checks every user-set option of `options` against option_ranges.
/// @throw std::invalid_argument "<option> must be in [lo, hi]" for the first one outside.
void validate(const ReconstructOptions& options);

/// Seconds spent in one stage.
struct StageTime {
  std::string stage;
  double seconds = 0.0;     ///< wall-clock seconds
  double cpuSeconds = 0.0;  ///< CPU seconds of the process, all threads
};

/// What the voxel method built.
struct VoxelMethodResult {
  Construction construction;  ///< the optimisations' result
};

/// What the hybrid method built: the voxel method's tree, then the repair.
struct HybridMethodResult {
  Construction construction;  ///< the voxel stage's optimisations
  CsgTree voxelTree;          ///< the voxel stage's tree, before the repair
  HybridResult repair;        ///< what the genetic repair search changed
  FinishResult finish;        ///< what the parameter fit did (finish.ran: whether it ran)
};

/// What the genetic-programming baseline built.
struct GpMethodResult {
  GpResult gp;  ///< the search's result
};

/// One method's own result; empty (monostate) until a method has run.
using MethodResult =
    std::variant<std::monostate, VoxelMethodResult, HybridMethodResult, GpMethodResult>;

/// Everything reconstruct() produced.
struct Reconstruction {
  enum class Status {
    Ok,             ///< `tree` holds the result
    NoSurfaces,     ///< detection found nothing usable (see message)
    NoCombination,  ///< no combination of the hypotheses explains the labelled voxels
    TimedOut,       ///< the time limit ran out before a tree existed
    TooLarge,       ///< the voxel stage would need more than memoryLimit
    Cancelled,      ///< the RunControl was cancelled (no tree)
  };
  Status status = Status::NoSurfaces;
  std::string message;  ///< one line: what was built, or why nothing was
  CsgTree tree;         ///< the result (empty unless Ok)
  DetectionResult detection;
  HypothesisSet hypotheses;
  VoxelGrid grid;
  int resolution = 0;              ///< the grid's (finer than asked when the part is thin)
  std::vector<ThinFeature> thin;   ///< features thinner than two voxels at the asked resolution
  std::size_t holesFromRims = 0;   ///< hole cylinders found from their rims (raw scans)
  std::size_t rimWindows = 0;      ///< windows found from their rims (raw scans)
  std::size_t boresFromWalls = 0;  ///< bore and boss cylinders found from their walls (raw scans)
  std::size_t facesFromPoints = 0;  ///< narrow faces found from their points (raw scans)
  /// Rounds that were a thin sheet's square edges: tori dropped, cylinders
  /// made end faces (raw scans; primitives/sheet_rounds.h).
  std::size_t sheetEdges = 0;
  /// Points the labels, the optimisation and the repair worked on: all of
  /// the scan's, or, for a scan larger than the detection's search
  /// (DetectOptions::ransacPoints), the even subsample detection searched
  /// (the genetic baseline keeps all). Count.
  std::size_t pointsAfterDetection = 0;
  /// Points added for the labels only, on hull faces no view saw (count)
  std::size_t unseenFacePoints = 0;
  BoreOpening boreOpening;  ///< inside labels turned outside in the bores seen
  VoxelLabels labels;
  Method method = Method::Voxel;   ///< the method asked for
  MethodResult result;             ///< the method's own result (monostate when none ran)
  VoxelSet voxels;                 ///< voxels whose centre `tree` holds
  std::vector<StageTime> timings;  ///< in pipeline order
  bool timeLimitHit = false;       ///< the limit stopped a search early

  bool ok() const { return status == Status::Ok; }
  /// Voxel IoU of the tree's voxels against the inside labels.
  double voxelIou() const;
  /// The method's result when it is a T, else null.
  template <class T>
  const T* resultAs() const {
    return std::get_if<T>(&result);
  }
};

/// Runs the whole reconstruction on an oriented scan. `onStage` hears each
/// stage start and end (with a one-line summary). `control` bounds the run:
/// its progress callback hears the long stages' fraction done and current
/// step; past its deadline detection fails (status TimedOut), while after
/// detection a limit never costs the tree: labels and description sets run
/// to their end, and the optimisations and searches stop and keep the best
/// solution found so far (the tree is valid but may not be the proved
/// optimum; stats.provedOptimal is then false, timeLimitHit true; the result
/// then depends on the machine's speed). A cancel request (control.cancel(),
/// or the progress callback returning false) stops whatever stage runs,
/// with status Cancelled and no tree.
/// @throw std::invalid_argument when the scan has no normals or is empty.
Reconstruction reconstruct(const PointCloud& scan, const ReconstructOptions& options = {},
                           const StageCallback& onStage = {}, const RunControl& control = {});

/// The stages after detection (labels, then the method's own), on surfaces
/// and candidates detectAndFit() already made for this scan with the same
/// resolution and seed: what `csgvox compare` runs once per method. `found`
/// must be ok().
/// @throw std::invalid_argument when `found` is not ok() or the scan has no normals.
Reconstruction reconstructDetected(const PointCloud& scan, const SurfacesAndCandidates& found,
                                   const ReconstructOptions& options = {},
                                   const StageCallback& onStage = {},
                                   const RunControl& control = {});

}  // namespace csgvox
