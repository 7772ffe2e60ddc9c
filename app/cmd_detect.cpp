// csgvox detect SCAN -o OUTDIR [--epsilon E] [--min-points M] ...

#include <cmath>
#include <cstdio>
#include <filesystem>

#include "app/commands.h"
#include "app/options.h"
#include "io/errors.h"
#include "io/output_set.h"
#include "io/point_writer.h"
#include "io/report.h"
#include "io/scan_reader.h"
#include "job/console.h"
#include "pipeline/detect_and_fit.h"

namespace csgvox::app {

namespace fs = std::filesystem;

namespace {

struct DetectCommandOptions {
  std::string scan;
  std::string outDir;
  DetectAndFitOptions fit;
};

// A distinct, stable colour per surface; grey for unassigned points.
Rgb8 surfaceColor(int surface) {
  if (surface < 0) return Rgb8{128, 128, 128};
  const double h = std::fmod(0.618033988749895 * surface, 1.0) * 6.0;
  const double x = 1.0 - std::abs(std::fmod(h, 2.0) - 1.0);
  double r = 0, g = 0, b = 0;
  switch (int(h)) {
    case 0:
      r = 1, g = x;
      break;
    case 1:
      r = x, g = 1;
      break;
    case 2:
      g = 1, b = x;
      break;
    case 3:
      g = x, b = 1;
      break;
    case 4:
      r = x, b = 1;
      break;
    default:
      r = 1, b = x;
  }
  const auto c = [](double v) { return std::uint8_t(40 + 215 * v); };
  return Rgb8{c(r), c(g), c(b)};
}

}  // namespace

Command setupDetect(CLI::App& app, CommonOptions& common) {
  auto opt = std::make_shared<DetectCommandOptions>();
  DetectOptions& d = opt->fit.detect;
  app.add_option("SCAN", opt->scan, "Scan (any format csgvox reads)")->required();
  app.add_option("-o,--output", opt->outDir, "Output directory")->required();
  app.add_option("--epsilon", d.epsilon,
                 "Largest inlier distance, fraction of the diagonal D (raised to "
                 "--noise-factor x the estimated noise)")
      ->check(inRange(1e-6, 0.5));
  app.add_option("--noise-factor", d.noiseFactor, "epsilon >= this x estimated noise sigma")
      ->check(inRange(0.0, 100.0));
  app.add_option("--max-epsilon", d.maxEpsilon, "Cap on epsilon, fraction of D")
      ->check(inRange(1e-6, 0.5));
  app.add_option("--cluster-epsilon", d.clusterEpsilon,
                 "Largest gap inside one patch, fraction of D")
      ->check(inRange(1e-6, 0.5));
  app.add_option("--normal-threshold", d.normalThreshold,
                 "Smallest cosine between a point's normal and its surface's")
      ->check(inRange(0.0, 1.0));
  app.add_option("--min-points", d.minPoints, "Fewest inliers of a surface, fraction of points")
      ->check(inRange(1e-6, 1.0));
  app.add_option("--probability", d.probability, "RANSAC probability of missing a shape")
      ->check(inRange(1e-6, 0.5));
  app.add_option("--passes", d.passes, "RANSAC passes over the unassigned points")
      ->check(inRange(1, 10));
  app.add_option("--res", opt->fit.resolution,
                 "Voxels along the longest side of the main job's grid: the fit tolerance of "
                 "the hypotheses (the same --res gives the main job's candidates)")
      ->check(inRange(8, 1024));
  app.add_option("--max-candidates", opt->fit.hypotheses.maxCandidates,
                 "Cap on the number of hypotheses (0: none)")
      ->check(nonNegativeInteger());
  app.add_option("--seed", opt->fit.seed, "Random seed (as the main job's --seed)")
      ->check(nonNegativeInteger());
  return [opt, &common]() -> int {
    Console console(common.quiet);
    common.subject = opt->scan;
    const fs::path scanPath(opt->scan);
    Stopwatch total;
    Stopwatch watch;
    ReadOptions ro;
    ro.seed = opt->fit.seed;
    const Scan scan = readScan(scanPath, ro);
    const double readSeconds = watch.seconds();
    console.info("read " + scanPath.string() + ": " + describeScan(scan));
    const fs::path inputs[] = {scanPath};
    OutputSet output(opt->outDir, {"surfaces.json", "candidates.json", "segments.ply"}, inputs);

    opt->fit.detect.estimatedNormals = scan.info.normalsEstimated;
    const SurfacesAndCandidates found = detectAndFit(scan.cloud, opt->fit);
    const DetectionResult& det = found.detection;
    console.info("detection: " + det.message);
    if (!found.ok()) throw ParseError(scanPath.string() + ": " + det.message);
    console.info("surface fit and regularisation: " + std::to_string(det.surfaces.size()) +
                 " surfaces: " + found.regularization.summary());
    console.info("hypotheses: " + std::to_string(found.hypotheses.candidates.size()) +
                 " candidates");

    const std::string scanName = scanPath.string();
    writeJsonFile(output.path("surfaces.json"), surfacesJson(scanName, det));
    writeJsonFile(output.path("candidates.json"), candidatesJson(scanName, found.hypotheses));
    std::vector<Rgb8> colors(scan.cloud.size());
    for (std::size_t i = 0; i < colors.size(); ++i) colors[i] = surfaceColor(det.assignment[i]);
    writePointCloudPly(output.path("segments.ply"), scan.cloud, colors);
    output.commit();

    char buf[256];
    std::snprintf(buf, sizeof(buf),
                  "read %.2f s, detection %.2f s, surface fit %.2f s, regularisation %.3f s, "
                  "hypotheses %.2f s, total %.2f s",
                  readSeconds, found.detectSeconds, found.fitSeconds, found.regularizeSeconds,
                  found.hypothesisSeconds, total.seconds());
    console.info(buf);
    console.info("wrote surfaces.json, candidates.json, segments.ply in " +
                 output.folder().string());
    return 0;
  };
}

}  // namespace csgvox::app
