#pragma once
/// Runs the main job on many scans, several at once, each in its own
/// process (`csgvox SCAN -o FOLDER --quiet [job options]`), so every scan
/// gets exactly the files and the tree a single run gives it, and a scan
/// that crashes or runs out of memory costs only its own row.

#include <filesystem>
#include <string>
#include <vector>

#include "app/batch_inputs.h"
#include "job/console.h"

namespace csgvox::app {

/// Options of runBatch().
struct BatchOptions {
  std::filesystem::path outDir;      ///< the scans' output folders go here
  std::filesystem::path summaryDir;  ///< summary.jsonl and summary.csv go here (empty: outDir)
  int jobs = 0;  ///< scans at once (0: as many as the cores and the available memory allow)
  int threadsPerJob = 0;  ///< worker threads of each job (0: the cores shared among the jobs)
  bool resume = false;  ///< skip scans with complete outputs or a recorded error; keep the summary
  std::vector<std::string> jobArguments;  ///< main-job options given to every job, as words
  std::filesystem::path executable = "/proc/self/exe";  ///< the csgvox executable to run
  double memoryPerJob = 1.0;  ///< GiB of available memory another job waits for
};

/// What runBatch() did.
struct BatchOutcome {
  int ok = 0;                ///< scans reconstructed now
  int failed = 0;            ///< scans that failed now (a row each)
  int skipped = 0;           ///< scans --resume found done (including failedBefore)
  int failedBefore = 0;      ///< skipped scans whose recorded row is a failure
  bool interrupted = false;  ///< SIGINT or SIGTERM stopped the batch (unfinished scans have no row)
};

/// The number of scans run at once for `requested` jobs (0: automatic):
/// the cores this process may use, fewer when the available memory holds
/// fewer jobs of `memoryPerJob` GiB; at least 1.
int batchJobs(int requested, double memoryPerJob);

/// Runs the main job on every scan, the largest files first, and appends a
/// row per finished scan to summary.jsonl and summary.csv in
/// options.summaryDir (default options.outDir). A failing scan is a row
/// (status "error" with the job's one-line message, or "crashed"), never an
/// abort. Progress (done and failed counts, an ETA) goes to stderr unless
/// the console is quiet.
/// @throw IoError when the output folder or the summary cannot be written,
///        or a job cannot be started.
BatchOutcome runBatch(const std::vector<BatchScan>& scans, const BatchOptions& options,
                      const Console& console);

}  // namespace csgvox::app
