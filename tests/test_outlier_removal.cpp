// Tests for primitives/outlier_removal.h: injected outliers and mixed pixels
// found, true points kept (also where the scan is ten times sparser), the
// bundled scans left alone, determinism across thread counts.

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <filesystem>
#include <string>
#include <vector>

#include "core/nearest_neighbors.h"
#include "io/point_arrays.h"
#include "io/scan_reader.h"
#include "primitives/outlier_removal.h"
#include "raw_scan.h"

namespace csgvox {
namespace {

namespace fs = std::filesystem;

TEST(FindOutliers, FindsInjectedOutliersAndKeepsTheSurface) {
  for (const char* part : {"stepped_shaft", "flange", "pipe_tee"}) {
    for (std::uint64_t seed : {1, 2}) {
      SCOPED_TRACE(std::string(part) + " seed " + std::to_string(seed));
      test::RawScanOptions o;
      o.seed = seed;
      const test::RawScan raw = test::makeRawScan(part, o);
      const Outliers found = findOutliers(raw.points);
      // Scattered outliers farther from the surface than 1 % of D (nearer
      // ones are as close as the points of the sparse region are apart).
      std::vector<Vec3> surface;
      for (std::size_t i = 0; i < raw.points.size(); ++i) {
        if (raw.kind[i] == 0) surface.push_back(raw.points[i]);
      }
      const NearestNeighbors tree(surface);
      std::size_t far = 0, farFound = 0, all = 0, allFound = 0, kept = 0;
      for (std::size_t i = 0; i < raw.points.size(); ++i) {
        if (raw.kind[i] == 0) {
          kept += !found.outlier[i];
          continue;
        }
        if (raw.kind[i] != 1) continue;
        ++all;
        allFound += found.outlier[i];
        double d2 = 0.0;
        tree.nearest(raw.points[i], &d2);
        if (d2 > 1e-4 * raw.diagonal * raw.diagonal) {
          ++far;
          farFound += found.outlier[i];
        }
      }
      // Measured: 88 % to 98 % of the far ones; those left lie near the
      // surface or next to another outlier.
      EXPECT_GE(double(farFound), 0.85 * double(far));
      EXPECT_GE(double(allFound), 0.8 * double(all));
      EXPECT_GT(double(kept), 0.995 * double(surface.size()));
    }
  }
}

TEST(FindOutliers, KeepsASparseRegionAndThinFeatures) {
  // No injected points: 30 % of the part ten times sparser, noise, a
  // doubled surface; and the thin parts.
  test::RawScanOptions o;
  o.outliers = 0.0;
  o.mixedPixels = 0.0;
  const test::RawScan raw = test::makeRawScan("flange", o);
  EXPECT_LE(findOutliers(raw.points).count(), raw.points.size() / 500);
  for (const char* part : {"thin/pin_base", "thin/sheet_bracket", "thin/slotted_plate"}) {
    SCOPED_TRACE(part);
    const Scan scan = readScan(fs::path(CSGVOX_DATA_DIR) / part / "scan.ply", [] {
      ReadOptions r;
      r.removeOutliers = false;
      return r;
    }());
    EXPECT_EQ(findOutliers(scan.cloud.points).count(), 0u);
  }
}

TEST(FindOutliers, TheBundledScansLoseAlmostNothing) {
  // Clean scans: at most a point each (measured: 0 on 10 of 12, 1 on two).
  // (The noisy ones, sigma 0.5 % of D, lose 0 to 3 of 10 000.)
  for (const auto& entry : fs::directory_iterator(CSGVOX_DATA_DIR)) {
    const fs::path path = entry.path() / "scan.ply";
    if (!fs::exists(path)) continue;
    SCOPED_TRACE(path.string());
    EXPECT_LE(readScan(path).info.outliersRemoved, 1u);
  }
}

TEST(FindOutliers, SameResultWithAnyNumberOfThreads) {
  const test::RawScan raw = test::makeRawScan("flange");
  Outliers one, two;
  {
    const tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    one = findOutliers(raw.points);
  }
  {
    const tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
    two = findOutliers(raw.points);
  }
  EXPECT_EQ(one.outlier, two.outlier);
}

TEST(FindOutliers, TheReaderCountsWhatItRemoves) {
  const test::RawScan raw = test::makeRawScan("stepped_shaft");
  const std::size_t found = findOutliers(raw.points).count();
  const Scan scan = scanFromArrays(raw.points, {});
  EXPECT_EQ(scan.info.outliersRemoved, found);
  EXPECT_EQ(scan.cloud.size(), raw.points.size() - found);
  EXPECT_GT(found, raw.count(1) / 2);
}

}  // namespace
}  // namespace csgvox
