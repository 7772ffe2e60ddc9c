#include "app/batch_runner.h"

#include <fcntl.h>
#include <sched.h>
#include <signal.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <deque>
#include <fstream>
#include <map>
#include <thread>

#include "app/job_options.h"
#include "io/batch_summary.h"
#include "io/errors.h"

extern char** environ;

namespace csgvox::app {

namespace fs = std::filesystem;

namespace {

volatile std::sig_atomic_t gStop = 0;

void onStopSignal(int) { gStop = 1; }

// SIGINT and SIGTERM set gStop (without restarting system calls, so a wait
// returns) while the object lives.
class StopSignals {
 public:
  StopSignals() {
    gStop = 0;
    struct sigaction sa {};
    sa.sa_handler = onStopSignal;
    sigemptyset(&sa.sa_mask);
    sa.sa_flags = 0;
    sigaction(SIGINT, &sa, &oldInt_);
    sigaction(SIGTERM, &sa, &oldTerm_);
  }
  ~StopSignals() {
    sigaction(SIGINT, &oldInt_, nullptr);
    sigaction(SIGTERM, &oldTerm_, nullptr);
  }

 private:
  struct sigaction oldInt_ {
  }, oldTerm_{};
};

int usableCores() {
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof(set), &set) == 0) return std::max(1, CPU_COUNT(&set));
  return std::max(1u, std::thread::hardware_concurrency());
}

// MemAvailable of /proc/meminfo in GiB; infinity when unknown.
double availableMemoryGiB() {
  std::ifstream in("/proc/meminfo");
  std::string key;
  double kib = 0.0;
  std::string unit;
  while (in >> key >> kib >> unit) {
    if (key == "MemAvailable:") return kib / (1024.0 * 1024.0);
  }
  return INFINITY;
}

std::string duration(double seconds) {
  const long s = std::lround(std::max(0.0, seconds));
  char buf[32];
  if (s >= 3600) {
    std::snprintf(buf, sizeof(buf), "%ld:%02ld:%02ld", s / 3600, s / 60 % 60, s % 60);
  } else {
    std::snprintf(buf, sizeof(buf), "%ld:%02ld", s / 60, s % 60);
  }
  return buf;
}

// The job's one-line message: the last "csgvox: error: " line of its stderr.
std::string errorLine(const fs::path& log) {
  std::ifstream in(log, std::ios::binary);
  std::string line, last, lastError;
  constexpr std::string_view prefix = "csgvox: error: ";
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    last = line;
    if (line.starts_with(prefix)) lastError = line.substr(prefix.size());
  }
  return lastError.empty() ? last : lastError;
}

// Whether `folder` holds a finished job: a report.json with status "ok"
// and every file its `outputs` names (every job file without that list).
bool complete(const fs::path& folder) {
  std::ifstream in(folder / "report.json", std::ios::binary);
  if (!in) return false;
  const nlohmann::json report = nlohmann::json::parse(in, nullptr, false);
  if (!report.is_object() || report.value("status", std::string()) != "ok") return false;
  std::vector<std::string> files = jobFiles();
  if (report.contains("outputs") && report["outputs"].is_array()) {
    files.clear();
    for (const auto& name : report["outputs"]) {
      if (name.is_string()) files.push_back(name.get<std::string>());
    }
  }
  std::error_code ec;
  for (const std::string& f : files) {
    if (!fs::is_regular_file(folder / f, ec)) return false;
  }
  return true;
}

/// The progress line: a bar, done and failed counts, the running jobs and an ETA.
class Progress {
 public:
  Progress(const Console& console, int total)
      : console_(console), total_(total), tty_(isatty(STDERR_FILENO) == 1) {}

  void update(int done, int failed, int running, double elapsed, int ranNow) const {
    if (console_.quiet() || !tty_) return;
    std::fprintf(stderr, "\r\033[K%s", line(done, failed, running, elapsed, ranNow).c_str());
    std::fflush(stderr);
  }
  // A finished scan: one line of its own (above the bar on a terminal).
  void finished(const SummaryRow& row, int done, int failed, int running, double elapsed,
                int ranNow) const {
    if (console_.quiet()) return;
    char seconds[32];
    std::snprintf(seconds, sizeof(seconds), " (%.1f s)", row.seconds);
    std::string what = std::string(rowStatusName(row.status)) + " " + row.path + seconds;
    if (!row.error.empty()) what += ": " + row.error;
    if (tty_) std::fprintf(stderr, "\r\033[K");
    std::fprintf(stderr, "[%7.2f s] %s\n", console_.elapsed(), what.c_str());
    if (tty_) {
      update(done, failed, running, elapsed, ranNow);
    } else {
      std::fprintf(stderr, "[%7.2f s] %s\n", console_.elapsed(),
                   line(done, failed, running, elapsed, ranNow).c_str());
    }
  }
  void end() const {
    if (!console_.quiet() && tty_) std::fprintf(stderr, "\n");
  }

 private:
  std::string line(int done, int failed, int running, double elapsed, int ranNow) const {
    constexpr int width = 30;
    const int filled = total_ > 0 ? done * width / total_ : width;
    std::string bar = "[" + std::string(filled, '#') + std::string(width - filled, '.') + "]";
    std::string eta = "--";
    // Scans finished by this run set the pace; skipped ones took no time.
    if (ranNow > 0) eta = duration(elapsed / ranNow * (total_ - done));
    char buf[160];
    std::snprintf(buf, sizeof(buf), "%s %d/%d done, %d failed, %d running, ETA %s", bar.c_str(),
                  done, total_, failed, running, eta.c_str());
    return buf;
  }

  const Console& console_;
  int total_;
  bool tty_;
};

struct Running {
  std::size_t index = 0;
  fs::path log;
  std::chrono::steady_clock::time_point start;
};

pid_t spawnJob(const BatchOptions& options, const BatchScan& scan, int threads,
               const fs::path& log) {
  std::vector<std::string> args = {options.executable.string(),
                                   "-o",
                                   (options.outDir / scan.output).string(),
                                   "--quiet",
                                   "--threads",
                                   std::to_string(threads)};
  args.insert(args.end(), options.jobArguments.begin(), options.jobArguments.end());
  args.push_back("--");
  args.push_back(scan.file.string());
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);

  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, log.c_str(),
                                   O_WRONLY | O_CREAT | O_TRUNC, 0644);
  pid_t pid = 0;
  const int rc = posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (rc != 0) {
    throw IoError(options.executable.string() + ": cannot be started: " + std::strerror(rc));
  }
  return pid;
}

SummaryRow finishedRow(const BatchScan& scan, const BatchOptions& options, int status,
                       double seconds, const fs::path& log) {
  const fs::path folder = options.outDir / scan.output;
  SummaryRow row;
  row.path = scan.label;
  row.output = folder.string();
  row.seconds = seconds;
  if (WIFEXITED(status) && WEXITSTATUS(status) == 0) {
    try {
      return rowFromReport(folder / "report.json", scan.label, folder.string(), seconds);
    } catch (const std::exception& e) {
      row.status = RowStatus::Crashed;
      row.error = e.what();
      return row;
    }
  }
  if (WIFEXITED(status) && (WEXITSTATUS(status) == 1 || WEXITSTATUS(status) == 2)) {
    row.status = RowStatus::Error;
    row.error = errorLine(log);
    if (row.error.empty())
      row.error = "failed with exit code " + std::to_string(WEXITSTATUS(status));
    return row;
  }
  row.status = RowStatus::Crashed;
  if (WIFSIGNALED(status)) {
    row.error = std::string("killed by signal ") + std::to_string(WTERMSIG(status)) + " (" +
                sigdescr_np(WTERMSIG(status)) + ")";
  } else {
    row.error = "exit code " + std::to_string(WEXITSTATUS(status));
  }
  const std::string last = errorLine(log);
  if (!last.empty()) row.error += ": " + last;
  return row;
}

double secondsSince(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

// A batch run: the scans, the options, the summary rows being written and
// the counts, with the scans still to run and the jobs running.
struct BatchRun {
  const std::vector<BatchScan>& scans;
  const BatchOptions& options;
  SummaryWriter& summary;
  BatchOutcome& outcome;
  std::deque<std::size_t> pending{};  // scans to run, in order
  int jobs = 1;                       // at once
  int threads = 1;                    // per job
  fs::path logs{};                    // the folder of the running jobs' stderr
  std::map<pid_t, Running> running{};
  int done = 0;    // scans done, skipped ones included
  int ranNow = 0;  // scans this run finished

  // --resume: finished outputs and recorded errors are done; a finished
  // scan whose row a killed run did not write gets it now.
  void queueScans(const std::map<std::string, nlohmann::json>& recorded) {
    for (std::size_t i = 0; i < scans.size(); ++i) {
      const BatchScan& scan = scans[i];
      if (!options.resume) {
        pending.push_back(i);
        continue;
      }
      const fs::path folder = options.outDir / scan.output;
      const auto row = recorded.find(scan.label);
      const std::string status =
          row == recorded.end() ? "" : row->second.value("status", std::string());
      if (complete(folder)) {
        if (status != "ok") {
          try {
            summary.append(rowFromReport(folder / "report.json", scan.label, folder.string()));
          } catch (const ParseError&) {
            pending.push_back(i);  // not a finished job's report: run it again
            continue;
          }
        }
        ++outcome.skipped;
      } else if (status == "error") {
        ++outcome.skipped;
        ++outcome.failedBefore;
      } else {
        pending.push_back(i);
      }
    }
  }

  // Largest files first: the longest jobs start early instead of running
  // alone at the end (rows are written as scans finish in any case).
  void sortLargestFirst() {
    std::error_code ec;
    std::vector<std::uintmax_t> sizes(scans.size(), 0);
    for (const std::size_t i : pending) {
      const std::uintmax_t size = fs::file_size(scans[i].file, ec);
      sizes[i] = ec ? 0 : size;
    }
    std::stable_sort(pending.begin(), pending.end(),
                     [&](std::size_t a, std::size_t b) { return sizes[a] > sizes[b]; });
  }

  // Start jobs while there are cores, and memory for more than one.
  void startJobs() {
    while (!gStop && !pending.empty() && int(running.size()) < jobs &&
           (running.empty() || availableMemoryGiB() >= options.memoryPerJob)) {
      const std::size_t i = pending.front();
      pending.pop_front();
      const fs::path log = logs / (std::to_string(i) + ".log");
      const pid_t pid = spawnJob(options, scans[i], threads, log);
      running[pid] = {i, log, std::chrono::steady_clock::now()};
    }
  }

  // The job `pid` ended with `status`: its row is written and counted, unless
  // the run is stopping.
  void finishJob(pid_t pid, int status, const Progress& progress,
                 std::chrono::steady_clock::time_point start) {
    std::error_code ec;
    const auto job = running.find(pid);
    if (job == running.end()) return;
    const Running r = job->second;
    running.erase(job);
    if (gStop) {
      fs::remove(r.log, ec);
      return;  // interrupted: no row, --resume runs it again
    }
    const SummaryRow row =
        finishedRow(scans[r.index], options, status, secondsSince(r.start), r.log);
    fs::remove(r.log, ec);
    summary.append(row);
    ++done;
    ++ranNow;
    if (row.status == RowStatus::Ok) {
      ++outcome.ok;
    } else {
      ++outcome.failed;
    }
    progress.finished(row, done, outcome.failedBefore + outcome.failed, int(running.size()),
                      secondsSince(start), ranNow);
  }

  // Runs the pending scans until all are done or a stop signal has ended
  // the running ones.
  void runJobs(const Progress& progress) {
    const auto start = std::chrono::steady_clock::now();
    bool stopping = false;
    while (!pending.empty() || !running.empty()) {
      if (gStop && !stopping) {
        for (const auto& [p, r] : running) kill(p, SIGTERM);
        stopping = true;
      }
      startJobs();
      progress.update(done, outcome.failedBefore + outcome.failed, int(running.size()),
                      secondsSince(start), ranNow);
      if (gStop && running.empty()) break;
      if (running.empty()) {
        // Waiting for memory with nothing running cannot happen (one job
        // always starts); guard against a busy loop anyway.
        std::this_thread::sleep_for(std::chrono::milliseconds(200));
        continue;
      }
      int status = 0;
      // Without memory for another job, look again now and then.
      const bool waitingForMemory = !pending.empty() && int(running.size()) < jobs;
      const pid_t pid = waitpid(-1, &status, waitingForMemory ? WNOHANG : 0);
      if (pid == 0) {
        std::this_thread::sleep_for(std::chrono::milliseconds(500));
        continue;
      }
      if (pid < 0) {
        if (errno == ECHILD) break;
        continue;  // EINTR: a stop signal, handled at the top
      }
      finishJob(pid, status, progress, start);
    }
  }

  // Ends the running jobs and removes the logs, after a failure.
  void abandon() {
    std::error_code ec;
    for (const auto& [p, r] : running) kill(p, SIGTERM);
    for (const auto& [p, r] : running) waitpid(p, nullptr, 0);
    fs::remove_all(logs, ec);
  }
};

}  // namespace

int batchJobs(int requested, double memoryPerJob) {
  if (requested > 0) return requested;
  const double memory = availableMemoryGiB();
  int jobs = usableCores();
  if (std::isfinite(memory) && memoryPerJob > 0.0) {
    jobs = std::min<double>(jobs, std::floor(memory / memoryPerJob));
  }
  return std::max(1, jobs);
}

BatchOutcome runBatch(const std::vector<BatchScan>& scans, const BatchOptions& options,
                      const Console& console) {
  BatchOutcome outcome;
  std::error_code ec;
  const fs::path summaryDir = options.summaryDir.empty() ? options.outDir : options.summaryDir;
  for (const fs::path& dir : {options.outDir, summaryDir}) {
    fs::create_directories(dir, ec);
    if (ec) throw IoError(dir.string() + ": cannot be created: " + ec.message());
  }
  const std::map<std::string, nlohmann::json> recorded =
      options.resume ? readSummaryRows(summaryDir / "summary.jsonl")
                     : std::map<std::string, nlohmann::json>{};
  SummaryWriter summary(summaryDir, options.resume);
  BatchRun run{scans, options, summary, outcome};
  run.queueScans(recorded);
  run.sortLargestFirst();

  const int total = int(scans.size());
  run.jobs = std::min<int>(batchJobs(options.jobs, options.memoryPerJob),
                           std::max<std::size_t>(run.pending.size(), 1));
  run.threads =
      options.threadsPerJob > 0 ? options.threadsPerJob : std::max(1, usableCores() / run.jobs);
  if (options.resume && outcome.skipped > 0) {
    console.info("resume: " + std::to_string(outcome.skipped) + " of " + std::to_string(total) +
                 " scans already done");
  }
  console.info(std::to_string(run.pending.size()) + (run.pending.size() == 1 ? " scan" : " scans") +
               " to run, " + std::to_string(run.jobs) + " at once, " + std::to_string(run.threads) +
               (run.threads == 1 ? " thread" : " threads") + " each");

  run.logs = summaryDir / (".batch-logs-" + std::to_string(getpid()));
  fs::create_directories(run.logs, ec);
  if (ec) throw IoError(run.logs.string() + ": cannot be created: " + ec.message());

  Progress progress(console, total);
  run.done = outcome.skipped;
  StopSignals signals;
  try {
    run.runJobs(progress);
  } catch (...) {
    run.abandon();
    throw;
  }
  progress.end();
  fs::remove_all(run.logs, ec);
  outcome.interrupted = gStop != 0;
  return outcome;
}

}  // namespace csgvox::app
