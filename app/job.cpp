#include "app/job.h"

#include <cmath>
#include <cstdio>
#include <optional>

#include "app/options.h"
#include "cad/step_export.h"
#include "evolve/fitness.h"
#include "io/csg_writer.h"
#include "io/mesh_files.h"
#include "io/png_file.h"
#include "io/report.h"
#include "io/scad_export.h"
#include "io/text_export.h"
#include "io/tree_json.h"
#include "mesh/fit_metrics.h"
#include "mesh/mesh_export.h"
#include "render/preview.h"

namespace csgvox::app {

void addJobOptions(CLI::App& app, JobSettings& s) {
  app.add_option("--method", s.method,
                 "How the tree is built: hybrid (the voxel method, then a genetic search on the "
                 "points repairs its tree where they disagree with it; the default), voxel "
                 "(bounded hypotheses and Wu's two binary optimisations over voxel labels) or gp "
                 "(the genetic-programming baseline of Fayolle & Pasko 2016: unbounded surfaces "
                 "and separators combined by a genetic search on the points)")
      ->check(CLI::IsMember({"hybrid", "voxel", "gp"}));
  app.add_option("--res", s.resolution, "Voxels along the longest side of the part")
      ->check(inRange(8, 1024));
  app.add_flag("!--no-refine-thin", s.pipeline.refineThin,
               "Keep the resolution as given even when the surfaces show a wall, slot, rod or "
               "hole thinner than two voxels (by default the grid is then laid finer, up to "
               "twice the resolution)");
  app.add_option("--seed", s.seed, "Random seed; the same seed gives the same tree")
      ->check(nonNegativeInteger());
  app.add_option("--label", s.labelMethod,
                 "Voxel labelling: winding (generalised winding number) or vote (Wu's K-nearest "
                 "normal vote)")
      ->check(CLI::IsMember({"winding", "vote"}));
  app.add_option("--label-boundary", s.boundary,
                 "Voxels holding scan points: centre (labelled at their centre like every other "
                 "voxel; default) or inside (always inside, Wu's rule)")
      ->check(CLI::IsMember({"centre", "inside"}));
  app.add_option("-K,--neighbors", s.pipeline.labels.neighbors, "vote: nearest points per voxel")
      ->check(inRange(1, 1000));
  app.add_option("--vote-epsilon", s.pipeline.labels.epsilon,
                 "vote: outside when more than this fraction of neighbours face the voxel")
      ->check(inRange(0.0, 1.0));
  app.add_option("--alpha", s.pipeline.construct.subtree.alpha,
                 "voxel: weight of the fit term of Wu Eq. 4")
      ->check(inRange(0.0, 100.0));
  app.add_option("--beta", s.pipeline.construct.unionChoice.beta,
                 "voxel: weight of the fit term of Wu Eq. 6")
      ->check(inRange(0.0, 100.0));
  app.add_option("--time-limit", s.pipeline.timeLimit,
                 "Seconds for the reconstruction (0: none). Detection past it fails; the "
                 "optimisations and the genetic search past it keep the best tree found so far")
      ->check(inRange(0.0, 1e6));
  app.add_option("--mesh-res", s.meshResolution, "Resolution of mesh.ply")->check(inRange(8, 2048));
  HybridOptions& hy = s.pipeline.hybrid;
  app.add_option("--refine-generations", hy.evolve.maxGenerations,
                 "hybrid: generations at most of each region's search")
      ->check(inRange(0, 1e7));
  app.add_option("--refine-stall", hy.evolve.stallGenerations,
                 "hybrid: a region's search stops after this many generations without "
                 "improvement (0: never)")
      ->check(inRange(0, 1e7));
  app.add_option("--refine-searches", hy.searches,
                 "hybrid: independent searches of each region, each with its own seed; the one "
                 "with the best fitness on the region's points is kept")
      ->check(inRange(1, 64));
  app.add_option("--refine-population", hy.evolve.population,
                 "hybrid: creatures per generation of each region's search")
      ->check(inRange(3, 100000));
  app.add_option("--refine-operations", s.refineOperations,
                 "hybrid: field of the set operations in the regions' fitness: minmax (the "
                 "default), sardf (smooth: differs from minmax only at points off the surface, "
                 "about 7 times slower) or rfunction")
      ->check(CLI::IsMember({"minmax", "rfunction", "sardf"}));
  app.add_option("--bad-angle", hy.badAngle,
                 "hybrid: a point whose normal is further than this from the tree's, in degrees, "
                 "is badly explained (so is one farther than 1% of the diagonal)")
      ->check(inRange(0.1, 180.0));
  app.add_flag("--finish,!--no-finish", s.pipeline.finish.enabled,
               "hybrid: end with the finish (the Ceres fit of every primitive parameter of the "
               "final tree on the points, relations kept exact); off by default");
  app.add_flag("!--no-preview", s.preview, "Do not write preview.png");
  GpOptions& gp = s.pipeline.gp;
  app.add_option("--population", gp.evolve.population, "gp: creatures per generation")
      ->check(inRange(3, 100000));
  app.add_option("--generations", gp.evolve.maxGenerations, "gp: generations at most")
      ->check(inRange(0, 1e7));
  app.add_option("--stall", gp.evolve.stallGenerations,
                 "gp: stop after this many generations without improvement (0: never)")
      ->check(inRange(0, 1e7));
  app.add_option("--crossover", gp.evolve.crossoverRate, "gp: crossover probability")
      ->check(inRange(0.0, 1.0));
  app.add_option("--mutation", gp.evolve.mutationRate, "gp: mutation probability")
      ->check(inRange(0.0, 1.0));
  app.add_option("--max-depth", gp.evolve.variation.maxDepth, "gp: deepest tree (levels)")
      ->check(inRange(2, 1000));
  app.add_option("--operations", s.operations,
                 "gp: field of the set operations in the fitness: minmax (as published), "
                 "rfunction or sardf (the solid is the same; the field, its gradients and so the "
                 "normal term differ near edges)")
      ->check(CLI::IsMember({"minmax", "rfunction", "sardf"}));
  app.add_option("--angle", gp.fitness.angleTolerance,
                 "gp: normal tolerance alpha of Eq. 7, degrees (about 35 for noisy scans)")
      ->check(inRange(0.1, 180.0));
  app.add_option("--distance", gp.fitness.distanceTolerance,
                 "gp: distance tolerance epsilon of Eq. 7, fraction of the scan's diagonal")
      ->check(inRange(1e-6, 1.0));
  app.add_option("--voxel-weight", gp.fitness.voxelWeight,
                 "gp: weight of the volumetric term (tree against the voxel labels); 0 as "
                 "published")
      ->check(inRange(0.0, 1e6));
  app.add_option("--rough-points", gp.roughPoints,
                 "gp: generations use at most this many points until the search stalls, then all "
                 "(0: always all)")
      ->check(inRange(0, 1e9));
  app.add_flag("!--no-separators", gp.primitives.separators,
               "gp: no separating half-spaces around the curved surfaces");
  app.add_flag("--partition", gp.partition,
               "gp: partition the search (one search per maximal clique of the primitive-overlap "
               "graph, in parallel; the trees merged, then a search on all points seeded with "
               "them)");
}

ReconstructOptions pipelineOptions(const JobSettings& s) {
  ReconstructOptions o = s.pipeline;
  o.seed = s.seed;
  o.resolution = s.resolution;
  o.method = methodFromName(s.method);
  o.labels.method = labelMethodFromName(s.labelMethod);
  o.labels.boundary = s.boundary == "inside" ? BoundaryRule::Inside : BoundaryRule::Centre;
  o.hybrid.fitness.operations = s.refineOperations == "rfunction" ? SetOperationKind::RFunction
                                : s.refineOperations == "minmax"  ? SetOperationKind::MinMax
                                                                  : SetOperationKind::Sardf;
  o.gp.fitness.operations = s.operations == "rfunction" ? SetOperationKind::RFunction
                            : s.operations == "sardf"   ? SetOperationKind::Sardf
                                                        : SetOperationKind::MinMax;
  return o;
}

namespace {

std::string fmt(const char* format, double a, double b = 0.0) {
  char buf[256];
  std::snprintf(buf, sizeof(buf), format, a, b);
  return buf;
}

// Eq. 7 of the tree on every scan point with the gp settings' tolerances and
// min/max, whatever built the tree: the figure `compare` ranks methods by.
Fitness pointFitness(const CsgTree& tree, const Scan& scan, const JobSettings& s) {
  FitnessOptions fo = s.pipeline.gp.fitness;
  fo.operations = SetOperationKind::MinMax;
  fo.voxelWeight = 0.0;
  const FitnessModel model(scan.cloud.points, scan.cloud.normals, scan.cloud.diagonal(),
                           PrimitiveLibrary::ofTree(tree), fo);
  return model.evaluate(tree);
}

// tree.step and preview.png. The tree is the result: a solid OpenCASCADE
// cannot build costs tree.step only (one error line naming the node, a
// warning in the report), not the job.
void writeCadOutputs(OutputSet& output, const Scan& scan, const CsgTree& tree,
                     const TriangleMesh& mesh, const JobSettings& settings,
                     nlohmann::ordered_json& timings, nlohmann::ordered_json& warnings) {
  Stopwatch watch;
  if (!stepExportAvailable()) {
    output.skip("tree.step");
    warnings.push_back("tree.step: not written: this build has no OpenCASCADE");
  } else {
    try {
      writeStep(output.path("tree.step"), tree);
    } catch (const CadError& e) {
      output.skip("tree.step");
      std::fprintf(stderr, "csgvox: error: tree.step not written: %s\n", e.what());
      warnings.push_back(std::string("tree.step: not written: ") + e.what());
    }
  }
  timings["step"] = watch.seconds();
  if (!settings.preview) {
    output.skip("preview.png");
    return;
  }
  watch = Stopwatch();
  writePng(output.path("preview.png"), renderPreview(tree, mesh, &scan.cloud).image);
  timings["preview"] = watch.seconds();
}

}  // namespace

nlohmann::ordered_json writeJob(OutputSet& output, const std::filesystem::path& scanPath,
                                const Scan& scan, const Reconstruction& rec,
                                const JobSettings& settings, nlohmann::ordered_json timings,
                                const Console& console) {
  const CsgTree& tree = rec.tree;
  Stopwatch watch;
  writeTreeJson(output.path("tree.json"), tree);
  writeScad(output.path("tree.scad"), tree);
  writeTreeText(output.path("tree.txt"), tree);
  writeCsg(output.path("tree.csg"), tree);
  MeshOptions mo;
  mo.resolution = settings.meshResolution;
  const TriangleMesh mesh = meshTree(tree, mo, console.progress());
  writeMesh(output.path("mesh.ply"), mesh);
  timings["export"] = watch.seconds();
  nlohmann::ordered_json warnings = nlohmann::ordered_json::array();
  writeCadOutputs(output, scan, tree, mesh, settings, timings, warnings);
  nlohmann::ordered_json report =
      jobReport(scanPath, scan, rec, settings, timings, warnings, console, &output);
  writeJsonFile(output.path("report.json"), report);
  return report;
}

nlohmann::ordered_json jobReport(const std::filesystem::path& scanPath, const Scan& scan,
                                 const Reconstruction& rec, const JobSettings& settings,
                                 nlohmann::ordered_json timings, nlohmann::ordered_json warnings,
                                 const Console& console, const OutputSet* output) {
  const CsgTree& tree = rec.tree;
  // The tree is the result: a metric that cannot be computed is a warning
  // in the report, not a failed job.
  Stopwatch watch;
  std::optional<FitMetrics> fit;
  try {
    FitOptions fo;
    fo.surfaceSamples = 100000;
    fo.seed = settings.seed;
    fit = evaluateFit(tree, scan.cloud, fo);
  } catch (const std::exception& e) {
    warnings.push_back(std::string("fit metrics: ") + e.what());
    console.info("warning: fit metrics not computed: " + std::string(e.what()));
  }
  const Fitness eq7 = pointFitness(tree, scan, settings);
  timings["metrics"] = watch.seconds();

  const ReconstructOptions& po = settings.pipeline;
  nlohmann::ordered_json report;
  report["status"] = "ok";
  report["input"] = scanJson(scanPath, scan);
  nlohmann::ordered_json parameters = {{"method", methodName(rec.method)},
                                       {"res", settings.resolution},
                                       {"seed", settings.seed},
                                       {"label", settings.labelMethod},
                                       {"label_boundary", settings.boundary},
                                       {"time_limit_s", po.timeLimit}};
  if (rec.method == Method::Imported) {
    // The tree was read, not built: only the scan-side settings apply.
  } else if (rec.method != Method::Gp) {
    parameters["alpha"] = po.construct.subtree.alpha;
    parameters["beta"] = po.construct.unionChoice.beta;
    if (rec.method == Method::Hybrid) {
      const HybridOptions& h = po.hybrid;
      parameters["refine_population"] = h.evolve.population;
      parameters["refine_generations"] = h.evolve.maxGenerations;
      parameters["refine_stall"] = h.evolve.stallGenerations;
      parameters["refine_searches"] = h.searches;
      parameters["bad_angle_deg"] = h.badAngle;
      parameters["refine_operations"] = settings.refineOperations;
      parameters["refine_voxel_weight"] = h.fitness.voxelWeight;
      parameters["finish"] = po.finish.enabled;
    }
  } else {
    const GpOptions& gp = po.gp;
    parameters["population"] = gp.evolve.population;
    parameters["generations"] = gp.evolve.maxGenerations;
    parameters["stall"] = gp.evolve.stallGenerations;
    parameters["crossover"] = gp.evolve.crossoverRate;
    parameters["mutation"] = gp.evolve.mutationRate;
    parameters["max_depth"] = gp.evolve.variation.maxDepth;
    parameters["operations"] = settings.operations;
    parameters["distance_tolerance"] = gp.fitness.distanceTolerance;
    parameters["angle_tolerance_deg"] = gp.fitness.angleTolerance;
    parameters["voxel_weight"] = gp.fitness.voxelWeight;
    parameters["rough_points"] = gp.roughPoints;
    parameters["separators"] = gp.primitives.separators;
    parameters["partition"] = gp.partition;
  }
  report["parameters"] = std::move(parameters);
  const auto& dims = rec.grid.dims();
  report["grid"] = {{"dims", {dims[0], dims[1], dims[2]}},
                    {"voxel_size", rec.grid.voxelSize()},
                    {"resolution", rec.resolution}};
  if (rec.method != Method::Imported && rec.method != Method::Gp) {
    // The features that made the grid finer (thinner than two voxels at the
    // asked resolution), thinnest first.
    nlohmann::ordered_json thin = nlohmann::ordered_json::array();
    for (const ThinFeature& f : rec.thin) {
      thin.push_back({{"kind", thinKindName(f.kind)}, {"thickness", f.thickness}});
    }
    report["grid"]["thin_features"] = std::move(thin);
  }
  if (rec.method == Method::Imported) {
    report["counts"] = {{"surfaces", rec.detection.surfaces.size()}};
  } else if (rec.method != Method::Gp) {
    const ConstructStats& st = rec.construction.stats;
    report["counts"] = {{"surfaces", rec.detection.surfaces.size()},
                        {"hypotheses", rec.hypotheses.candidates.size()},
                        {"usable_roots", st.usableRoots},
                        {"truncation_roots", st.truncationRoots},
                        {"subtrees", st.subtrees},
                        {"union_candidates", st.unionCandidates},
                        {"selected", st.selected},
                        {"chosen", st.chosen},
                        {"proved_optimal", st.provedOptimal},
                        {"time_limit_hit", rec.timeLimitHit}};
    if (rec.method == Method::Hybrid) {
      const HybridResult& h = rec.hybrid;
      nlohmann::ordered_json regions = nlohmann::ordered_json::array();
      for (const HybridRegion& r : h.regions) {
        regions.push_back({{"bad_points", r.badPoints},
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
                           {"seconds", r.seconds}});
      }
      report["refinement"] = {{"bad_points", h.badPoints},
                              {"regions", std::move(regions)},
                              {"subtrees_replaced", h.replaced},
                              {"fitness_before", h.before.total},
                              {"fitness_after", h.after.total},
                              {"primitives_before", h.primitivesBefore},
                              {"primitives_after", h.primitivesAfter},
                              {"ghost_points_before", h.ghostBefore},
                              {"ghost_points_after", h.ghostAfter},
                              {"boundary_area", h.area},
                              {"unsupported_area_before", h.unsupportedBefore},
                              {"unsupported_area_after", h.unsupportedAfter}};
      if (po.finish.enabled) {
        const FinishResult& f = rec.finish;
        report["finish"] = {{"ran", f.ran},
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
    }
  } else {
    const EvolveResult& s = rec.gp.search;
    report["counts"] = {{"surfaces", rec.detection.surfaces.size()},
                        {"library", rec.gp.primitives.library.size()},
                        {"separators", rec.gp.primitives.separators},
                        {"generations", s.generations},
                        {"evaluations", s.evaluations},
                        {"stop", evolveStopName(s.stop)},
                        {"clipped_to_scan_box", rec.gp.clipped},
                        {"time_limit_hit", rec.timeLimitHit}};
    if (rec.gp.partitioned) {
      const PartitionedResult& p = *rec.gp.partitioned;
      nlohmann::ordered_json parts = nlohmann::ordered_json::array();
      for (const PartitionRun& run : p.partitions) {
        parts.push_back({{"primitives", run.primitives.size()},
                         {"points", run.points},
                         {"generations", run.generations},
                         {"nodes", run.nodes},
                         {"seconds", run.seconds}});
      }
      report["partitioning"] = {
          {"partitions", std::move(parts)},          {"merged_nodes", p.mergedNodes},
          {"partition_seconds", p.partitionSeconds}, {"search_seconds", p.searchSeconds},
          {"merge_seconds", p.mergeSeconds},         {"final_seconds", p.finalSeconds}};
    }
  }
  report["tree"] = {{"primitives", tree.primitiveCount()},
                    {"operations", tree.operationCount()},
                    {"depth", tree.depth()}};
  nlohmann::ordered_json metrics = {{"voxel_iou", rec.voxelIou()}};
  if (fit) {
    metrics["rmse"] = fit->rmse;
    metrics["rmse_relative"] = fit->rmse / fit->diagonal;
    metrics["chamfer"] = fit->chamfer;
    metrics["chamfer_relative"] = fit->chamfer / fit->diagonal;
    metrics["within_1pct"] = fit->withinFraction;
    metrics["normal_agreement"] = fit->normalAgreement;
  }
  metrics["fitness"] = {{"total", eq7.total},
                        {"distance_term", eq7.distanceTerm},
                        {"normal_term", eq7.normalTerm},
                        {"size_penalty", eq7.sizePenalty},
                        {"points", scan.cloud.size()}};
  report["metrics"] = std::move(metrics);
  report["warnings"] = std::move(warnings);
  nlohmann::ordered_json outputs = nlohmann::ordered_json::array();
  for (const std::string& name : jobFiles()) {
    if (output && (name == "report.json" || std::filesystem::exists(output->path(name))))
      outputs.push_back(name);
  }
  report["outputs"] = std::move(outputs);
  report["timings_s"] = timings;
  if (fit) {
    console.info(fmt("fit: Chamfer %.3g %% of D, RMSE %.3g %% of D",
                     100 * fit->chamfer / fit->diagonal, 100 * fit->rmse / fit->diagonal));
  }
  return report;
}

}  // namespace csgvox::app
