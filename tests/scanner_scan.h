#pragma once
// A bundled part as the project's scanner model scans it (its defaults:
// two setups, depth noise, mixed pixels, outliers), for tests.

#include <cstddef>
#include <string>

#include "core/point_cloud.h"
#include "io/tree_json.h"
#include "part_list.h"
#include "scanner/scanner.h"
#include "scanner/tree_caster.h"

namespace csgvox::test {

/// `points` points of data/<part>/tree.json, with the scanner's own normals
/// or none.
inline PointCloud scannerScan(const std::string& part, std::size_t points,
                              ScannerNormals normals) {
  const CsgTree truth = readTreeJson(dataDir() / part / "tree.json");
  const TreeCaster caster(truth);
  ScannerOptions so;
  so.normals = normals;
  so.points = points;
  return scanPart(caster, so).cloud;
}

}  // namespace csgvox::test
