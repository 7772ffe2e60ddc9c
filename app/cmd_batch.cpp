// csgvox batch INPUT... -o OUTDIR [--jobs N] [--resume] [main-job options]:
// the main job on every scan of the inputs, a row per scan in
// summary.jsonl and summary.csv.

#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "app/batch_inputs.h"
#include "app/batch_runner.h"
#include "app/commands.h"
#include "app/job_options.h"
#include "app/options.h"
#include "io/errors.h"
#include "job/console.h"

namespace csgvox::app {

namespace fs = std::filesystem;

namespace {

struct CommandOptions {
  std::vector<std::string> inputs;
  std::string outDir;
  std::string summaryDir;
  bool list = false;
  int task = 0;
  int jobs = 0;
  bool resume = false;
  JobOptions job;
};

// The main-job options given on the command line, as words for the jobs.
std::vector<std::string> givenOptions(const CLI::App& group) {
  std::vector<std::string> words;
  for (const CLI::Option* opt : group.get_options()) {
    if (opt->count() == 0) continue;
    const std::string name = opt->get_name();
    if (opt->get_type_size() == 0) {
      words.push_back(name);
      continue;
    }
    for (const std::string& value : opt->results()) {
      words.push_back(name);
      words.push_back(value);
    }
  }
  return words;
}

}  // namespace

Command setupBatch(CLI::App& app, CommonOptions& common) {
  auto opt = std::make_shared<CommandOptions>();
  app.option_defaults()->always_capture_default();
  app.add_option("INPUT", opt->inputs,
                 "Scan files, folders (every scan file under them) or text files listing paths")
      ->required();
  app.add_option("-o,--output", opt->outDir,
                 "Output folder: a folder per scan with the main job's files, summary.jsonl and "
                 "summary.csv")
      ->required();
  app.add_option("-j,--jobs", opt->jobs,
                 "Scans at once (0: as many as the cores and the available memory allow)")
      ->check(inRange(0, 1024));
  app.add_flag("--resume", opt->resume,
               "Skip scans whose outputs are complete or whose error is recorded; keep the "
               "summary's rows");
  app.add_option("--summary-dir", opt->summaryDir,
                 "Folder of summary.jsonl and summary.csv (default: the output folder); one per "
                 "task when tasks of a cluster share the output folder");
  app.add_flag("--list", opt->list,
               "Print the scans the inputs hold, one path per line, and run nothing");
  app.add_option("--task", opt->task,
                 "Run only the N-th scan (from 1) of the inputs, in the order --list prints them: "
                 "one task of a job list or job array")
      ->check(inRange(1, 1e9));
  CLI::Option_group* job = app.add_option_group("Main job", "Options of every scan's main job");
  addJobOptions(*job, opt->job);
  return [opt, job, &common]() -> int {
    Console console(common.quiet);
    BatchOptions bo;
    bo.outDir = opt->outDir;
    bo.summaryDir = opt->summaryDir;
    bo.jobs = opt->jobs;
    bo.threadsPerJob = common.threads;
    bo.resume = opt->resume;
    bo.jobArguments = givenOptions(*job);
    std::vector<BatchScan> scans = collectScans(opt->inputs, bo.outDir);
    if (scans.empty()) throw IoError("no scan files found in the inputs");
    if (opt->task > 0) {
      if (std::size_t(opt->task) > scans.size()) {
        throw IoError("task " + std::to_string(opt->task) + ": the inputs hold only " +
                      std::to_string(scans.size()) + " scans");
      }
      scans = {scans[std::size_t(opt->task) - 1]};
    }
    if (opt->list) {
      for (const BatchScan& scan : scans) std::printf("%s\n", scan.label.c_str());
      return 0;
    }
    const BatchOutcome out = runBatch(scans, bo, console);
    const fs::path summaryDir = bo.summaryDir.empty() ? bo.outDir : bo.summaryDir;
    const int failed = out.failed + out.failedBefore;
    console.info("batch: " + std::to_string(out.ok) + " reconstructed, " +
                 std::to_string(out.failed) + " failed, " + std::to_string(out.skipped) +
                 " already done; rows in " + (summaryDir / "summary.csv").string());
    if (out.interrupted) {
      std::fprintf(stderr, "csgvox: error: interrupted; run again with --resume to finish\n");
      return 130;
    }
    if (failed > 0) {
      throw ParseError(std::to_string(failed) + " of " + std::to_string(scans.size()) +
                       " scans failed; see " + (summaryDir / "summary.csv").string());
    }
    return 0;
  };
}

}  // namespace csgvox::app
