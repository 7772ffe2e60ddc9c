// Detection, refinement, regularisation and hypotheses on synthetic scans of a
// bundled part at several sizes: time per stage and peak memory.
// Run: build/bench/bench_detection [data/<part>/tree.json] [noise]

#include <sys/resource.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "bench_common.h"
#include "io/tree_json.h"
#include "mesh/surface_sampler.h"
#include "pipeline/detect_and_fit.h"

namespace {

using csgvox::bench::peakMiB;
using csgvox::bench::seconds;

}  // namespace

int main(int argc, char** argv) {
  using namespace csgvox;
  const std::string treePath =
      argc > 1 ? argv[1] : std::string(CSGVOX_DATA_DIR) + "/housing_complex/tree.json";
  const double noise = argc > 2 ? std::atof(argv[2]) : 0.0;
  const CsgTree tree = readTreeJson(std::filesystem::path(treePath));
  std::printf("part %s, noise %.4f D, %zu primitives\n", treePath.c_str(), noise,
              tree.primitiveCount());
  std::printf("%8s %9s %9s %9s %9s %9s %9s %8s %10s %9s\n", "points", "detect_s", "fit_s",
              "regul_s", "hypoth_s", "total_s", "surfaces", "cands", "eq3", "peak_MiB");
  for (std::size_t n : {50000u, 100000u, 500000u}) {
    SampleOptions so;
    so.points = n;
    so.noise = noise;
    so.seed = 1;
    const PointCloud scan = sampleSurface(tree, so).cloud;
    const auto t0 = std::chrono::steady_clock::now();
    // The main job's configuration: res 64, seed 1.
    const SurfacesAndCandidates found = detectAndFit(scan);
    const HypothesisSet& hyp = found.hypotheses;
    std::printf("%8zu %9.3f %9.3f %9.4f %9.3f %9.3f %9zu %8zu %10zu %9.0f\n", n,
                found.detectSeconds, found.fitSeconds, found.regularizeSeconds,
                found.hypothesisSeconds, seconds(t0), found.detection.surfaces.size(),
                hyp.candidates.size(), hyp.stats.cuboids.eq3Count, peakMiB());
    std::fflush(stdout);
  }
  return 0;
}
