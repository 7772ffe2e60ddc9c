// csgvox sample TREE.json -o SCAN.ply [--points N] [--noise R] [--drop K] [--seed S]

#include <cstdio>

#include "app/commands.h"
#include "app/options.h"
#include "app/tree_command.h"
#include "io/errors.h"
#include "io/point_writer.h"
#include "job/console.h"
#include "mesh/surface_sampler.h"

namespace csgvox::app {

namespace {

struct SampleCommandOptions {
  std::string tree;
  std::string output;
  SampleOptions sample;
  bool ascii = false;
};

}  // namespace

Command setupSample(CLI::App& app, CommonOptions& common) {
  auto opt = std::make_shared<SampleCommandOptions>();
  app.add_option("TREE", opt->tree, "CSG tree (tree.json)")->required();
  app.add_option("-o,--output", opt->output,
                 "Output scan: .ply (binary, x y z nx ny nz) or .xyz (text, x y z nx ny nz)")
      ->required();
  app.add_option("--points", opt->sample.points, "Number of points")
      ->check(inRange(1, 100'000'000));
  app.add_option("--noise", opt->sample.noise,
                 "Gaussian position noise sigma, as a fraction of the bounding-box diagonal")
      ->check(inRange(0.0, 1.0));
  app.add_option("--drop", opt->sample.dropPatches,
                 "Remove this many round patches, imitating scanner holes")
      ->check(inRange(0, 1000));
  app.add_option("--drop-radius", opt->sample.patchRadius,
                 "Radius of each removed patch, as a fraction of the diagonal")
      ->check(inRange(1e-6, 1.0));
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
    const SurfaceSample s = sampleSurface(tree, opt->sample);
    char buf[256];
    std::snprintf(buf, sizeof(buf), "sampled %zu points in %.2f s (surface area %.6g, D %.6g)",
                  s.cloud.size(), watch.seconds(), s.surfaceArea, s.diagonal);
    console.info(buf);
    if (ext == "ply") {
      writePointCloudPly(opt->output, s.cloud,
                         opt->ascii ? PlyEncoding::Ascii : PlyEncoding::BinaryLittleEndian);
    } else {
      writePointCloudXyz(opt->output, s.cloud);
    }
    console.info("wrote " + opt->output);
    return 0;
  };
}

}  // namespace csgvox::app
