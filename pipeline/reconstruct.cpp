#include "pipeline/reconstruct.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <stdexcept>

#include "core/cpu_time.h"
#include "core/nearest_neighbors.h"
#include "core/run_control.h"
#include "evolve/redundancy.h"

namespace csgvox {
namespace {

using Clock = std::chrono::steady_clock;

std::string dimsText(const VoxelGrid& grid) {
  const auto& d = grid.dims();
  return std::to_string(d[0]) + " x " + std::to_string(d[1]) + " x " + std::to_string(d[2]);
}

// Times one stage, reports its start and end, and records its duration.
class StageClock {
 public:
  StageClock(Reconstruction& out, const StageCallback& onStage) : out_(out), onStage_(onStage) {}
  void start(std::string_view stage) {
    stage_ = stage;
    start_ = Clock::now();
    cpuStart_ = processCpuSeconds();
    if (onStage_) onStage_(stage_, false, {});
  }
  void finish(const std::string& summary) {
    const double s = std::chrono::duration<double>(Clock::now() - start_).count();
    out_.timings.push_back({std::string(stage_), s, processCpuSeconds() - cpuStart_});
    if (onStage_) onStage_(stage_, true, summary);
  }

 private:
  Reconstruction& out_;
  const StageCallback& onStage_;
  std::string_view stage_;
  Clock::time_point start_;
  double cpuStart_ = 0.0;
};

}  // namespace

double Reconstruction::voxelIou() const { return VoxelSet::iou(voxels, labels.inside); }

std::string_view methodName(Method method) { return nameOf<Method>(kMethodNames, method); }

Method methodFromName(std::string_view name) {
  return valueNamed<Method>(kMethodNames, name, "method");
}

void validate(const ReconstructOptions& o) {
  namespace r = option_ranges;
  checkRange("res", o.resolution, r::resolution);
  checkRange("neighbors", o.labels.neighbors, r::neighbors);
  checkRange("vote_epsilon", o.labels.epsilon, r::voteEpsilon);
  checkRange("alpha", o.construct.subtree.alpha, r::fitWeight);
  checkRange("beta", o.construct.unionChoice.beta, r::fitWeight);
  const HybridOptions& h = o.hybrid;
  checkRange("repair_generations", double(h.evolve.maxGenerations), r::generations);
  checkRange("repair_stall", double(h.evolve.stallGenerations), r::generations);
  checkRange("repair_searches", double(h.searches), r::searches);
  checkRange("repair_population", double(h.evolve.population), r::population);
  checkRange("bad_angle", h.badAngle, r::angle);
  const GpOptions& g = o.gp;
  checkRange("population", double(g.evolve.population), r::population);
  checkRange("generations", double(g.evolve.maxGenerations), r::generations);
  checkRange("stall", double(g.evolve.stallGenerations), r::generations);
  checkRange("crossover", g.evolve.crossoverRate, r::probability);
  checkRange("mutation", g.evolve.mutationRate, r::probability);
  checkRange("max_depth", g.evolve.variation.maxDepth, r::maxDepth);
  checkRange("angle", g.fitness.angleTolerance, r::angle);
  checkRange("distance", g.fitness.distanceTolerance, r::distance);
  checkRange("voxel_weight", g.fitness.voxelWeight, r::voxelWeight);
  checkRange("rough_points", double(g.roughPoints), r::roughPoints);
}

namespace {

// The optimisations of Wu et al. on the labelled voxels.
Construction voxelMethod(Reconstruction& out, const PointCloud& scan,
                         const ReconstructOptions& options, StageClock& clock,
                         const RunControl& control) {
  clock.start("description_sets");
  std::vector<CsgTree> candidates;
  candidates.reserve(out.hypotheses.candidates.size());
  for (const Candidate& c : out.hypotheses.candidates) candidates.push_back(c.tree);
  const std::vector<DescriptionSet> descriptions =
      describeAll(candidates, out.grid, out.labels, control);
  clock.finish(std::to_string(descriptions.size()) + " sets");
  if (control.cancelled()) return {};

  clock.start("optimisation");
  ConstructOptions co = options.construct;
  co.seed = options.seed;
  if (co.snapDistance == 0.0) co.snapDistance = out.grid.voxelSize();
  // Scan points decide whether a sub-voxel skin is a real wall.
  const NearestNeighbors scanIndex(scan.points);
  const double nearScan = std::max(0.5 * out.grid.voxelSize(), 3.0 * out.detection.noise);
  if (!co.scannedAt) {
    co.scannedAt = [&](const Vec3& p) {
      double d2 = 0.0;
      scanIndex.nearest(p, &d2);
      return d2 <= nearScan * nearScan;
    };
  }
  co.subtree.control = control;
  co.unionChoice.control = control;
  Construction built =
      constructCsg(candidates, descriptions, out.labels.inside, co, control.asProgress());
  out.timeLimitHit = out.timeLimitHit || control.pastDeadline();
  const ConstructStats& st = built.stats;
  clock.finish(std::to_string(st.chosen) +
               (st.chosen == 1 ? " union member (" : " union members (") +
               std::to_string(st.selected) + " of " + std::to_string(st.unionCandidates) +
               " candidates selected" +
               (st.chosen != st.selected ? ", then changed by the union search" : "") +
               (st.provedOptimal ? ", proved optimal)" : ")"));
  out.tree = built.tree;
  out.voxels = built.voxels;
  return built;
}

// The genetic-programming baseline on the points.
void gpMethod(Reconstruction& out, const PointCloud& scan, const ReconstructOptions& options,
              StageClock& clock, const RunControl& control) {
  clock.start("evolve");
  GpOptions go = options.gp;
  go.evolve.seed = options.seed;
  go.evolve.control = control;
  VoxelTarget target;
  if (go.fitness.voxelWeight > 0.0) target = {out.grid, out.labels.inside};
  const std::size_t most = go.evolve.maxGenerations;
  GpResult gp = runGp(
      scan, out.detection.surfaces, go,
      [&](const GenerationReport& g) {
        char step[160];
        std::snprintf(step, sizeof(step), "generation %zu, best %.6g, %zu nodes, %.0f gen/s%s",
                      g.generation, g.bestFitness, g.bestNodes,
                      g.seconds > 0 ? double(g.generation) / g.seconds : 0.0,
                      g.rough ? " (rough)" : "");
        return control.report(most > 0 ? double(g.generation) / double(most) : 1.0, step);
      },
      go.fitness.voxelWeight > 0.0 ? &target : nullptr);
  out.timeLimitHit = out.timeLimitHit || gp.search.stop == EvolveStop::TimeLimit;
  if (control.cancelled()) {
    clock.finish("cancelled");
    return;
  }
  const EvolveResult& s = gp.search;
  char summary[200];
  std::snprintf(summary, sizeof(summary),
                "%zu generations (%s), %zu trees evaluated, fitness %.6g, %zu primitives in the "
                "library (%zu separators)",
                s.generations, std::string(evolveStopName(s.stop)).c_str(), s.evaluations,
                s.fitness.total, gp.primitives.library.size(), gp.primitives.separators);
  std::string note = summary;
  if (gp.partitioned) {
    const PartitionedResult& p = *gp.partitioned;
    std::snprintf(summary, sizeof(summary),
                  "; %zu partitions searched in %.2f s, merged to %zu nodes, final search %.2f s",
                  p.partitions.size(), p.searchSeconds, p.mergedNodes, p.finalSeconds);
    note += summary;
  }
  clock.finish(note);
  out.tree = gp.tree;
  out.voxels = solidVoxels(out.tree, out.grid);
  out.result = GpMethodResult{std::move(gp)};
}

// The hybrid method's repair of the voxel tree on the points, then the finish.
void hybridMethod(Reconstruction& out, HybridMethodResult& hy, const PointCloud& scan,
                  const ReconstructOptions& options, StageClock& clock, const RunControl& control) {
  clock.start("repair");
  HybridOptions ho = options.hybrid;
  ho.evolve.seed = options.seed;
  ho.noise = out.detection.noise;
  hy.voxelTree = out.tree;
  hy.repair = repairTree(scan, out.tree, out.hypotheses.candidates, out.grid, out.labels.inside, ho,
                         control);
  const HybridResult& h = hy.repair;
  char summary[240];
  std::snprintf(summary, sizeof(summary),
                "%zu badly explained points, %zu regions, %zu subtrees replaced, %zu seen holes "
                "subtracted, fitness %.6g -> %.6g, primitives %zu -> %zu",
                h.badPoints, h.regions.size(), h.replaced, h.holesAdded, h.before.total,
                h.after.total,
                h.primitivesBefore, h.primitivesAfter);
  clock.finish(summary);
  out.tree = h.tree;
  if (options.finish.enabled && !control.shouldStop()) {
    clock.start("finish");
    FinishOptions fo = options.finish;
    fo.fitness = ho.fitness;
    fo.control = control;
    const VoxelTarget target{out.grid, out.labels.inside};
    hy.finish = finishTree(scan, out.tree, &target, fo);
    const FinishResult& f = hy.finish;
    std::snprintf(summary, sizeof(summary), "residual RMS %.4g -> %.4g, fitness %.6g -> %.6g, %s",
                  f.fit.rmsBefore, f.fit.rmsAfter, f.before.total, f.after.total,
                  f.accepted ? "accepted" : "input kept");
    clock.finish(summary);
    out.tree = f.tree;
  }
  out.voxels = solidVoxels(out.tree, out.grid);
}

// The reconstruction stopped by a cancel request after `stage`.
Reconstruction cancelledAfter(Reconstruction out, std::string_view stage) {
  out.status = Reconstruction::Status::Cancelled;
  out.message = "cancelled during " + std::string(stage);
  out.tree = CsgTree();
  return out;
}

// Fails with TooLarge when the voxel stage would need more than the memory
// limit; true when it fits.
bool fitsInMemory(Reconstruction& out, const ReconstructOptions& options) {
  if (options.method == Method::Gp || options.memoryLimit == 0) return true;
  const double need = voxelStageBytes(out.hypotheses.candidates.size(), out.grid.voxelCount());
  if (need <= double(options.memoryLimit)) return true;
  // Voxel count grows with the cube of the resolution.
  const double fit = double(out.resolution) * std::cbrt(double(options.memoryLimit) / need);
  out.status = Reconstruction::Status::TooLarge;
  char buf[256];
  std::snprintf(buf, sizeof(buf),
                "resolution %d needs about %.1f GiB for %zu candidates on %zu voxels, more "
                "than the %.1f GiB allowed; use a resolution of at most %d",
                out.resolution, need / double(1u << 30), out.hypotheses.candidates.size(),
                out.grid.voxelCount(), double(options.memoryLimit) / double(1u << 30), int(fit));
  out.message = buf;
  return false;
}

// Everything after detection, into `out` (which may hold timings already);
// `found` is taken over.
Reconstruction afterDetection(Reconstruction out, SurfacesAndCandidates found,
                              const PointCloud& scan, const ReconstructOptions& options,
                              const StageCallback& onStage, const RunControl& control) {
  StageClock clock(out, onStage);
  out.method = options.method;
  out.detection = std::move(found.detection);
  out.grid = std::move(found.grid);
  out.hypotheses = std::move(found.hypotheses);
  out.resolution = found.resolution;
  out.thin = std::move(found.thin);
  out.holesFromRims = found.rimHoles.holes;
  out.rimWindows = found.rimHoles.windows;
  out.sheetEdges = found.sheetRounds.tori + found.sheetRounds.cylinders +
                   found.sheetRounds.corners + found.sheetRounds.tilted;
  out.boresFromWalls = found.wallBores.bores;
  out.facesFromPoints = found.wallPlanes.planes;
  out.timeLimitHit = control.pastDeadline();
  if (!fitsInMemory(out, options)) return out;
  if (control.cancelled()) return cancelledAfter(std::move(out), "hypotheses");

  // A scan larger than the detection's search was searched on an even
  // subsample; the labels, the optimisation and the repair work on those
  // points too, so a big scan gives the tree of its subsample (the surfaces
  // were fitted on every point) in the subsample's time. The genetic
  // baseline keeps every point, as its published form does.
  PointCloud subsample;
  const bool onSubsample = !out.detection.searched.empty() && options.method != Method::Gp;
  if (onSubsample) subsample = scan.subset(out.detection.searched);
  const PointCloud& points = onSubsample ? subsample : scan;
  out.pointsAfterDetection = points.size();

  clock.start("labels");
  LabelOptions lo = options.labels;
  lo.noise = out.detection.noise;
  lo.control = control;
  // The faces no view saw (the one a part stood on) are closed for the
  // labels with points on the convex hull; the rest of the run keeps the scan.
  const UnseenFaces unseen =
      options.method == Method::Gp || !points.hasNormals()
          ? UnseenFaces{}
          : unseenHullFaces(points, 0.5 * out.grid.voxelSize(), options.unseen);
  out.unseenFacePoints = unseen.points.size();
  if (unseen.points.empty()) {
    out.labels = labelVoxels(out.grid, points, lo);
  } else {
    PointCloud closed = points;
    closed.points.insert(closed.points.end(), unseen.points.points.begin(),
                         unseen.points.points.end());
    closed.normals.insert(closed.normals.end(), unseen.points.normals.begin(),
                          unseen.points.normals.end());
    out.labels = labelVoxels(out.grid, closed, lo);
  }
  if (!control.cancelled()) {
    out.boreOpening =
        openSeenBores(out.grid, scan, out.detection.surfaces, out.labels.inside, options.bores);
  }
  const BoreOpening& bores = out.boreOpening;
  clock.finish(
      "voxels " + dimsText(out.grid) + ", " + std::to_string(out.labels.inside.count()) +
      " inside (" + std::string(labelMethodName(options.labels.method)) + ")" +
      (onSubsample ? " from the " + std::to_string(points.size()) + " points detection searched"
                   : std::string()) +
      (unseen.points.empty() ? std::string()
                             : "; " + std::to_string(unseen.points.size()) +
                                   " points close faces never seen") +
      (bores.voxels == 0
           ? std::string()
           : "; " + std::to_string(bores.voxels) + " opened in " + std::to_string(bores.bores) +
                 " bore" + (bores.bores == 1 ? "" : "s") + " seen around their axis" +
                 (bores.extended == 0
                      ? std::string()
                      : ", " + std::to_string(bores.extended) + " extended into another's")));
  if (control.cancelled()) return cancelledAfter(std::move(out), "labels");

  if (options.method == Method::Gp) {
    gpMethod(out, scan, options, clock, control);
  } else if (options.method == Method::Voxel) {
    out.result = VoxelMethodResult{voxelMethod(out, points, options, clock, control)};
  } else {
    HybridMethodResult hy;
    hy.construction = voxelMethod(out, points, options, clock, control);
    if (!out.tree.empty() && !control.cancelled()) {
      hybridMethod(out, hy, points, options, clock, control);
    }
    out.result = std::move(hy);
  }
  // The voxel stage judges its members by voxels and the repair by the
  // points, so a member that only grazes the rest (a corner of a box where
  // another member's cylinder meets it), or a cut that only grazes what it
  // cuts, can stay: an operand that changes less than a voxel's volume of
  // the solid goes. A surface cut from two members of a union, each to its
  // own depth (a bore through a flange and again through its hub), is then
  // cut once from both where that too changes less than a voxel's volume.
  // The genetic baseline's tree is left as its search gave it.
  if (options.method != Method::Gp && !out.tree.empty() && !control.cancelled()) {
    const double h = out.grid.voxelSize();
    const CsgTree kept = withSharedCuts(
        withoutNegligibleOperands(withoutEmptySubtrees(out.tree), 0.5 * h, h * h * h), 0.5 * h,
        h * h * h);
    if (kept.primitiveCount() != out.tree.primitiveCount()) {
      out.tree = kept;
      out.voxels = solidVoxels(out.tree, out.grid);
    }
  }
  if (control.cancelled()) {
    const std::string stage = out.timings.empty() ? "labels" : out.timings.back().stage;
    return cancelledAfter(std::move(out), stage);
  }
  if (out.tree.empty()) {
    out.status = Reconstruction::Status::NoCombination;
    out.message = "no combination of the detected primitives explains the scan";
    return out;
  }
  out.status = Reconstruction::Status::Ok;
  out.message = std::to_string(out.tree.primitiveCount()) + " primitives, " +
                std::to_string(out.tree.operationCount()) + " operations, depth " +
                std::to_string(out.tree.depth());
  return out;
}

}  // namespace

Reconstruction reconstruct(const PointCloud& scan, const ReconstructOptions& options,
                           const StageCallback& onStage, const RunControl& control) {
  Reconstruction out;
  // Detection stops at the deadline. After it, a limit never costs the
  // tree: labels and description sets run to the end, and the optimisation
  // (or the search) stops at the deadline and keeps the best tree it has.
  // A cancel request stops any stage.
  DetectAndFitOptions fo;
  fo.resolution = options.resolution;
  fo.seed = options.seed;
  fo.detect = options.detect;
  fo.finerGrid = options.finerGrid && options.method != Method::Gp;
  fo.memoryLimit = options.memoryLimit;
  fo.rimHoleOptions = options.rims;
  fo.sheetRounds = options.sheetRounds;
  SurfacesAndCandidates found =
      detectAndFit(scan, fo, onStage, [&](double fraction, std::string_view step) {
        return control.report(fraction, step) && !control.pastDeadline();
      });
  if (found.detection.status == DetectionResult::Status::Cancelled || control.cancelled()) {
    out.detection = std::move(found.detection);
    if (control.cancelled()) return cancelledAfter(std::move(out), "detection");
    out.status = Reconstruction::Status::TimedOut;
    out.message = "time limit reached during detection";
    out.timeLimitHit = true;
    return out;
  }
  if (!found.ok()) {
    out.detection = std::move(found.detection);
    out.status = Reconstruction::Status::NoSurfaces;
    out.message = out.detection.message;
    return out;
  }
  out.timings.push_back(
      {"detect", found.detectSeconds + found.fitSeconds + found.regularizeSeconds,
       found.detectCpuSeconds + found.fitCpuSeconds + found.regularizeCpuSeconds});
  out.timings.push_back({"hypotheses", found.hypothesisSeconds, found.hypothesisCpuSeconds});
  return afterDetection(std::move(out), std::move(found), scan, options, onStage, control);
}

Reconstruction reconstructDetected(const PointCloud& scan, const SurfacesAndCandidates& found,
                                   const ReconstructOptions& options, const StageCallback& onStage,
                                   const RunControl& control) {
  if (!found.ok()) throw std::invalid_argument("reconstructDetected: the detection found nothing");
  if (!scan.hasNormals())
    throw std::invalid_argument("reconstructDetected: the scan has no normals");
  return afterDetection(Reconstruction{}, found, scan, options, onStage, control);
}

}  // namespace csgvox
