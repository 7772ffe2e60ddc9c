#include "mesh/surface_support.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
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
  std::vector<double> d2(p.size(), 0.0);  // squared distance to the nearest scan point
  tbb::parallel_for(std::size_t{0}, p.size(), [&](std::size_t i) { scan.nearest(p[i], &d2[i]); });
  SurfaceSupport out;
  out.area = s.surfaceArea;
  out.sampleArea = s.surfaceArea / double(p.size());
  out.unsupported = out.sampleArea * double(std::count_if(d2.begin(), d2.end(),
                                                          [&](double d) { return d > limit; }));
  if (options.keepUnsupported) {
    for (std::size_t i = 0; i < p.size(); ++i) {
      if (d2[i] <= limit) continue;
      out.unsupportedSamples.push_back(p[i]);
      out.unsupportedDistances.push_back(std::sqrt(d2[i]));
    }
  }
  return out;
}

}  // namespace csgvox
