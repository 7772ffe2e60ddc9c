// The csgvox executable under hostile or unlucky input: outputs that would
// replace an input, failures after some outputs exist, killed runs, pipes,
// scattered points, random normals, NaN options, and the scans on which a
// good tree was once lost at the last step.

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <csignal>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>
#include <thread>

#include "cli_helpers.h"
#include "io/scan_reader.h"
#include "part_list.h"

namespace csgvox {
namespace {

const char* const kMainOutputs[] = {"tree.json", "tree.scad",    "tree.txt",
                                    "mesh.ply",  "report.json",  "tree.csg",
                                    "tree.step", "tree.FCMacro", "preview.png"};
constexpr int kMainOutputCount = int(std::size(kMainOutputs));

// The main job's outputs, and `extra`.
std::vector<std::string> mainOutputsAnd(std::vector<std::string> extra) {
  extra.insert(extra.end(), std::begin(kMainOutputs), std::end(kMainOutputs));
  return extra;
}

std::string quoted(const fs::path& p) { return "'" + p.string() + "'"; }

// How many of the main job's outputs `dir` holds.
int mainOutputsIn(const fs::path& dir) {
  int n = 0;
  for (const char* name : kMainOutputs) n += fs::exists(dir / name);
  return n;
}

// Files in `dir` other than the given ones.
std::vector<std::string> otherFiles(const fs::path& dir, const std::vector<std::string>& known) {
  std::vector<std::string> out;
  for (const auto& e : fs::directory_iterator(dir)) {
    const std::string name = e.path().filename().string();
    if (std::find(known.begin(), known.end(), name) == known.end()) out.push_back(name);
  }
  return out;
}

TEST_F(Cli, MainJobNeverWritesOverItsScan) {
  // A scan named like an output, inside the output folder.
  fs::create_directories(dir_ / "o");
  fs::copy_file(test::dataDir() / "plate_holes" / "scan.ply", dir_ / "o" / "mesh.ply");
  const std::string before = slurp(dir_ / "o" / "mesh.ply");
  expectCleanError(quoted(dir_ / "o" / "mesh.ply") + " -q -o " + quoted(dir_ / "o"),
                   (dir_ / "o" / "mesh.ply").string());
  EXPECT_EQ(slurp(dir_ / "o" / "mesh.ply"), before);
  EXPECT_EQ(mainOutputsIn(dir_ / "o"), 1);  // the scan itself, nothing else
  EXPECT_EQ(otherFiles(dir_ / "o", {"mesh.ply"}), std::vector<std::string>{});
}

TEST_F(Cli, DetectNeverWritesOverItsScan) {
  fs::create_directories(dir_ / "o");
  fs::copy_file(test::dataDir() / "plate_holes" / "scan.ply", dir_ / "o" / "segments.ply");
  const std::string before = slurp(dir_ / "o" / "segments.ply");
  expectCleanError("detect " + quoted(dir_ / "o" / "segments.ply") + " -q -o " + quoted(dir_ / "o"),
                   (dir_ / "o" / "segments.ply").string());
  EXPECT_EQ(slurp(dir_ / "o" / "segments.ply"), before);
  EXPECT_EQ(otherFiles(dir_ / "o", {"segments.ply"}), std::vector<std::string>{});
}

TEST_F(Cli, OutputsAppearTogetherIntoANewOrAnExistingFolder) {
  const fs::path scan = test::dataDir() / "plate_holes" / "scan.ply";
  // A new folder, and an existing one holding an unrelated file.
  const RunResult fresh = run(quoted(scan) + " -q -o " + quoted(dir_ / "new" / "out"), dir_);
  ASSERT_EQ(fresh.code, 0) << fresh.err;
  EXPECT_EQ(mainOutputsIn(dir_ / "new" / "out"), kMainOutputCount);
  EXPECT_EQ(otherFiles(dir_ / "new", {"out"}), std::vector<std::string>{});  // no staging left
  fs::create_directories(dir_ / "old");
  write(dir_ / "old" / "notes.txt", "mine");
  const RunResult again = run(quoted(scan) + " -q -o " + quoted(dir_ / "old"), dir_);
  ASSERT_EQ(again.code, 0) << again.err;
  EXPECT_EQ(mainOutputsIn(dir_ / "old"), kMainOutputCount);
  EXPECT_EQ(slurp(dir_ / "old" / "notes.txt"), "mine");
  EXPECT_EQ(otherFiles(dir_ / "old", mainOutputsAnd({"notes.txt"})), std::vector<std::string>{});
}

TEST_F(Cli, AFailureAfterTheTreeLeavesNoOutputs) {
  // A cube scaled by 1e-30 got as far as a tree and then failed, leaving
  // tree.json, tree.scad and tree.txt behind.
  const fs::path scan = dir_ / "tiny.xyz";
  {
    std::ofstream out(scan);
    out.precision(17);
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    // A cube's six faces, 400 points each, with normals, scaled by 1e-30.
    for (int face = 0; face < 6; ++face) {
      for (int i = 0; i < 400; ++i) {
        double p[3] = {u(rng), u(rng), u(rng)}, n[3] = {0, 0, 0};
        const int axis = face / 2;
        p[axis] = face % 2 ? 1.0 : -1.0;
        n[axis] = p[axis];
        out << p[0] * 1e-30 << " " << p[1] * 1e-30 << " " << p[2] * 1e-30 << " " << n[0] << " "
            << n[1] << " " << n[2] << "\n";
      }
    }
  }
  // It fails at meshing (far below the smallest voxel the mesher supports),
  // after the tree exists: nothing may be left behind.
  const RunResult r = run(quoted(scan) + " -q -o " + quoted(dir_ / "out"), dir_);
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find(scan.string()), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("too small"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "out"));
  EXPECT_EQ(otherFiles(dir_, {"tiny.xyz", "out", "stdout.txt", "stderr.txt"}),
            std::vector<std::string>{});
}

TEST_F(Cli, AKilledRunLeavesAllOutputsOrNone) {
  const fs::path scan = test::dataDir() / "housing_complex" / "scan.ply";
  for (const int ms : {300, 1500}) {
    SCOPED_TRACE(ms);
    const fs::path out = dir_ / ("out" + std::to_string(ms));
    const pid_t pid = fork();
    ASSERT_GE(pid, 0);
    if (pid == 0) {
      const int devnull = ::open("/dev/null", O_WRONLY);
      ::dup2(devnull, 2);
      ::execl(CSGVOX_BINARY, CSGVOX_BINARY, scan.c_str(), "-q", "-o", out.c_str(), nullptr);
      ::_exit(127);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(ms));
    ::kill(pid, SIGKILL);
    int status = 0;
    ::waitpid(pid, &status, 0);
    const int n = fs::exists(out) ? mainOutputsIn(out) : 0;
    EXPECT_TRUE(n == 0 || n == kMainOutputCount) << n << " of the outputs";
  }
  // The next run into the same folders removes what the killed ones left.
  for (const int ms : {300, 1500}) {
    const fs::path out = dir_ / ("out" + std::to_string(ms));
    const RunResult r = run(quoted(scan) + " -q -o " + quoted(out), dir_);
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(mainOutputsIn(out), kMainOutputCount);
  }
  EXPECT_EQ(otherFiles(dir_, {"out300", "out1500", "stdout.txt", "stderr.txt"}),
            std::vector<std::string>{});
  EXPECT_EQ(otherFiles(dir_ / "out300", mainOutputsAnd({})), std::vector<std::string>{});
}

TEST_F(Cli, PipesAndDevicesAreRefusedWithoutBlocking) {
  ASSERT_EQ(::mkfifo((dir_ / "f.ply").c_str(), 0600), 0);
  ASSERT_EQ(::mkfifo((dir_ / "f.json").c_str(), 0600), 0);
  // A hang would end in `timeout`'s exit code 124 instead of a stuck suite.
  for (const std::string& args :
       {quoted(dir_ / "f.ply") + " -q -o " + quoted(dir_ / "o"),
        "render " + quoted(dir_ / "f.json") + " -o " + quoted(dir_ / "m.ply"),
        "eval " + quoted(test::dataDir() / "plate_holes" / "tree.json") + " " +
            quoted(dir_ / "f.ply")}) {
    SCOPED_TRACE(args);
    const RunResult r = run(args, dir_, 30);
    EXPECT_EQ(r.code, 1) << r.err;
    EXPECT_NE(r.err.find("not a regular file"), std::string::npos) << r.err;
  }
  const RunResult dev = run("/dev/zero -q -o " + quoted(dir_ / "o"), dir_, 30);
  EXPECT_EQ(dev.code, 1);
  EXPECT_NE(dev.err.find("/dev/zero: is not a regular file"), std::string::npos) << dev.err;
}

TEST_F(Cli, ScatteredPointsAreRefusedEarly) {
  // Sparse and dense: in 30 000 random points a point's nearest neighbours
  // look like a noisy patch of surface (the local estimate reads 1.3 % of D).
  for (int n : {3000, 30000}) {
    SCOPED_TRACE(n);
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::ostringstream s;
    for (int i = 0; i < n; ++i) s << u(rng) << " " << u(rng) << " " << u(rng) << "\n";
    write(dir_ / "scattered.xyz", s.str());
    expectCleanError(quoted(dir_ / "scattered.xyz") + " -q -o " + quoted(dir_ / "out"),
                     (dir_ / "scattered.xyz").string());
    const RunResult r =
        run(quoted(dir_ / "scattered.xyz") + " -q -o " + quoted(dir_ / "out"), dir_);
    EXPECT_NE(r.err.find("the points do not lie on surfaces"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir_ / "out"));
  }
}

TEST_F(Cli, RandomNormalsAreReEstimated) {
  // The flange's points with normals in random directions: detection
  // searched them for half a minute (more under load) before finding that
  // they lie on no surface. The reader tells them from the surface's and
  // estimates them; the read line says so.
  const Scan truth = readScan(test::dataDir() / "flange" / "scan.ply");
  std::mt19937_64 rng(7);
  std::normal_distribution<double> gauss;
  std::ostringstream s;
  s.precision(9);
  for (const Vec3& p : truth.cloud.points) {
    const Vec3 n = Vec3(gauss(rng), gauss(rng), gauss(rng)).normalized();
    s << p.x() << " " << p.y() << " " << p.z() << " " << n.x() << " " << n.y() << " " << n.z()
      << "\n";
  }
  write(dir_ / "random_normals.xyzn", s.str());
  const RunResult r =
      run("detect " + quoted(dir_ / "random_normals.xyzn") + " -o " + quoted(dir_ / "out"), dir_,
          60 * CSGVOX_TEST_SLOWDOWN);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE((r.out + r.err).find("normals re-estimated"), std::string::npos) << r.out << r.err;
}

TEST_F(Cli, RepeatedPointsWithoutNormalsAreNoCrash) {
  // 18 or more copies of one point reached the jet fit's SVD (SIGSEGV).
  std::string same;
  for (int i = 0; i < 200; ++i) same += "1 2 3\n";
  write(dir_ / "same.xyz", same);
  expectCleanError(quoted(dir_ / "same.xyz") + " -q -o " + quoted(dir_ / "out"),
                   (dir_ / "same.xyz").string());
  // A real scan, without normals, whose first point is repeated 18 times.
  const RunResult conv = run("sample " + quoted(test::dataDir() / "plate_holes" / "tree.json") +
                                 " -q --points 4000 -o " + quoted(dir_ / "s.xyz"),
                             dir_);
  ASSERT_EQ(conv.code, 0) << conv.err;
  std::istringstream lines(slurp(dir_ / "s.xyz"));
  std::string line, points, first;
  while (std::getline(lines, line)) {
    std::istringstream words(line);
    double x, y, z;
    words >> x >> y >> z;
    std::ostringstream p;
    p.precision(17);
    p << x << " " << y << " " << z << "\n";
    if (first.empty()) first = p.str();
    points += p.str();
  }
  for (int i = 0; i < 18; ++i) points += first;
  write(dir_ / "repeated.xyz", points);
  const RunResult r = run(quoted(dir_ / "repeated.xyz") + " -q -o " + quoted(dir_ / "out2"), dir_);
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(mainOutputsIn(dir_ / "out2"), kMainOutputCount);
}

TEST_F(Cli, NumericOptionsMustBeFiniteAndInRange) {
  const std::string scan = quoted(test::dataDir() / "plate_holes" / "scan.ply");
  const std::string tree = quoted(test::dataDir() / "plate_holes" / "tree.json");
  const std::string out = quoted(dir_ / "out");
  const std::vector<std::pair<std::string, std::string>> cases = {
      {scan + " -o " + out + " --alpha nan", "--alpha"},
      {scan + " -o " + out + " --beta inf", "--beta"},
      {scan + " -o " + out + " --vote-epsilon nan", "--vote-epsilon"},
      {scan + " -o " + out + " --time-limit nan", "--time-limit"},
      {scan + " -o " + out + " --time-limit -1", "--time-limit"},
      {scan + " -o " + out + " --seed -5", "--seed"},
      {"sample " + tree + " -o " + quoted(dir_ / "s.ply") + " --noise nan", "--noise"},
      {"sample " + tree + " -o " + quoted(dir_ / "s.ply") + " --drop-radius nan", "--drop-radius"},
      {"detect " + scan + " -o " + out + " --epsilon nan", "--epsilon"},
      {"detect " + scan + " -o " + out + " --min-points nan", "--min-points"},
      {"detect " + scan + " -o " + out + " --seed -1", "--seed"},
  };
  for (const auto& [args, option] : cases) {
    SCOPED_TRACE(args);
    const RunResult r = run(args, dir_);
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_NE(r.err.find(option), std::string::npos) << r.err;
  }
  EXPECT_FALSE(fs::exists(dir_ / "out"));
  EXPECT_FALSE(fs::exists(dir_ / "s.ply"));
}

TEST_F(Cli, QuietMeansNoSolverLog) {
  // A noisy scan whose fits make the solver warn; -q prints nothing at all.
  const RunResult r = run(
      quoted(test::dataDir() / "funnel" / "scan_noisy.ply") + " -q -o " + quoted(dir_ / "o"), dir_);
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.err, "");
}

// Scans on which a good tree was built and then lost: the fit metrics found
// no boundary to sample because a nearly flat face was fitted as a cylinder
// thousands of times wider than the part (InverseCSG parts, 60 000 points).
class RegressionScan : public Cli, public ::testing::WithParamInterface<std::string> {};

TEST_P(RegressionScan, MainJobEndsWithTheTreeAndItsMetrics) {
  const fs::path scan = test::dataDir() / "regressions" / GetParam();
  const RunResult r = run(quoted(scan) + " -q -o " + quoted(dir_ / "out"), dir_);
  ASSERT_EQ(r.code, 0) << r.err;
  const auto report = nlohmann::json::parse(slurp(dir_ / "out" / "report.json"));
  // tree.step is left out, with a warning, when OpenCASCADE cannot build the
  // tree's solid (it is written from the fitted values, with a warning, when
  // only the designed values' solid fails); every other output is always there.
  const bool step = fs::exists(dir_ / "out" / "tree.step");
  ASSERT_EQ(mainOutputsIn(dir_ / "out"), kMainOutputCount - (step ? 0 : 1));
  int notWritten = 0;
  for (const auto& w : report.at("warnings")) {
    const std::string text = w.get<std::string>();
    EXPECT_EQ(text.rfind("tree.step: ", 0), 0u) << text;
    notWritten += text.rfind("tree.step: not written", 0) == 0;
  }
  EXPECT_EQ(notWritten, step ? 0 : 1) << report.at("warnings");
  const auto& m = report.at("metrics");
  ASSERT_TRUE(m.contains("chamfer_relative")) << m;
  EXPECT_LT(m.at("chamfer_relative").get<double>(), 0.02);
  EXPECT_GT(m.at("within_1pct").get<double>(), 0.5);
}

INSTANTIATE_TEST_SUITE_P(InverseCsg, RegressionScan,
                         ::testing::Values("inversecsg-060-60k.ply", "inversecsg-123-60k.ply",
                                           "inversecsg-139-60k.ply", "inversecsg-143-60k.ply",
                                           "inversecsg-148-60k.ply", "inversecsg-155-60k.ply"),
                         [](const auto& info) {
                           std::string s = info.param.substr(11, 3);
                           return "part_" + s;
                         });

}  // namespace
}  // namespace csgvox
