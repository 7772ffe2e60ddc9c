#include "app/job_options.h"

#include "app/options.h"

namespace csgvox::app {

void addJobOptions(CLI::App& app, JobOptions& job) {
  namespace range = option_ranges;
  ReconstructOptions& o = job.reconstruct;
  addNamedOption<Method>(
      app, "--method", o.method, kMethodNames,
      "How the tree is built: hybrid (the voxel method, then a genetic search on the "
      "points repairs its tree where they disagree with it; the default), voxel "
      "(bounded hypotheses and Wu's two binary optimisations over voxel labels) or gp "
      "(the genetic-programming baseline of Fayolle & Pasko 2016: unbounded surfaces "
      "and separators combined by a genetic search on the points)");
  app.add_option("--res", o.resolution, "Voxels along the longest side of the part")
      ->check(inRange(range::resolution));
  app.add_flag("!--no-finer-grid,!--no-refine-thin", o.finerGrid,
               "Keep the resolution as given even when the surfaces show a wall, slot, rod or "
               "hole thinner than two voxels (by default the grid is then laid finer, up to "
               "twice the resolution). --no-refine-thin: old name, kept for one release");
  app.add_option("--seed", o.seed, "Random seed; the same seed gives the same tree")
      ->check(nonNegativeInteger());
  addNamedOption<LabelMethod>(
      app, "--label", o.labels.method, kLabelMethodNames,
      "Voxel labelling: winding (generalised winding number) or vote (Wu's K-nearest "
      "normal vote)");
  addNamedOption<BoundaryRule>(
      app, "--label-boundary", o.labels.boundary, kBoundaryRuleNames,
      "Voxels holding scan points: centre (labelled at their centre like every other "
      "voxel; default) or inside (always inside, Wu's rule)");
  app.add_option("-K,--neighbors", o.labels.neighbors, "vote: nearest points per voxel")
      ->check(inRange(range::neighbors));
  app.add_option("--vote-epsilon", o.labels.epsilon,
                 "vote: outside when more than this fraction of neighbours face the voxel")
      ->check(inRange(range::voteEpsilon));
  app.add_option("--alpha", o.construct.subtree.alpha, "voxel: weight of the fit term of Wu Eq. 4")
      ->check(inRange(range::fitWeight));
  app.add_option("--beta", o.construct.unionChoice.beta,
                 "voxel: weight of the fit term of Wu Eq. 6")
      ->check(inRange(range::fitWeight));
  app.add_option("--time-limit", job.timeLimit,
                 "Seconds for the reconstruction (0: none). Detection past it fails; the "
                 "optimisations and the genetic search past it keep the best tree found so far")
      ->check(inRange(range::timeLimit));
  app.add_option("--mesh-res", job.meshResolution, "Resolution of mesh.ply")
      ->check(inRange(range::meshResolution));
  HybridOptions& hy = o.hybrid;
  app.add_option("--repair-generations,--refine-generations", hy.evolve.maxGenerations,
                 "hybrid: generations at most of each region's search")
      ->check(inRange(range::generations));
  app.add_option("--repair-stall,--refine-stall", hy.evolve.stallGenerations,
                 "hybrid: a region's search stops after this many generations without "
                 "improvement (0: never)")
      ->check(inRange(range::generations));
  app.add_option("--repair-searches,--refine-searches", hy.searches,
                 "hybrid: independent searches of each region, each with its own seed; the one "
                 "with the best fitness on the region's points is kept")
      ->check(inRange(range::searches));
  app.add_option("--repair-population,--refine-population", hy.evolve.population,
                 "hybrid: creatures per generation of each region's search")
      ->check(inRange(range::population));
  addNamedOption<SetOperationKind>(
      app, "--repair-operations,--refine-operations", hy.fitness.operations, kSetOperationNames,
      "hybrid: field of the set operations in the regions' fitness: minmax (the "
      "default), sardf (smooth: differs from minmax only near edges and off the surface; "
      "its generations about 10 times slower) or rfunction");
  app.add_option("--bad-angle", hy.badAngle,
                 "hybrid: a point whose normal is further than this from the tree's, in degrees, "
                 "is badly explained (so is one farther than 1% of the diagonal)")
      ->check(inRange(range::angle));
  app.add_flag("--finish,!--no-finish", o.finish.enabled,
               "hybrid: end with the finish (the Ceres fit of every primitive parameter of the "
               "final tree on the points, relations kept exact); off by default");
  app.add_flag("!--no-preview", job.preview, "Do not write preview.png");
  app.add_flag("--raw-values", job.rawValues,
               "Write the tree as fitted: no part frame, no snapped values, no parameters or "
               "patterns in tree.scad, tree.json and tree.txt (by default they hold the designed "
               "tree: the simplest values within the fit's uncertainty, shared parameters, "
               "patterns as loops)");
  GpOptions& gp = o.gp;
  app.add_option("--population", gp.evolve.population, "gp: creatures per generation")
      ->check(inRange(range::population));
  app.add_option("--generations", gp.evolve.maxGenerations, "gp: generations at most")
      ->check(inRange(range::generations));
  app.add_option("--stall", gp.evolve.stallGenerations,
                 "gp: stop after this many generations without improvement (0: never)")
      ->check(inRange(range::generations));
  app.add_option("--crossover", gp.evolve.crossoverRate, "gp: crossover probability")
      ->check(inRange(range::probability));
  app.add_option("--mutation", gp.evolve.mutationRate, "gp: mutation probability")
      ->check(inRange(range::probability));
  app.add_option("--max-depth", gp.evolve.variation.maxDepth, "gp: deepest tree (levels)")
      ->check(inRange(range::maxDepth));
  addNamedOption<SetOperationKind>(
      app, "--operations", gp.fitness.operations, kSetOperationNames,
      "gp: field of the set operations in the fitness: minmax (as published), "
      "rfunction or sardf (the solid is the same; the field, its gradients and so the "
      "normal term differ near edges)");
  app.add_option("--angle", gp.fitness.angleTolerance,
                 "gp: normal tolerance alpha of Eq. 7, degrees (about 35 for noisy scans)")
      ->check(inRange(range::angle));
  app.add_option("--distance", gp.fitness.distanceTolerance,
                 "gp: distance tolerance epsilon of Eq. 7, fraction of the scan's diagonal")
      ->check(inRange(range::distance));
  app.add_option("--voxel-weight", gp.fitness.voxelWeight,
                 "gp: weight of the volumetric term (tree against the voxel labels); 0 as "
                 "published")
      ->check(inRange(range::voxelWeight));
  app.add_option("--rough-points", gp.roughPoints,
                 "gp: generations use at most this many points until the search stalls, then all "
                 "(0: always all)")
      ->check(inRange(range::roughPoints));
  app.add_flag("!--no-separators", gp.primitives.separators,
               "gp: no separating half-spaces around the curved surfaces");
  app.add_flag("--partition", gp.partition,
               "gp: partition the search (one search per maximal clique of the primitive-overlap "
               "graph, in parallel; the trees merged, then a search on all points seeded with "
               "them)");
}

}  // namespace csgvox::app
