#include "mesh/surface_support.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <stdexcept>

#include "mesh/surface_sampler.h"

namespace csgvox {

SurfaceSupport surfaceSupport(const CsgTree& tree, const NearestNeighbors& scan,
                              const SupportOptions& options) {
  if (scan.size() == 0) throw std::invalid_argument("no scan points to support the surface");
  SampleOptions so;
  so.points = options.samples;
  so.seed = options.seed;
  const SurfaceSample s = sampleSurface(tree, so);
  const double limit = options.distance * options.distance;
  const std::vector<Vec3>& p = s.cloud.points;
  const std::size_t far = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, p.size()), std::size_t{0},
      [&](const tbb::blocked_range<std::size_t>& r, std::size_t n) {
        for (std::size_t i = r.begin(); i < r.end(); ++i) {
          double d2 = 0.0;
          scan.nearest(p[i], &d2);
          n += d2 > limit;
        }
        return n;
      },
      [](std::size_t a, std::size_t b) { return a + b; });
  return {s.surfaceArea, s.surfaceArea * double(far) / double(p.size())};
}

}  // namespace csgvox
