// csgvox detect SCAN -o OUTDIR [--epsilon E] [--min-points M] ...

#include "primitives/bounding_box.h"
#include "app/commands.h"
#include "app/console.h"
#include "app/report.h"
#include "io/errors.h"
#include "io/point_writer.h"
#include "io/scan_reader.h"
#include "io/tree_json.h"
#include "primitives/hypotheses.h"
#include "primitives/regularization.h"
#include "primitives/surface_detection.h"
#include "primitives/surface_refinement.h"
#include "voxel/voxel_grid.h"

#include <cmath>
#include <cstdio>
#include <filesystem>

namespace csgvox::app {

namespace fs = std::filesystem;
using Json = nlohmann::ordered_json;

namespace {

struct DetectCommandOptions {
  std::string scan;
  std::string outDir;
  DetectOptions detect;
  HypothesisOptions hypotheses;
  int resolution = 64;
};

Json surfaceJson(const Surface& s) {
  Json j;
  j["type"] = std::string(surfaceTypeName(s.type()));
  j["inliers"] = s.inliers.size();
  j["rms"] = s.rms;
  if (s.type() != SurfaceType::Plane) j["convex"] = s.convex;
  if (const auto* p = s.as<PlaneSurface>()) {
    j["normal"] = toJson(p->normal);
    j["offset"] = p->offset;
  } else if (const auto* c = s.as<CylinderSurface>()) {
    j["axis_point"] = toJson(c->axisPoint);
    j["axis_dir"] = toJson(c->axisDir);
    j["radius"] = c->radius;
  } else if (const auto* c = s.as<ConeSurface>()) {
    j["apex"] = toJson(c->apex);
    j["axis_dir"] = toJson(c->axisDir);
    j["half_angle"] = c->halfAngle;
  } else if (const auto* sp = s.as<SphereSurface>()) {
    j["center"] = toJson(sp->center);
    j["radius"] = sp->radius;
  } else if (const auto* t = s.as<TorusSurface>()) {
    j["center"] = toJson(t->center);
    j["axis_dir"] = toJson(t->axisDir);
    j["major_radius"] = t->majorRadius;
    j["minor_radius"] = t->minorRadius;
  }
  return j;
}

// A distinct, stable colour per surface; grey for unassigned points.
Rgb8 surfaceColor(int surface) {
  if (surface < 0) return Rgb8{128, 128, 128};
  const double h = std::fmod(0.618033988749895 * surface, 1.0) * 6.0;
  const double x = 1.0 - std::abs(std::fmod(h, 2.0) - 1.0);
  double r = 0, g = 0, b = 0;
  switch (int(h)) {
    case 0: r = 1, g = x; break;
    case 1: r = x, g = 1; break;
    case 2: g = 1, b = x; break;
    case 3: g = x, b = 1; break;
    case 4: r = x, b = 1; break;
    default: r = 1, b = x;
  }
  const auto c = [](double v) { return std::uint8_t(40 + 215 * v); };
  return Rgb8{c(r), c(g), c(b)};
}

}  // namespace

Command setupDetect(CLI::App& app, CommonOptions& common) {
  auto opt = std::make_shared<DetectCommandOptions>();
  DetectOptions& d = opt->detect;
  app.add_option("SCAN", opt->scan, "Scan (any format csgvox reads)")->required();
  app.add_option("-o,--output", opt->outDir, "Output directory")->required();
  app.add_option("--epsilon", d.epsilon,
                 "Largest inlier distance, fraction of the diagonal D (raised to "
                 "--noise-factor x the estimated noise)")
      ->check(CLI::Range(1e-6, 0.5));
  app.add_option("--noise-factor", d.noiseFactor, "epsilon >= this x estimated noise sigma")
      ->check(CLI::Range(0.0, 100.0));
  app.add_option("--max-epsilon", d.maxEpsilon, "Cap on epsilon, fraction of D")
      ->check(CLI::Range(1e-6, 0.5));
  app.add_option("--cluster-epsilon", d.clusterEpsilon,
                 "Largest gap inside one patch, fraction of D")
      ->check(CLI::Range(1e-6, 0.5));
  app.add_option("--normal-threshold", d.normalThreshold,
                 "Smallest cosine between a point's normal and its surface's")
      ->check(CLI::Range(0.0, 1.0));
  app.add_option("--min-points", d.minPoints, "Fewest inliers of a surface, fraction of points")
      ->check(CLI::Range(1e-6, 1.0));
  app.add_option("--probability", d.probability, "RANSAC probability of missing a shape")
      ->check(CLI::Range(1e-6, 0.5));
  app.add_option("--passes", d.passes, "RANSAC passes over the unassigned points")
      ->check(CLI::Range(1, 10));
  app.add_option("--res", opt->resolution,
                 "Voxels along the longest side: the fit tolerance of cuboid hypotheses")
      ->check(CLI::Range(8, 1024));
  app.add_option("--max-candidates", opt->hypotheses.maxCandidates,
                 "Cap on the number of hypotheses (0: none)");
  app.add_option("--seed", d.seed, "Random seed");
  return [opt, &common]() -> int {
    Console console(common.quiet);
    const fs::path scanPath(opt->scan);
    Stopwatch total;
    Stopwatch watch;
    const Scan scan = readScan(scanPath);
    const double readSeconds = watch.seconds();
    console.info("read " + scanPath.string() + ": " + describeScan(scan));
    const fs::path out(opt->outDir);
    std::error_code ec;
    fs::create_directories(out, ec);
    if (ec || !fs::is_directory(out)) {
      throw IoError(out.string() + ": cannot create the output directory");
    }

    watch = Stopwatch();
    DetectionResult det = detectSurfaces(scan.cloud, opt->detect);
    const double detectSeconds = watch.seconds();
    console.info("detection: " + det.message);
    if (det.status != DetectionResult::Status::Ok) {
      throw ParseError(scanPath.string() + ": " + det.message);
    }
    watch = Stopwatch();
    refineSurfaces(scan.cloud, det);
    const double refineSeconds = watch.seconds();
    watch = Stopwatch();
    const RegularizationReport reg = regularizeSurfaces(det);
    const double regularizeSeconds = watch.seconds();
    console.info("refined and regularised " + std::to_string(det.surfaces.size()) +
                 " surfaces: " + reg.summary());

    watch = Stopwatch();
    HypothesisOptions ho = opt->hypotheses;
    ho.seed = std::uint32_t(opt->detect.seed);
    // The cuboid fit tolerance is one voxel at the requested resolution.
    const OrientedBox box = minimalOrientedBox(scan.cloud.points);
    ho.voxelSize = 2.0 * box.halfSize.maxCoeff() / double(opt->resolution);
    const HypothesisSet hyp = generateHypotheses(scan.cloud, det.surfaces, ho);
    const double hypothesisSeconds = watch.seconds();
    console.info("hypotheses: " + std::to_string(hyp.candidates.size()) + " candidates");

    Json surfaces = Json::array();
    for (const Surface& s : det.surfaces) surfaces.push_back(surfaceJson(s));
    Report sj;
    sj.json["scan"] = scanPath.string();
    sj.json["diagonal"] = det.diagonal;
    sj.json["noise"] = det.noise;
    sj.json["epsilon"] = det.epsilon;
    sj.json["surfaces"] = std::move(surfaces);
    sj.write(out / "surfaces.json");

    Json cands = Json::array();
    for (const Candidate& c : hyp.candidates) {
      Json j;
      j["origin"] = std::string(candidateOriginName(c.origin));
      j["surfaces"] = c.surfaces;
      j["support"] = c.support;
      if (c.tool) j["tool"] = true;
      j["tree"] = Json::parse(treeNodeJson(c.tree));
      cands.push_back(std::move(j));
    }
    Report cj;
    cj.json["scan"] = scanPath.string();
    Json counts;
    for (std::size_t o = 0; o < kCandidateOriginCount; ++o) {
      counts[std::string(candidateOriginName(CandidateOrigin(o)))] = hyp.stats.returned.count[o];
    }
    cj.json["counts"] = counts;
    cj.json["capped"] = hyp.stats.capped;
    cj.json["candidates"] = std::move(cands);
    cj.write(out / "candidates.json");

    std::vector<Rgb8> colors(scan.cloud.size());
    for (std::size_t i = 0; i < colors.size(); ++i) colors[i] = surfaceColor(det.assignment[i]);
    writePointCloudPly(out / "segments.ply", scan.cloud, colors);

    char buf[256];
    std::snprintf(buf, sizeof(buf),
                  "read %.2f s, detection %.2f s, refinement %.2f s, regularisation %.3f s, "
                  "hypotheses %.2f s, total %.2f s",
                  readSeconds, detectSeconds, refineSeconds, regularizeSeconds,
                  hypothesisSeconds, total.seconds());
    console.info(buf);
    console.info("wrote surfaces.json, candidates.json, segments.ply in " + out.string());
    return 0;
  };
}

}  // namespace csgvox::app
