#include "mesh/surface_support.h"

#include <tbb/parallel_for.h>

#include <algorithm>
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
  std::vector<char> far(p.size(), 0);
  tbb::parallel_for(std::size_t{0}, p.size(), [&](std::size_t i) {
    double d2 = 0.0;
    scan.nearest(p[i], &d2);
    far[i] = d2 > limit;
  });
  SurfaceSupport out;
  out.area = s.surfaceArea;
  out.sampleArea = s.surfaceArea / double(p.size());
  out.unsupported = out.sampleArea * double(std::count(far.begin(), far.end(), 1));
  if (options.keepUnsupported) {
    for (std::size_t i = 0; i < p.size(); ++i)
      if (far[i]) out.unsupportedSamples.push_back(p[i]);
  }
  return out;
}

}  // namespace csgvox
