#pragma once
/// What the main job and `compare` share: the options of a reconstruction
/// (any method), and the outputs of one finished reconstruction (tree.json,
/// tree.scad, tree.txt, mesh.ply, report.json) with its fit figures.

#include <CLI/CLI.hpp>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "app/console.h"
#include "io/output_set.h"
#include "io/scan_reader.h"
#include "pipeline/reconstruct.h"

namespace csgvox::app {

/// The reconstruction options as given on the command line.
struct JobSettings {
  int resolution = 64;
  std::uint64_t seed = 1;
  std::string method = "hybrid";
  std::string labelMethod = "winding";
  std::string boundary = "centre";
  std::string operations = "minmax";
  std::string refineOperations = "minmax";  ///< hybrid: minmax, rfunction or sardf
  ReconstructOptions pipeline;
  int meshResolution = 160;
  bool preview = true;  ///< write preview.png
};

/// The command line of a command that reconstructs one scan (the main job,
/// `compare`).
struct ScanJobOptions {
  std::string scan;    ///< the scan's path
  std::string outDir;  ///< -o: the output folder (empty: beside the scan)
  JobSettings job;     ///< how to reconstruct it
};

/// Registers every reconstruction option (all but the scan and the output).
void addJobOptions(CLI::App& app, JobSettings& settings);

/// The pipeline options the settings stand for.
ReconstructOptions pipelineOptions(const JobSettings& settings);

/// The files of one job (tree.step and preview.png may be skipped: see writeJob).
inline const std::vector<std::string>& jobFiles() {
  static const std::vector<std::string> files = {"tree.json", "tree.scad",  "tree.txt",
                                                 "tree.csg",  "tree.step",  "preview.png",
                                                 "mesh.ply",  "report.json"};
  return files;
}

/// Writes a finished reconstruction's files into `output` (not committed)
/// and returns its report (also written as report.json, whose `outputs`
/// lists the files written). `timings` holds the seconds of the steps before
/// (read, ...); export, step, preview and metrics are added. preview.png is
/// skipped with settings.preview off; tree.step is skipped, with one error
/// line on stderr naming the node and a warning in the report, when
/// OpenCASCADE cannot build the solid (or the build has no OpenCASCADE):
/// the other files are still written.
nlohmann::ordered_json writeJob(OutputSet& output, const std::filesystem::path& scanPath,
                                const Scan& scan, const Reconstruction& rec,
                                const JobSettings& settings, nlohmann::ordered_json timings,
                                const Console& console);

/// The report of a finished reconstruction (report.json's content, as
/// writeJob writes it): the settings, counts, the tree's size, its fit
/// metrics against the scan, `timings` with the metrics' seconds added, and
/// `warnings` with any metric that cannot be computed added. `outputs`
/// lists the files staged in `output` (empty without one).
nlohmann::ordered_json jobReport(const std::filesystem::path& scanPath, const Scan& scan,
                                 const Reconstruction& rec, const JobSettings& settings,
                                 nlohmann::ordered_json timings, nlohmann::ordered_json warnings,
                                 const Console& console, const OutputSet* output = nullptr);

}  // namespace csgvox::app
