#pragma once
// The main job on a raw scan with one of its stages on and off, for the
// tests that measure what the stage adds to a tree.

#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <functional>

#include "io/scan_reader.h"
#include "io/tree_json.h"
#include "pipeline/reconstruct.h"
#include "test_helpers.h"

namespace csgvox::test {

struct MainJobPair {
  CsgTree truth;
  Reconstruction with, without;            // the stage on (the defaults), off
  double iouWith = 0.0, iouWithout = 0.0;  // against the truth
};

// Reads the raw scan `scanFile` (normals estimated) and the true tree
// `treeFile`, runs the main job on seed `seed` with its defaults and again
// after `off` changed its options. Fails the test (and returns what it has)
// when the scan had normals or a run failed.
inline MainJobPair mainJobWithAndWithout(const std::filesystem::path& scanFile,
                                         const std::filesystem::path& treeFile, std::uint64_t seed,
                                         const std::function<void(ReconstructOptions&)>& off) {
  MainJobPair pair;
  const Scan scan = readScan(scanFile);
  EXPECT_TRUE(scan.info.normalsEstimated) << scanFile;
  pair.truth = readTreeJson(treeFile);
  ReconstructOptions options;
  options.seed = seed;
  options.detect.estimatedNormals = true;
  pair.with = reconstruct(scan.cloud, options);
  EXPECT_TRUE(pair.with.ok()) << pair.with.message;
  off(options);
  pair.without = reconstruct(scan.cloud, options);
  EXPECT_TRUE(pair.without.ok()) << pair.without.message;
  if (pair.with.ok()) pair.iouWith = treeIou(pair.with.tree, pair.truth);
  if (pair.without.ok()) pair.iouWithout = treeIou(pair.without.tree, pair.truth);
  return pair;
}

}  // namespace csgvox::test
