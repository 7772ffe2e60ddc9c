#pragma once
/// The main job after the reconstruction, shared by the command line
/// (`csgvox SCAN`, `compare`, `batch`) and the Python module: its options,
/// its files (tree.json, tree.scad, tree.txt, tree.csg, tree.step,
/// preview.png, mesh.ply, report.json) and the measurements its report
/// carries. No command-line parsing here (see app/job_options.h).

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "io/output_set.h"
#include "io/reconstruction_report.h"
#include "io/scan_reader.h"
#include "job/console.h"
#include "pipeline/reconstruct.h"

namespace csgvox {

/// Everything a job is told: the reconstruction's options and how its
/// files are made.
struct JobOptions {
  ReconstructOptions reconstruct;  ///< the reconstruction (method, resolution, seed, ...)
  /// Wall-clock seconds for the reconstruction (0: none): the deadline of
  /// its RunControl (see reconstruct()).
  double timeLimit = 0.0;
  int meshResolution = 160;  ///< grid of mesh.ply along the longest side
  bool preview = true;       ///< write preview.png
  /// Write the tree as fitted (no frame, snapped values, parameters or
  /// patterns): every file then holds the fitted numbers. Off: the files
  /// hold the designed tree (design/designed_tree.h).
  bool rawValues = false;
};

/// The files of one job (tree.step and preview.png may be skipped: see writeJob).
const std::vector<std::string>& jobFiles();

/// The tree measured against its scan as report.json gives it: voxel IoU,
/// Chamfer / RMSE (a failure is added to `warnings` and printed), and
/// Eq. 7's fitness on every point (min/max with the gp tolerances,
/// whatever built the tree: the figure `compare` ranks methods by).
TreeMetrics measureTree(const CsgTree& tree, const Scan& scan, double voxelIou,
                        const JobOptions& options, nlohmann::ordered_json& warnings,
                        const Console& console);

/// Writes a finished reconstruction's files into `output` (not committed)
/// and returns its report (also written as report.json, whose `outputs`
/// lists the files written). `timings` holds the wall-clock and CPU seconds of
/// the steps before (read, ...); design, export, step, preview and metrics are added
/// (tree.step is built on a task of its own while the other files are written and the
/// tree is measured: with two threads or more it leaves the critical path). preview.png is
/// skipped with options.preview off; tree.step is skipped, with one error
/// line on stderr naming the node and a warning in the report, when
/// OpenCASCADE cannot build the solid (or the build has no OpenCASCADE):
/// the other files are still written. A cancel request to `control` stops
/// the meshing and the STEP export with CancelledError (its deadline does
/// not apply: the files of a finished tree are always written whole).
nlohmann::ordered_json writeJob(OutputSet& output, const std::filesystem::path& scanPath,
                                const Scan& scan, const Reconstruction& rec,
                                const JobOptions& options, StepTimes timings,
                                const Console& console, const RunControl& control = {});

/// As writeJob, for a tree read from a file (`compare --import-gp`) and
/// measured on a detection's grid and labels.
nlohmann::ordered_json writeImportedJob(OutputSet& output, const std::filesystem::path& scanPath,
                                        const Scan& scan, const ImportedTree& imported,
                                        double voxelIou, const JobOptions& options,
                                        const Console& console, const RunControl& control = {});

/// The report of a finished reconstruction without its files (what the
/// Python module returns): report.json's content with no outputs.
nlohmann::ordered_json reportWithoutFiles(const std::filesystem::path& scanPath, const Scan& scan,
                                          const Reconstruction& rec, const JobOptions& options,
                                          StepTimes timings, const Console& console);

}  // namespace csgvox
