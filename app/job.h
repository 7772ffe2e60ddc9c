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
  std::string method = "voxel";
  std::string labelMethod = "winding";
  std::string boundary = "centre";
  std::string operations = "minmax";
  ReconstructOptions pipeline;
  int meshResolution = 160;
};

/// Registers every reconstruction option (all but the scan and the output).
void addJobOptions(CLI::App& app, JobSettings& settings);

/// The pipeline options the settings stand for.
ReconstructOptions pipelineOptions(const JobSettings& settings);

/// The files of one job.
inline const std::vector<std::string>& jobFiles() {
  static const std::vector<std::string> files = {"tree.json", "tree.scad", "tree.txt", "mesh.ply",
                                                 "report.json"};
  return files;
}

/// Writes a finished reconstruction's files into `output` (not committed)
/// and returns its report (also written as report.json). `timings` holds the
/// seconds of the steps before (read, ...); export and metrics are added.
nlohmann::ordered_json writeJob(const OutputSet& output, const std::filesystem::path& scanPath,
                                const Scan& scan, const Reconstruction& rec,
                                const JobSettings& settings, nlohmann::ordered_json timings,
                                const Console& console);

/// The report of a finished reconstruction (report.json without writing
/// it): the settings, counts, the tree's size, its fit metrics against the
/// scan (a metric that cannot be computed is a warning) and `timings` with
/// the metrics' seconds added.
nlohmann::ordered_json jobReport(const std::filesystem::path& scanPath, const Scan& scan,
                                 const Reconstruction& rec, const JobSettings& settings,
                                 nlohmann::ordered_json timings, const Console& console);

}  // namespace csgvox::app
