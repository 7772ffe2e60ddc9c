#pragma once
/// The main job's options on the command line: every reconstruction option
/// registered with CLI11 from the name tables and ranges of the pipeline
/// (pipeline/reconstruct.h), into the one settings type, JobOptions.

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

#include "job/job.h"

namespace csgvox::app {

/// The command line of a command that reconstructs one scan (the main job,
/// `compare`).
struct ScanJobOptions {
  std::string scan;    ///< the scan's path
  std::vector<std::string> moreScans;  ///< further files of the same scan (the main job)
  std::string outDir;  ///< -o: the output folder (empty: beside the scan)
  JobOptions job;      ///< how to reconstruct it
};

/// Registers every reconstruction option (all but the scan and the output).
void addJobOptions(CLI::App& app, JobOptions& options);

}  // namespace csgvox::app
