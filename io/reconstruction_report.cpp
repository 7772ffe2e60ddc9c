#include "io/reconstruction_report.h"

#include <stdexcept>
#include <type_traits>

#include "io/report.h"

namespace csgvox {
namespace {

using Json = nlohmann::ordered_json;

// The settings every method shares: how the scan was labelled.
Json scanParameters(std::string_view method, const ReconstructOptions& o,
                    const ReportContext& ctx) {
  return {{"method", method},
          {"res", o.resolution},
          {"seed", o.seed},
          {"label", labelMethodName(o.labels.method)},
          {"label_boundary", nameOf<BoundaryRule>(kBoundaryRuleNames, o.labels.boundary)},
          {"time_limit_s", ctx.timeLimit}};
}

Json voxelParameters(const ReconstructOptions& o, const ReportContext& ctx) {
  Json p = scanParameters(methodName(o.method), o, ctx);
  p["alpha"] = o.construct.subtree.alpha;
  p["beta"] = o.construct.unionChoice.beta;
  return p;
}

Json hybridParameters(const ReconstructOptions& o, const ReportContext& ctx) {
  Json p = voxelParameters(o, ctx);
  const HybridOptions& h = o.hybrid;
  p["repair_population"] = h.evolve.population;
  p["repair_generations"] = h.evolve.maxGenerations;
  p["repair_stall"] = h.evolve.stallGenerations;
  p["repair_searches"] = h.searches;
  p["bad_angle_deg"] = h.badAngle;
  p["repair_operations"] = nameOf<SetOperationKind>(kSetOperationNames, h.fitness.operations);
  p["repair_voxel_weight"] = h.fitness.voxelWeight;
  p["finish"] = o.finish.enabled;
  // The keys' names before the repair search had its own name, kept for one
  // release (docs/formats.md).
  for (const char* key :
       {"population", "generations", "stall", "searches", "operations", "voxel_weight"}) {
    p[std::string("refine_") + key] = p[std::string("repair_") + key];
  }
  return p;
}

Json gpParameters(const ReconstructOptions& o, const ReportContext& ctx) {
  Json p = scanParameters(methodName(o.method), o, ctx);
  const GpOptions& gp = o.gp;
  p["population"] = gp.evolve.population;
  p["generations"] = gp.evolve.maxGenerations;
  p["stall"] = gp.evolve.stallGenerations;
  p["crossover"] = gp.evolve.crossoverRate;
  p["mutation"] = gp.evolve.mutationRate;
  p["max_depth"] = gp.evolve.variation.maxDepth;
  p["operations"] = nameOf<SetOperationKind>(kSetOperationNames, gp.fitness.operations);
  p["distance_tolerance"] = gp.fitness.distanceTolerance;
  p["angle_tolerance_deg"] = gp.fitness.angleTolerance;
  p["voxel_weight"] = gp.fitness.voxelWeight;
  p["rough_points"] = gp.roughPoints;
  p["separators"] = gp.primitives.separators;
  p["partition"] = gp.partition;
  return p;
}

Json gridJson(const VoxelGrid& grid, int resolution) {
  const auto& dims = grid.dims();
  return {{"dims", {dims[0], dims[1], dims[2]}},
          {"voxel_size", grid.voxelSize()},
          {"resolution", resolution}};
}

// The features that made the grid finer (thinner than two voxels at the
// asked resolution), thinnest first.
Json thinJson(const std::vector<ThinFeature>& thin) {
  Json out = Json::array();
  for (const ThinFeature& f : thin) {
    out.push_back({{"kind", thinKindName(f.kind)}, {"thickness", f.thickness}});
  }
  return out;
}

Json voxelCounts(const Reconstruction& rec, const Construction& c) {
  const ConstructStats& st = c.stats;
  return {{"surfaces", rec.detection.surfaces.size()},
          {"holes_from_rims", rec.holesFromRims},
          {"windows_from_rims", rec.rimWindows},
          {"sheet_edges_from_rounds", rec.sheetEdges},
          {"bores_from_walls", rec.boresFromWalls},
          {"faces_from_points", rec.facesFromPoints},
          {"points_after_detection", rec.pointsAfterDetection},
          {"unseen_face_points", rec.unseenFacePoints},
          {"bores_seen", rec.boreOpening.bores},
          {"bore_voxels_opened", rec.boreOpening.voxels},
          {"hypotheses", rec.hypotheses.candidates.size()},
          {"usable_roots", st.usableRoots},
          {"truncation_roots", st.truncationRoots},
          {"subtrees", st.subtrees},
          {"union_candidates", st.unionCandidates},
          {"selected", st.selected},
          {"chosen", st.chosen},
          {"proved_optimal", st.provedOptimal},
          {"time_limit_hit", rec.timeLimitHit}};
}

Json regionJson(const HybridRegion& r) {
  return {{"bad_points", r.badPoints},
          {"unsupported_boundary", r.unsupportedArea},
          {"points", r.points},
          {"members", r.members},
          {"library", r.library},
          {"generations", r.generations},
          {"search", r.search()},
          {"search_fitness", r.searchFitness},
          {"fitness_before", r.localBefore},
          {"fitness_after", r.localAfter},
          {"primitives_before", r.primitivesBefore},
          {"primitives_after", r.primitivesAfter},
          {"replaced", r.replaced()},
          {"verdict", regionVerdictName(r.verdict)},
          {"unsupported_area", r.unsupported},
          {"seconds", r.seconds}};
}

Json repairJson(const HybridResult& h) {
  Json regions = Json::array();
  for (const HybridRegion& r : h.regions) regions.push_back(regionJson(r));
  return {{"bad_points", h.badPoints},
          {"regions", std::move(regions)},
          {"subtrees_replaced", h.replaced},
          {"holes_added", h.holesAdded},
          {"fitness_before", h.before.total},
          {"fitness_after", h.after.total},
          {"primitives_before", h.primitivesBefore},
          {"primitives_after", h.primitivesAfter},
          {"ghost_points_before", h.ghostBefore},
          {"ghost_points_after", h.ghostAfter},
          {"boundary_area", h.area},
          {"unsupported_area_before", h.unsupportedBefore},
          {"unsupported_area_after", h.unsupportedAfter}};
}

Json finishJson(const FinishResult& f) {
  return {{"ran", f.ran},
          {"accepted", f.accepted},
          {"points", f.fit.points},
          {"parameters", f.fit.parameters},
          {"shared_blocks", f.fit.sharedBlocks},
          {"iterations", f.fit.iterations},
          {"residual_rms_before", f.fit.rmsBefore},
          {"residual_rms_after", f.fit.rmsAfter},
          {"fitness_before", f.before.total},
          {"fitness_after", f.after.total},
          {"voxel_iou_before", f.voxelIouBefore},
          {"voxel_iou_after", f.voxelIouAfter},
          {"primitives_changed", f.primitivesChanged},
          {"seconds", f.seconds}};
}

Json gpCounts(const Reconstruction& rec, const GpResult& gp) {
  const EvolveResult& s = gp.search;
  return {{"surfaces", rec.detection.surfaces.size()},
          {"library", gp.primitives.library.size()},
          {"separators", gp.primitives.separators},
          {"generations", s.generations},
          {"evaluations", s.evaluations},
          {"stop", evolveStopName(s.stop)},
          {"clipped_to_scan_box", gp.clipped},
          {"time_limit_hit", rec.timeLimitHit}};
}

Json partitioningJson(const PartitionedResult& p) {
  Json parts = Json::array();
  for (const PartitionRun& run : p.partitions) {
    parts.push_back({{"primitives", run.primitives.size()},
                     {"points", run.points},
                     {"generations", run.generations},
                     {"nodes", run.nodes},
                     {"seconds", run.seconds}});
  }
  return {{"partitions", std::move(parts)},          {"merged_nodes", p.mergedNodes},
          {"partition_seconds", p.partitionSeconds}, {"search_seconds", p.searchSeconds},
          {"merge_seconds", p.mergeSeconds},         {"final_seconds", p.finalSeconds}};
}

Json metricsJson(const TreeMetrics& m, std::size_t points) {
  Json out = {{"voxel_iou", m.voxelIou}};
  if (m.fit) {
    const FitMetrics& f = *m.fit;
    out["rmse"] = f.rmse;
    out["rmse_relative"] = f.rmse / f.diagonal;
    out["chamfer"] = f.chamfer;
    out["chamfer_relative"] = f.chamfer / f.diagonal;
    out["within_1pct"] = f.withinFraction;
    out["normal_agreement"] = f.normalAgreement;
  }
  out["fitness"] = {{"total", m.fitness.total},
                    {"distance_term", m.fitness.distanceTerm},
                    {"normal_term", m.fitness.normalTerm},
                    {"size_penalty", m.fitness.sizePenalty},
                    {"points", points}};
  return out;
}

// The head every report starts with: status, input, parameters.
Json head(const ReportContext& ctx, Json parameters) {
  if (!ctx.scan) throw std::invalid_argument("a report needs its scan");
  Json report;
  report["status"] = "ok";
  report["input"] = scanJson(ctx.scanPath, *ctx.scan);
  report["parameters"] = std::move(parameters);
  return report;
}

// The tail every report ends with: tree, metrics, warnings, outputs, timings.
void tail(Json& report, const CsgTree& tree, const ReportContext& ctx) {
  report["tree"] = {{"primitives", tree.primitiveCount()},
                    {"operations", tree.operationCount()},
                    {"depth", tree.depth()}};
  report["metrics"] = metricsJson(ctx.metrics, ctx.scan->cloud.size());
  report["warnings"] = ctx.warnings;
  report["outputs"] = ctx.outputs;
  report["timings_s"] = ctx.timings.wall;
  // The repair stage's old name, kept for one release.
  if (ctx.timings.wall.contains("repair")) {
    report["timings_s"]["refine"] = ctx.timings.wall["repair"];
  }
  report["cpu_s"] = ctx.timings.cpu;
}

// The voxel stage's sections, shared by the voxel and hybrid methods.
void voxelSections(Json& report, const Reconstruction& rec, const Construction& c) {
  report["grid"] = gridJson(rec.grid, rec.resolution);
  report["grid"]["thin_features"] = thinJson(rec.thin);
  report["counts"] = voxelCounts(rec, c);
}

}  // namespace

Json reconstructionReport(const Reconstruction& rec, const ReconstructOptions& options,
                          const ReportContext& ctx) {
  Json report;
  std::visit(
      [&](const auto& result) {
        using T = std::decay_t<decltype(result)>;
        if constexpr (std::is_same_v<T, std::monostate>) {
          throw std::invalid_argument("a report needs a finished reconstruction");
        } else if constexpr (std::is_same_v<T, VoxelMethodResult>) {
          report = head(ctx, voxelParameters(options, ctx));
          voxelSections(report, rec, result.construction);
        } else if constexpr (std::is_same_v<T, HybridMethodResult>) {
          report = head(ctx, hybridParameters(options, ctx));
          voxelSections(report, rec, result.construction);
          report["repair"] = repairJson(result.repair);
          report["refinement"] = report["repair"];  // the old name, kept for one release
          if (options.finish.enabled) report["finish"] = finishJson(result.finish);
        } else {
          report = head(ctx, gpParameters(options, ctx));
          report["grid"] = gridJson(rec.grid, rec.resolution);
          report["counts"] = gpCounts(rec, result.gp);
          if (result.gp.partitioned) {
            report["partitioning"] = partitioningJson(*result.gp.partitioned);
          }
        }
      },
      rec.result);
  tail(report, rec.tree, ctx);
  return report;
}

Json importedTreeReport(const ImportedTree& imported, const ReconstructOptions& options,
                        const ReportContext& ctx) {
  if (!imported.tree || !imported.grid) {
    throw std::invalid_argument("an imported tree's report needs the tree and its grid");
  }
  // The tree was read, not built: only the scan-side settings apply.
  Json report = head(ctx, scanParameters("import-gp", options, ctx));
  report["grid"] = gridJson(*imported.grid, imported.resolution);
  report["counts"] = {{"surfaces", imported.surfaces}};
  tail(report, *imported.tree, ctx);
  return report;
}

}  // namespace csgvox
