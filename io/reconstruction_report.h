#pragma once
/// report.json: the schema of a finished reconstruction's report, one
/// builder per kind of result (voxel, hybrid, gp, or a tree read from a
/// file). The caller measures the tree (TreeMetrics) and prints; these only
/// shape the document. The format is documented in docs/formats.md.

#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "evolve/fitness.h"
#include "io/scan_reader.h"
#include "mesh/fit_metrics.h"
#include "pipeline/reconstruct.h"

namespace csgvox {

/// The figures of a tree against its scan that a report carries.
struct TreeMetrics {
  double voxelIou = 0.0;          ///< the tree's voxels against the inside labels
  std::optional<FitMetrics> fit;  ///< surface figures (absent when they could not be computed)
  Fitness fitness;                ///< Eq. 7 on every scan point (min/max, the gp tolerances)
};

/// Seconds of a job's steps, as report.json gives them: `wall` (timings_s)
/// and `cpu` (cpu_s: CPU seconds of the process, all threads), each an
/// object of step name to seconds in the order the steps ran.
struct StepTimes {
  nlohmann::ordered_json wall = nlohmann::ordered_json::object();  ///< wall-clock seconds per step
  nlohmann::ordered_json cpu = nlohmann::ordered_json::object();   ///< CPU seconds per step
  /// Records one step's seconds (a step recorded again is overwritten).
  void add(const std::string& step, double wallSeconds, double cpuSeconds) {
    wall[step] = wallSeconds;
    cpu[step] = cpuSeconds;
  }
};

/// What every report holds besides the method's own part.
struct ReportContext {
  std::filesystem::path scanPath;  ///< the scan's file, as given
  const Scan* scan = nullptr;      ///< the scan read from it (required)
  double timeLimit = 0.0;          ///< seconds the reconstruction was given (0: none)
  TreeMetrics metrics;             ///< the tree measured against the scan
  nlohmann::ordered_json warnings = nlohmann::ordered_json::array();  ///< one line each
  std::vector<std::string> outputs;                                   ///< files written
  StepTimes timings;  ///< wall-clock and CPU seconds per step
};

/// report.json of a reconstruction built by `rec.method` with `options`:
/// status, input, parameters, grid, counts, the method's own sections
/// (hybrid: repair and finish; gp: partitioning), tree, metrics, warnings,
/// outputs, timings_s and cpu_s.
/// @throw std::invalid_argument when rec holds no method result or ctx no scan.
nlohmann::ordered_json reconstructionReport(const Reconstruction& rec,
                                            const ReconstructOptions& options,
                                            const ReportContext& ctx);

/// A tree read from a file rather than built (`compare --import-gp`),
/// measured on the grid and labels of a detection of the same scan.
struct ImportedTree {
  const CsgTree* tree = nullptr;    ///< the tree (required)
  const VoxelGrid* grid = nullptr;  ///< the grid it was measured on (required)
  int resolution = 0;               ///< the grid's resolution
  std::size_t surfaces = 0;         ///< surfaces the detection found
};

/// report.json of an imported tree: the scan-side settings of `options`,
/// the grid, the detection's surface count, tree, metrics, warnings,
/// outputs, timings_s and cpu_s.
/// @throw std::invalid_argument when the tree, grid or scan is missing.
nlohmann::ordered_json importedTreeReport(const ImportedTree& imported,
                                          const ReconstructOptions& options,
                                          const ReportContext& ctx);

}  // namespace csgvox
