// How much of each InverseCSG part the scanner model can observe at all: the
// IoU against the part of the largest solid that no camera ray contradicts.
// A point outside the part is seen to be empty when the segment from one of
// the scanner's camera positions (scanner/scanner.h: defaults, both setups
// unless --setups 1) to it meets no surface; every other point outside (an
// internal chamber, the inside of a narrow slot, a hollow the part stood
// on) might as well be solid for all any ray tells. The largest consistent
// solid is the part with those points: its IoU, |part| / (|part| + |unseen
// empty|), is what a reconstruction gets that fills every space no ray
// entered. It is generous to the scan: rays are taken through every point
// (a file of points holds only their hits, and no camera positions), so a
// part below 0.95 here needs more than the scan to reach 0.95.
//
// Run: build/bench/bench_observable DIR [--models 011,039,...] [--samples S]
//        [--setups 1|2] [--seed S]
//   DIR        the InverseCSG benchmark folder (NNN.off meshes)
//   --models   comma-separated model names (default: every NNN.off in DIR)
//   --samples  random points over each part's box (default 100000)
//   --setups   the scanner's setups (default 2)
//   --seed     the random points' and the scanner's seed (default 1)

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "core/statistics.h"
#include "io/mesh_files.h"
#include "mesh/mesh_solid.h"
#include "scanner/mesh_caster.h"
#include "scanner/scanner.h"

namespace {

using namespace csgvox;

struct Options {
  std::filesystem::path dir;
  std::vector<std::string> models;
  std::size_t samples = 100000;
  int setups = 2;
  std::uint64_t seed = 1;
};

struct Observed {
  double part = 0.0;    // fraction of the box inside the part
  double unseen = 0.0;  // fraction of the box outside the part that no ray reaches
  double iou = 0.0;     // of the largest consistent solid
};

Observed observe(const Options& opt, const std::filesystem::path& path) {
  const TriangleMesh mesh = readMesh(path);
  const Aabb box = mesh.bounds();
  const MeshSolid solid(mesh, box.diagonal() / 400.0);
  const MeshCaster caster(mesh);
  ScannerOptions so;
  so.setups = opt.setups;
  so.points = 1000;  // the camera positions are all that is used
  so.seed = opt.seed;
  const std::vector<Vec3> sensors = scanPart(caster, so).sensors;
  std::mt19937_64 rng(opt.seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<Vec3> points(opt.samples);
  for (Vec3& p : points) {
    for (int k = 0; k < 3; ++k) p[k] = box.min[k] + unit(rng) * (box.max[k] - box.min[k]);
  }
  // 1: inside the part; 2: outside, no ray reaches it; 0: seen empty.
  std::vector<std::uint8_t> state(points.size(), 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points.size(), 256),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t i = r.begin(); i != r.end(); ++i) {
                        const Vec3& p = points[i];
                        if (solid.contains(p)) {
                          state[i] = 1;
                          continue;
                        }
                        const bool seen =
                            std::any_of(sensors.begin(), sensors.end(), [&](const Vec3& s) {
                              const Vec3 d = p - s;
                              const double length = d.norm();
                              return !caster.firstHit(s, d / length, length);
                            });
                        state[i] = seen ? 0 : 2;
                      }
                    });
  const double n = double(points.size());
  const double part = double(std::count(state.begin(), state.end(), 1));
  const double unseen = double(std::count(state.begin(), state.end(), 2));
  return {part / n, unseen / n, part > 0.0 ? part / (part + unseen) : 0.0};
}

}  // namespace

int main(int argc, char** argv) {
  Options opt;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    const bool hasValue = i + 1 < argc;
    if (arg == "--models" && hasValue) {
      std::stringstream list(argv[++i]);
      for (std::string m; std::getline(list, m, ',');) opt.models.push_back(m);
    } else if (arg == "--samples" && hasValue) {
      opt.samples = std::stoul(argv[++i]);
    } else if (arg == "--setups" && hasValue) {
      opt.setups = std::stoi(argv[++i]);
    } else if (arg == "--seed" && hasValue) {
      opt.seed = std::stoull(argv[++i]);
    } else if (opt.dir.empty() && arg.rfind("--", 0) != 0) {
      opt.dir = arg;
    } else {
      std::fprintf(stderr,
                   "usage: %s DIR [--models 011,039,...] [--samples S] [--setups 1|2] "
                   "[--seed S]\n",
                   argv[0]);
      return 2;
    }
  }
  if (opt.dir.empty() || opt.samples == 0) {
    std::fprintf(stderr, "usage: %s DIR [--models ...] [--samples S] [--setups 1|2] [--seed S]\n",
                 argv[0]);
    return 2;
  }
  if (opt.models.empty()) {
    std::error_code ec;
    for (const auto& e : std::filesystem::directory_iterator(opt.dir, ec)) {
      if (e.path().extension() == ".off") opt.models.push_back(e.path().stem().string());
    }
    if (ec) {
      std::fprintf(stderr, "%s: %s\n", opt.dir.string().c_str(), ec.message().c_str());
      return 1;
    }
    std::sort(opt.models.begin(), opt.models.end());
  }
  std::printf(
      "observable solid of %zu models: scanner %d setup(s), %zu points per box, seed %llu\n",
      opt.models.size(), opt.setups, opt.samples, (unsigned long long)opt.seed);
  std::printf("%-6s %8s %10s %8s\n", "model", "part", "unseen", "IoU");
  std::vector<double> ious;
  std::size_t above = 0;
  for (const std::string& model : opt.models) {
    try {
      const Observed o = observe(opt, opt.dir / (model + ".off"));
      std::printf("%-6s %7.1f%% %9.2f%% %8.4f\n", model.c_str(), 100.0 * o.part, 100.0 * o.unseen,
                  o.iou);
      ious.push_back(o.iou);
      above += o.iou >= 0.95;
    } catch (const std::exception& e) {
      std::printf("%-6s error: %s\n", model.c_str(), e.what());
    }
    std::fflush(stdout);
  }
  if (!ious.empty()) {
    std::printf("\nlargest consistent solid: IoU >= 0.95 on %zu / %zu, median %.4f\n", above,
                ious.size(), median(ious));
  }
  return 0;
}
