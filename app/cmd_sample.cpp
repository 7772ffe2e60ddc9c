// csgvox sample TREE.json -o SCAN.ply [--points N] [--noise R] [--drop K] [--seed S]
// csgvox sample TREE.json -o SCAN.ply --scanner [scanner options] (docs/scanner.md)

#include <cstdio>
#include <sstream>

#include "app/commands.h"
#include "app/options.h"
#include "app/tree_command.h"
#include "io/errors.h"
#include "io/point_writer.h"
#include "job/console.h"
#include "mesh/surface_sampler.h"
#include "scanner/scanner.h"
#include "scanner/tree_caster.h"

namespace csgvox::app {

namespace {

struct SampleCommandOptions {
  std::string tree;
  std::string output;
  SampleOptions sample;
  bool scanner = false;
  ScannerOptions scan;
  bool ascii = false;
};

constexpr NamedValue<ScannerNormals> kScannerNormalNames[] = {
    {"none", ScannerNormals::None},
    {"scanner", ScannerNormals::Scanner},
};

/// A finite number in the open interval (lo, hi), or in (lo, hi] with `closedAbove`.
CLI::Validator inOpenRange(double lo, double hi, bool closedAbove = false) {
  const std::string range = "(" + CLI::detail::to_string(lo) + ", " +
                            CLI::detail::to_string(hi) + (closedAbove ? "]" : ")");
  return CLI::Validator(
      [lo, hi, range, closedAbove](std::string& text) -> std::string {
        const std::string closed = inRange(lo, hi)(text);
        if (!closed.empty() && closed.find(" is not in ") == std::string::npos) return closed;
        const double v = std::strtod(text.c_str(), nullptr);
        if (!closed.empty() || v <= lo || (v >= hi && !(closedAbove && v == hi))) return text + " is not in " + range;
        return {};
      },
      "in " + range);
}

// Registers the scanner model's options; each needs --scanner.
void addScannerOptions(CLI::App& app, SampleCommandOptions& opt, CLI::Option* scanner) {
  ScannerOptions& s = opt.scan;
  std::vector<CLI::Option*> options;
  options.push_back(app.add_option("--views", s.views, "Scanner: turntable positions per turn")
                        ->check(inRange(1, 10000))
                        ->capture_default_str());
  options.push_back(app.add_option("--elevations", s.elevations,
                                   "Scanner: camera elevations above the table, degrees, "
                                   "comma-separated, each in (0, 90)")
                        ->delimiter(',')
                        ->check(inOpenRange(0.0, 90.0))
                        ->capture_default_str());
  options.push_back(app.add_option("--setups", s.setups,
                                   "Scanner: 1 (part on its lowest face) or 2 (also turned over "
                                   "and registered back)")
                        ->check(inRange(1, 2))
                        ->capture_default_str());
  options.push_back(app.add_option("--registration-shift", s.registrationTranslation,
                                   "Scanner: setup 2's registration error, translation as a "
                                   "fraction of the diagonal D")
                        ->check(inRange(0.0, 1.0))
                        ->capture_default_str());
  options.push_back(app.add_option("--registration-turn", s.registrationRotation,
                                   "Scanner: setup 2's registration error, rotation in radians")
                        ->check(inRange(0.0, 1.0))
                        ->capture_default_str());
  options.push_back(app.add_option("--depth-noise", s.depthNoise,
                                   "Scanner: depth noise sigma along the ray at the reference "
                                   "range and normal incidence, fraction of D (grows with "
                                   "range^2 / cos(incidence))")
                        ->check(inRange(0.0, 1.0))
                        ->capture_default_str());
  options.push_back(app.add_option("--noise-incidence-cap", s.noiseIncidenceCap,
                                   "Scanner: largest 1/cos(incidence) factor of the depth noise")
                        ->check(inRange(1.0, 1e6))
                        ->capture_default_str());
  options.push_back(app.add_option("--max-incidence", s.maxIncidence,
                                   "Scanner: hits at a larger angle between ray and surface "
                                   "normal are dropped, degrees")
                        ->check(inOpenRange(0.0, 90.0, true))
                        ->capture_default_str());
  options.push_back(app.add_option("--mixed-pixels", s.mixedPixels,
                                   "Scanner: probability that a pixel at a depth edge gives a "
                                   "point between the two depths")
                        ->check(inRange(0.0, 1.0))
                        ->capture_default_str());
  options.push_back(app.add_option("--density-variation", s.densityVariation,
                                   "Scanner: density at the dense end of the part over the sparse "
                                   "end's, a smooth ramp along the part's longest side (1: as the "
                                   "views give it)")
                        ->check(inRange(1.0, 1000.0))
                        ->capture_default_str());
  options.push_back(app.add_option("--depth-edge", s.depthEdge,
                                   "Scanner: a depth jump between neighbouring pixels larger "
                                   "than this many pixel footprints is a depth edge")
                        ->check(inOpenRange(0.0, 1e6, true))
                        ->capture_default_str());
  options.push_back(app.add_option("--outliers", s.outliers,
                                   "Scanner: sparse outliers, fraction of each view's points")
                        ->check(inRange(0.0, 1.0))
                        ->capture_default_str());
  options.push_back(app.add_option("--outlier-margin", s.outlierMargin,
                                   "Scanner: outliers lie in the part's box grown by this "
                                   "fraction of D")
                        ->check(inRange(0.0, 10.0))
                        ->capture_default_str());
  options.push_back(app.add_option("--field-of-view", s.fieldOfView,
                                   "Scanner: full angle of the camera's square image, degrees")
                        ->check(inOpenRange(0.0, 120.0))
                        ->capture_default_str());
  options.push_back(app.add_option("--standoff", s.standoff,
                                   "Scanner: camera distance over the one at which the part's "
                                   "bounding sphere just fills the image")
                        ->check(inRange(1.0, 100.0))
                        ->capture_default_str());
  options.push_back(app.add_option("--resolution", s.resolution,
                                   "Scanner: image side in pixels (0: the smallest that gives "
                                   "--points points)")
                        ->check(inRange(0, 8192))
                        ->capture_default_str());
  options.push_back(addNamedOption<ScannerNormals>(
      app, "--scanner-normals", s.normals, kScannerNormalNames,
      "Scanner: none (raw x y z) or scanner (from the range image, noisy, facing the sensor)"));
  for (CLI::Option* o : options) o->needs(scanner);
}

// The scanner model's counts line.
std::string countsLine(const ScannerScan& s, double seconds) {
  const ScannerCounts& c = s.counts;
  char buf[512];
  std::snprintf(buf, sizeof(buf),
                "scanned %zu views at %d x %d px in %.2f s: %zu hits, %zu dropped for incidence, "
                "%zu mixed pixels (of %zu at depth edges), %zu outliers, %zu points, %zu kept",
                s.sensors.size(), s.resolution, s.resolution, seconds, c.hits,
                c.droppedIncidence, c.mixed, c.edgePixels, c.outliers, c.points, c.kept);
  return buf;
}

}  // namespace

Command setupSample(CLI::App& app, CommonOptions& common) {
  auto opt = std::make_shared<SampleCommandOptions>();
  app.add_option("TREE", opt->tree, "CSG tree (tree.json)")->required();
  app.add_option("-o,--output", opt->output,
                 "Output scan: .ply (binary, x y z [nx ny nz]) or .xyz (text, x y z [nx ny nz])")
      ->required();
  app.add_option("--points", opt->sample.points, "Number of points")
      ->check(inRange(1, 100'000'000))
      ->capture_default_str();
  CLI::Option* scanner = app.add_flag(
      "--scanner", opt->scanner,
      "Scan the tree with the turntable scanner model instead of sampling it uniformly "
      "(docs/scanner.md)");
  app.add_option("--noise", opt->sample.noise,
                 "Gaussian position noise sigma, as a fraction of the bounding-box diagonal")
      ->check(inRange(0.0, 1.0))
      ->excludes(scanner);
  app.add_option("--drop", opt->sample.dropPatches,
                 "Remove this many round patches, imitating scanner holes")
      ->check(inRange(0, 1000))
      ->excludes(scanner);
  app.add_option("--drop-radius", opt->sample.patchRadius,
                 "Radius of each removed patch, as a fraction of the diagonal")
      ->check(inRange(1e-6, 1.0))
      ->excludes(scanner);
  addScannerOptions(app, *opt, scanner);
  app.add_option("--seed", opt->sample.seed, "Random seed")->check(nonNegativeInteger());
  app.add_flag("--ascii", opt->ascii, "Write ASCII PLY instead of binary");
  return [opt, &common]() -> int {
    Console console(common.quiet);
    const auto [tree, ext] = readTreeCommand(common, opt->tree, opt->output);
    if (ext != "ply" && ext != "xyz" && ext != "xyzn") {
      throw IoError(opt->output + ": unsupported output format (use .ply or .xyz)");
    }
    console.info("read " + opt->tree + ": " + std::to_string(tree.primitiveCount()) +
                 " primitives");
    Stopwatch watch;
    PointCloud cloud;
    if (opt->scanner) {
      ScannerOptions so = opt->scan;
      so.points = opt->sample.points;
      so.seed = opt->sample.seed;
      const TreeCaster caster(tree);
      const ScannerScan s = scanPart(caster, so);
      console.info(countsLine(s, watch.seconds()));
      cloud = s.cloud;
    } else {
      const SurfaceSample s = sampleSurface(tree, opt->sample);
      char buf[256];
      std::snprintf(buf, sizeof(buf), "sampled %zu points in %.2f s (surface area %.6g, D %.6g)",
                    s.cloud.size(), watch.seconds(), s.surfaceArea, s.diagonal);
      console.info(buf);
      cloud = s.cloud;
    }
    if (ext == "ply") {
      writePointCloudPly(opt->output, cloud,
                         opt->ascii ? PlyEncoding::Ascii : PlyEncoding::BinaryLittleEndian);
    } else {
      writePointCloudXyz(opt->output, cloud);
    }
    console.info("wrote " + opt->output);
    return 0;
  };
}

}  // namespace csgvox::app
