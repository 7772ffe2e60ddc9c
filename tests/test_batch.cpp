// csgvox batch: inputs, rows, failures, --resume, interruption, and the
// trees of single runs.

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <thread>

#include "cli_helpers.h"

namespace csgvox {
namespace {

std::vector<nlohmann::json> jsonRows(const fs::path& jsonl) {
  std::vector<nlohmann::json> rows;
  std::istringstream in(slurp(jsonl));
  for (std::string line; std::getline(in, line);) rows.push_back(nlohmann::json::parse(line));
  return rows;
}

std::vector<std::string> lines(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) out.push_back(line);
  return out;
}

// The first `bytes` bytes of a scan: a PLY whose data is truncated.
void writeTruncated(const fs::path& from, const fs::path& to, std::size_t bytes = 2000) {
  write(to, slurp(from).substr(0, bytes));
}

std::map<fs::path, fs::file_time_type> treeTimes(const fs::path& out) {
  std::map<fs::path, fs::file_time_type> times;
  for (const auto& e : fs::recursive_directory_iterator(out)) {
    if (e.path().filename() == "tree.json") times[e.path()] = e.last_write_time();
  }
  return times;
}

class Batch : public Cli {};

// The acceptance run: every bundled scan, one of them broken, gives
// a row per scan (23 ok, 1 error), trees identical to single runs, and
// --resume then does nothing.
TEST_F(Batch, BundledScansWithOneBrokenGiveRowsAndResumeDoesNothing) {
  const fs::path in = dir_ / "in";
  std::vector<fs::path> scans;
  for (const std::string& part : test::partNames()) {
    for (const char* name : {"scan.ply", "scan_noisy.ply"}) {
      fs::create_directories(in / part);
      scans.push_back(in / part / name);
      fs::create_symlink(test::dataDir() / part / name, scans.back());
    }
  }
  ASSERT_EQ(scans.size(), 24u);
  const fs::path broken = in / "knob" / "scan_noisy.ply";
  fs::remove(broken);
  writeTruncated(test::dataDir() / "knob" / "scan_noisy.ply", broken);

  const fs::path out = dir_ / "out";
  const RunResult r = run("batch '" + in.string() + "' -o '" + out.string() + "' --jobs 2", dir_);
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_NE(r.err.find("csgvox: error: 1 of 24 scans failed"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("24/24 done, 1 failed"), std::string::npos) << r.err;
  const std::vector<nlohmann::json> rows = jsonRows(out / "summary.jsonl");
  ASSERT_EQ(rows.size(), 24u);
  EXPECT_EQ(lines(slurp(out / "summary.csv")).size(), 25u);
  int ok = 0;
  std::vector<nlohmann::json> okRows;
  for (const nlohmann::json& row : rows) {
    if (row["status"] == "ok") {
      ++ok;
      okRows.push_back(row);
      for (const char* f : {"tree.json", "tree.scad", "tree.txt", "mesh.ply", "report.json"}) {
        EXPECT_TRUE(fs::exists(fs::path(row["output"].get<std::string>()) / f)) << row;
      }
      EXPECT_GE(row["primitives"].get<int>(), 1);
      EXPECT_GT(row["voxel_iou"].get<double>(), 0.5);
      EXPECT_LE(row["voxel_iou"].get<double>(), 1.0);
      EXPECT_GT(row["seconds"].get<double>(), 0.0);
    } else {
      EXPECT_EQ(row["status"], "error");
      EXPECT_EQ(row["path"], broken.string());
      EXPECT_TRUE(row["primitives"].is_null());
      const std::string message = row["error"].get<std::string>();
      EXPECT_NE(message.find(broken.string() + ": truncated"), std::string::npos) << message;
      // The main job's own message for that scan.
      const RunResult single =
          run("'" + broken.string() + "' -o '" + (dir_ / "x").string() + "'", dir_);
      EXPECT_EQ(single.err, "csgvox: error: " + message + "\n");
    }
  }
  EXPECT_EQ(ok, 23);

  // Single runs give the same trees and figures (three of the scans).
  for (std::size_t i = 0; i < 3; ++i) {
    const nlohmann::json& row = okRows[i * 7];
    const fs::path single = dir_ / ("single" + std::to_string(i));
    const RunResult s =
        run("'" + row["path"].get<std::string>() + "' -o '" + single.string() + "' --quiet", dir_);
    ASSERT_EQ(s.code, 0) << s.err;
    EXPECT_EQ(slurp(single / "tree.json"),
              slurp(fs::path(row["output"].get<std::string>()) / "tree.json"))
        << row["path"];
    const nlohmann::json report = nlohmann::json::parse(slurp(single / "report.json"));
    EXPECT_EQ(report["tree"]["primitives"], row["primitives"]);
    EXPECT_EQ(report["tree"]["operations"], row["operations"]);
    EXPECT_EQ(report["metrics"]["voxel_iou"], row["voxel_iou"]);
    EXPECT_EQ(report["metrics"]["chamfer"], row["chamfer"]);
  }

  // --resume: nothing to run, no row added, no output rewritten.
  const std::string jsonl = slurp(out / "summary.jsonl"), csv = slurp(out / "summary.csv");
  const auto times = treeTimes(out);
  const RunResult again =
      run("batch '" + in.string() + "' -o '" + out.string() + "' --jobs 2 --resume", dir_);
  EXPECT_NE(again.err.find("resume: 24 of 24 scans already done"), std::string::npos) << again.err;
  EXPECT_NE(again.err.find("0 scans to run"), std::string::npos) << again.err;
  EXPECT_EQ(slurp(out / "summary.jsonl"), jsonl);
  EXPECT_EQ(slurp(out / "summary.csv"), csv);
  EXPECT_EQ(treeTimes(out), times);
}

TEST_F(Batch, FindsScansInFoldersAndLists) {
  const fs::path in = dir_ / "in";
  fs::create_directories(in / "sub");
  fs::create_directories(in / ".hidden");
  fs::create_directories(in / "done");
  fs::create_directories(in / "out" / "x");
  const std::string ply = asciiPly(200);
  write(in / "a.ply", ply);
  write(in / "sub" / "b.xyz", "0 0 0\n1 0 0\n");
  write(in / "points.txt", "3\n# a comment\n0 0 0\n1 1 1\n2 2 2\n");
  write(in / "notes.txt", "not points at all\n");
  write(in / "tree.json", "{}");
  write(in / ".hidden" / "c.ply", ply);
  write(in / "done" / "report.json", "{}");  // a job's output folder
  write(in / "done" / "mesh.ply", ply);
  write(in / "out" / "x" / "y.ply", ply);  // the batch's own output folder
  const std::string outArg = " -o '" + (in / "out").string() + "'";
  RunResult r = run("batch --list '" + in.string() + "'" + outArg, dir_);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.out, (in / "a.ply").string() + "\n" + (in / "points.txt").string() + "\n" +
                       (in / "sub" / "b.xyz").string() + "\n");

  // A list: paths relative to its folder, comments and blank lines skipped;
  // a file reached twice is kept once.
  write(dir_ / "scans.lst", "# scans\nin/a.ply\n\n  in/sub  \nin/a.ply\n");
  r = run("batch --list '" + (dir_ / "scans.lst").string() + "'" + outArg, dir_);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.out, (dir_ / "in/a.ply").string() + "\n" + (dir_ / "in/sub/b.xyz").string() + "\n");
  // A .txt of paths is a list too.
  write(dir_ / "scans.txt", "in/points.txt\n");
  r = run("batch --list '" + (dir_ / "scans.txt").string() + "'" + outArg, dir_);
  EXPECT_EQ(r.out, (dir_ / "in/points.txt").string() + "\n") << r.err;

  expectCleanError("batch '" + (dir_ / "missing").string() + "'" + outArg, "missing");
  write(dir_ / "bad.lst", "in/a.ply\nnowhere.ply\n");
  expectCleanError("batch '" + (dir_ / "bad.lst").string() + "'" + outArg, "line 2");
  write(in / "a.xyz", "0 0 0\n");
  expectCleanError("batch '" + in.string() + "'" + outArg, "a.xyz");  // same output folder as a.ply
  fs::remove_all(in);
  fs::create_directories(in);
  expectCleanError("batch '" + in.string() + "'" + outArg, "no scan files");
  EXPECT_EQ(run("batch '" + in.string() + "'", dir_).code, 2);  // -o is required
  EXPECT_EQ(run("batch x.ply -o o --jobs -1", dir_).code, 2);
  EXPECT_EQ(run("batch x.ply -o o --res 5", dir_).code, 2);  // main-job options are checked
}

TEST_F(Batch, OptionsReachTheJobsAndATornSummaryIsRepaired) {
  const fs::path in = dir_ / "in";
  fs::create_directories(in);
  fs::copy_file(test::dataDir() / "wedge_block" / "scan.ply", in / "wedge.ply");
  fs::copy_file(test::dataDir() / "l_bracket" / "scan.ply", in / "bracket.ply");
  writeTruncated(test::dataDir() / "knob" / "scan.ply", in / "broken.ply");
  const fs::path out = dir_ / "out";
  const std::string cmd = "batch '" + in.string() + "' -o '" + out.string() +
                          "' --quiet --res 16 --mesh-res 16 --seed 5 --label vote";
  RunResult r = run(cmd, dir_);
  EXPECT_EQ(r.code, 1);
  EXPECT_EQ(r.err,
            "csgvox: error: 1 of 3 scans failed; see " + (out / "summary.csv").string() + "\n");
  const nlohmann::json report = nlohmann::json::parse(slurp(out / "wedge" / "report.json"));
  EXPECT_EQ(report["parameters"]["res"], 16);
  EXPECT_EQ(report["parameters"]["seed"], 5);
  EXPECT_EQ(report["parameters"]["label"], "vote");

  // The error's commas are quoted in the CSV.
  const std::vector<std::string> csv = lines(slurp(out / "summary.csv"));
  ASSERT_EQ(csv.size(), 4u);
  EXPECT_EQ(csv[0],
            "path,output,status,error,seconds,primitives,operations,chamfer,chamfer_relative,"
            "voxel_iou");
  bool quoted = false;
  for (const std::string& line : csv) {
    quoted = quoted || (line.find("broken.ply") != std::string::npos &&
                        line.find(",error,\"") != std::string::npos &&
                        line.find("truncated") != std::string::npos);
  }
  EXPECT_TRUE(quoted) << slurp(out / "summary.csv");

  // A killed run's torn last line and a finished scan without its row: the
  // tail is cut and the row comes from the scan's report, without running it.
  std::vector<std::string> rows = lines(slurp(out / "summary.jsonl"));
  std::string kept, bracketRow;
  for (const std::string& row : rows) {
    if (row.find("bracket.ply") != std::string::npos) {
      bracketRow = row;
    } else {
      kept += row + "\n";
    }
  }
  write(out / "summary.jsonl", kept + bracketRow.substr(0, 30));
  const auto times = treeTimes(out);
  r = run(cmd + " --resume", dir_);
  EXPECT_EQ(r.code, 1) << r.err;  // the recorded failure still counts
  EXPECT_EQ(treeTimes(out), times);
  rows = lines(slurp(out / "summary.jsonl"));
  ASSERT_EQ(rows.size(), 3u);
  const nlohmann::json restored = nlohmann::json::parse(rows[2]);
  const nlohmann::json original = nlohmann::json::parse(bracketRow);
  EXPECT_EQ(restored["path"], original["path"]);
  EXPECT_EQ(restored["primitives"], original["primitives"]);
  EXPECT_EQ(restored["voxel_iou"], original["voxel_iou"]);
}

TEST_F(Batch, InterruptedRunKeepsFinishedRowsAndResumes) {
  const fs::path in = dir_ / "in";
  fs::create_directories(in);
  int n = 0;
  for (const std::string& part : test::partNames()) {
    if (n++ == 4) break;
    fs::create_symlink(test::dataDir() / part / "scan.ply", in / (part + ".ply"));
  }
  const fs::path out = dir_ / "out";
  const pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    const int devnull = open("/dev/null", O_WRONLY);
    dup2(devnull, STDERR_FILENO);
    execl(CSGVOX_BINARY, CSGVOX_BINARY, "batch", in.c_str(), "-o", out.c_str(), "--jobs", "1",
          "--res", "24", "--mesh-res", "24", static_cast<char*>(nullptr));
    _exit(127);
  }
  // Stop it once the first row is written.
  const auto start = std::chrono::steady_clock::now();
  while (std::chrono::steady_clock::now() - start < std::chrono::seconds(120)) {
    if (fs::exists(out / "summary.jsonl") && fs::file_size(out / "summary.jsonl") > 0) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  kill(pid, SIGTERM);
  int status = 0;
  ASSERT_EQ(waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 130);
  const std::size_t finished = jsonRows(out / "summary.jsonl").size();
  EXPECT_GE(finished, 1u);
  EXPECT_LT(finished, 4u);
  for (const nlohmann::json& row : jsonRows(out / "summary.jsonl")) EXPECT_EQ(row["status"], "ok");

  const RunResult r = run("batch '" + in.string() + "' -o '" + out.string() +
                              "' --jobs 2 --res 24 --mesh-res 24 --resume",
                          dir_);
  EXPECT_EQ(r.code, 0) << r.err;
  // The one scan in flight may have committed its outputs before the signal
  // and not its row: the resume then writes its row from its report and
  // runs one scan fewer.
  const bool allLeft = r.err.find(std::to_string(4 - finished) + " scan") != std::string::npos;
  const bool oneDone = r.err.find(std::to_string(3 - finished) + " scan") != std::string::npos;
  EXPECT_TRUE(allLeft || oneDone) << r.err;
  const std::vector<nlohmann::json> rows = jsonRows(out / "summary.jsonl");
  ASSERT_EQ(rows.size(), 4u);
  std::set<std::string> paths;
  for (const nlohmann::json& row : rows) paths.insert(row["path"].get<std::string>());
  EXPECT_EQ(paths.size(), 4u);
}

}  // namespace
}  // namespace csgvox
