// The whole reconstruction on the InverseCSG benchmark: 50 CAD meshes
// (NNN.off) and the size of InverseCSG's solution for each
// (inversecsg-results.csv). Every mesh is sampled into an oriented scan,
// optionally noised, and reconstructed; the row reports the status, the wall
// time of reconstruct() (and of the reading step before it, for raw scans),
// the tree's size next to InverseCSG's, and the
// volumetric IoU between the tree and the mesh's solid.
//
// Run: build/bench/bench_inversecsg DIR [--points N] [--noise F] [--res R]
//        [--models 011,039,...] [--samples S] [--time-limit T] [--no-finer-grid]
//        [--no-unsupported-regions] [--finish] [--repair-searches K]
//        [--repair-stall S] [--repair-operations minmax|sardf|rfunction]
//        [--seed S] [--keep OUTDIR] [--estimate-normals]
//        [--scanner [--setups 1|2] [--depth-noise F] [--outliers F]
//         [--mixed-pixels P] [--scanner-normals none|scanner]
//         [--registration-shift F] [--registration-turn R]
//         [--density-variation F] [--scanner-only]]
//   --points      points sampled from each mesh, by area (default 50000)
//   --noise       Gaussian position noise, sigma = F x D (D: the scan's
//                 diagonal; default 0); normals are kept
//   --estimate-normals  the uniform scan's normals are dropped and
//                 estimated as for a file of raw x y z (outliers removed,
//                 normals oriented, detection told they are estimated)
//   --scanner     each model is also scanned with the turntable scanner
//                 model (scanner/scanner.h, docs/scanner.md: MeshCaster on the
//                 mesh, --points points, the scanner seed --seed) and reconstructed from that
//                 scan; its row (scan `scanner`) follows the uniform one
//                 (scan `uniform`), and the summary is given for each.
//                 Missing normals are estimated as for a file without them.
//                 --noise applies to the uniform scan only
//   --scanner-only  the scanner rows only (no uniform scan)
//   --setups, --depth-noise, --outliers, --mixed-pixels, --scanner-normals,
//   --registration-shift (fraction of D), --registration-turn (radians),
//   --density-variation (dense end over sparse end, >= 1)
//                 the scanner model's options (as `csgvox sample --scanner`;
//                 defaults: ScannerOptions)
//   --res         ReconstructOptions::resolution (default 64)
//   --method      hybrid (default), voxel or gp
//   --models      comma-separated model names (default: all of the CSV)
//   --samples     random points of the IoU estimate (default 200000)
//   --time-limit  the reconstruction's RunControl deadline in seconds (default 0: none);
//                 a model whose process runs past 3 T + 60 s is killed
//   --no-unsupported-regions  the hybrid searches only where points are
//                 badly explained (HybridOptions::unsupportedRegions off)
//   --repair-searches K, --repair-stall S  the hybrid's repair searches of
//                 each region and their stall rule (as `csgvox --repair-searches`,
//                 `--repair-stall`; the old --refine-* names are accepted too)
//   --repair-operations  the set operations of the repair searches' fitness
//                 (as `csgvox --repair-operations`; default: the hybrid's)
//   --seed        ReconstructOptions::seed (default 1; as `csgvox --seed`): the
//                 scans stay the same, only the reconstruction's random
//                 choices change, to tell a change's effect from luck
//   --finish      the hybrid ends with the finish (FinishOptions::enabled, as
//                 `csgvox --finish`)
//   --keep        folder where each model's scan (after the noise: NNN/scan.ply
//                 in floats for viewers, NNN/scan.xyz with every digit) and
//                 tree (NNN/tree.json) are written, to look at a weak part
//                 with `csgvox eval` or run it again with `csgvox` (from
//                 scan.xyz when the normals were given, which gives the
//                 run's tree but for the last bits of the normals, which
//                 reading scales to unit length),
//                 and the IoU's samples where they disagree: NNN/extra.ply in
//                 the tree only, NNN/missing.ply in the part only. A scan
//                 read as a file of raw points (scanner rows, --estimate-normals)
//                 also leaves NNN/raw.xyz, its points (and the scanner's
//                 normals, if it gave them) before the reading step:
//                 `csgvox NNN/raw.xyz` runs it as the benchmark did (its
//                 scan.xyz holds the normals the reading gave it, which the
//                 main job would take as given, skipping what it does for
//                 raw scans)
//
// Each row's note ends with the volume only in the tree and only in the
// part, then the voxel labels' own IoU against the part (labels IoU, and
// their extra and missing volume): where the labels are already wrong, the
// tree follows them; where they are right, the error is the tree's.
//
// Each model runs in a child process of its own, so a crash or a runaway
// model becomes a row with its reason and the run goes on. The children's
// stderr (solver warnings) is discarded.

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "core/named_values.h"
#include "core/set_operations.h"
#include "core/statistics.h"
#include "io/mesh_files.h"
#include "io/point_arrays.h"
#include "io/point_writer.h"
#include "io/scan_reader.h"
#include "io/tree_json.h"
#include "mesh/mesh_solid.h"
#include "pipeline/reconstruct.h"
#include "scanner/mesh_caster.h"
#include "scanner/scanner.h"

namespace {

using namespace csgvox;

struct Options {
  std::filesystem::path dir;
  std::size_t points = 50000;
  double noise = 0.0;
  bool estimateNormals = false;
  int resolution = 64;
  bool finerGrid = true;
  bool unsupportedRegions = true;
  std::size_t repairSearches = 0;                    // 0: the default
  std::size_t repairStall = 0;                       // 0: the default
  std::optional<SetOperationKind> repairOperations;  // none: the default
  bool finish = false;
  std::uint64_t seed = 1;
  int iouSamples = 200000;
  double timeLimit = 0.0;
  Method method = Method::Hybrid;
  std::vector<std::string> models;
  std::filesystem::path keep;  // empty: write nothing
  bool scanner = false;        // also run each model on a scanner-model scan
  bool uniform = true;         // run each model on a uniform scan
  ScannerOptions scan;         // the scanner model's options (points and seed set per run)
};

// How a model's scan is made.
enum class ScanKind { Uniform, Scanner };

const char* scanKindName(ScanKind kind) {
  return kind == ScanKind::Uniform ? "uniform" : "scanner";
}

// One line of inversecsg-results.csv.
struct Reference {
  std::size_t vertices = 0;
  std::size_t faces = 0;
  std::size_t primitives = 0;
  std::size_t operations = 0;
};

// What a child process reports about one model.
struct Result {
  std::string status = "crashed";  // Ok, NoSurfaces, ..., or error / crashed / killed
  double seconds = -1.0;           // wall time of reconstruct(), -1: not run
  double readSeconds = 0.0;        // wall time of the reading step (raw scans only)
  long primitives = -1;
  long operations = -1;
  double iou = -1.0;  // -1: not measured
  std::string note;   // the message, or why the IoU is missing

  // Read + reconstruct, -1: not run.
  double totalSeconds() const { return seconds >= 0.0 ? readSeconds + seconds : -1.0; }
};

double loadAverage() {
  std::ifstream in("/proc/loadavg");
  double load = -1.0;
  in >> load;
  return load;
}

const char* statusName(Reconstruction::Status s) {
  switch (s) {
    case Reconstruction::Status::Ok:
      return "Ok";
    case Reconstruction::Status::NoSurfaces:
      return "NoSurfaces";
    case Reconstruction::Status::NoCombination:
      return "NoCombination";
    case Reconstruction::Status::TimedOut:
      return "TimedOut";
    case Reconstruction::Status::TooLarge:
      return "TooLarge";
    case Reconstruction::Status::Cancelled:
      return "Cancelled";
  }
  return "?";
}

std::map<std::string, Reference> readReferences(const std::filesystem::path& csv) {
  std::ifstream in(csv);
  if (!in) throw std::runtime_error(csv.string() + ": cannot open");
  std::map<std::string, Reference> refs;
  std::string line;
  std::getline(in, line);  // header
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    std::replace(line.begin(), line.end(), ',', ' ');
    std::istringstream fields(line);
    std::string model;
    Reference r;
    if (fields >> model >> r.vertices >> r.faces >> r.primitives >> r.operations) refs[model] = r;
  }
  return refs;
}

// Volumetric IoU of two solids on uniform random points of `box`, and where
// they differ: the volume only in A and only in B, as fractions of B's.
// With `only`, the samples in A only and in B only are kept there.
struct Overlap {
  double iou = 1.0;
  double onlyA = 0.0;
  double onlyB = 0.0;
};

template <class InA, class InB>
Overlap sampledOverlap(const Aabb& box, InA&& inA, InB&& inB, int samples, std::uint64_t seed,
                       std::pair<PointCloud, PointCloud>* only = nullptr) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::size_t both = 0, onlyA = 0, onlyB = 0;
  for (int i = 0; i < samples; ++i) {
    Vec3 p;
    for (int k = 0; k < 3; ++k) p[k] = box.min[k] + unit(rng) * (box.max[k] - box.min[k]);
    const bool a = inA(p), b = inB(p);
    both += a && b;
    onlyA += a && !b;
    onlyB += b && !a;
    if (only && a != b) (a ? only->first : only->second).points.push_back(p);
  }
  Overlap o;
  const std::size_t either = both + onlyA + onlyB, inB_ = both + onlyB;
  if (either > 0) o.iou = double(both) / double(either);
  if (inB_ > 0) {
    o.onlyA = double(onlyA) / double(inB_);
    o.onlyB = double(onlyB) / double(inB_);
  }
  return o;
}

// The scanner model's scan of the mesh at `path`, as a file of it would hold
// it (normals only with --scanner-normals scanner), before the reading step.
PointCloud scannerScan(const Options& opt, const std::filesystem::path& path, std::string& note) {
  const TriangleMesh mesh = readMesh(path);
  const MeshCaster caster(mesh);
  ScannerOptions so = opt.scan;
  so.points = opt.points;
  so.seed = opt.seed;
  const auto t0 = std::chrono::steady_clock::now();
  ScannerScan s = scanPart(caster, so);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  char buf[160];
  std::snprintf(buf, sizeof buf, "scan %.2f s at %d px, %zu mixed, %zu outliers; ", seconds,
                s.resolution, s.counts.mixed, s.counts.outliers);
  note = buf;
  return std::move(s.cloud);
}

// Runs one model; never throws.
Result runModel(const Options& opt, const std::string& model, ScanKind kind) {
  Result res;
  const std::filesystem::path path = opt.dir / (model + ".off");
  try {
    std::string scanNote;
    PointCloud scan;
    // A scan to read as a file of it is read (outliers removed, missing
    // normals estimated): the scanner's, or the uniform one without normals.
    PointCloud raw;
    bool estimatedNormals = false;
    if (kind == ScanKind::Scanner) {
      raw = scannerScan(opt, path, scanNote);
    } else {
      ReadOptions rd;
      rd.meshSamples = opt.points;
      rd.seed = 1;
      scan = readScan(path, rd).cloud;
    }
    if (kind == ScanKind::Uniform && opt.noise > 0.0) {
      const double sigma = opt.noise * scan.diagonal();
      std::mt19937_64 rng(7);
      std::normal_distribution<double> gauss(0.0, sigma);
      for (Vec3& p : scan.points) p += Vec3(gauss(rng), gauss(rng), gauss(rng));
    }
    if (kind == ScanKind::Uniform && opt.estimateNormals) raw.points = std::move(scan.points);
    if (!raw.empty()) {
      const auto r0 = std::chrono::steady_clock::now();
      Scan read = scanFromArrays(raw.points, raw.normals, path.string());
      res.readSeconds =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - r0).count();
      estimatedNormals = read.info.normalsEstimated;
      scan = std::move(read.cloud);
    }
    const std::filesystem::path keep =
        opt.keep.empty() ? opt.keep
                         : opt.keep / (kind == ScanKind::Scanner ? model + "-scanner" : model);
    if (!keep.empty()) {
      std::filesystem::create_directories(keep);
      writePointCloudPly(keep / "scan.ply", scan);  // floats, for viewers
      writePointCloudXyz(keep / "scan.xyz", scan);  // every digit, to run it again
      // A scan read as raw points is run again from them: the scan above
      // holds the normals the reading gave it, which the main job would take
      // as given.
      if (!raw.empty()) writePointCloudXyz(keep / "raw.xyz", raw);
    }

    ReconstructOptions ro;
    ro.resolution = opt.resolution;
    ro.finerGrid = opt.finerGrid;
    ro.hybrid.unsupportedRegions = opt.unsupportedRegions;
    if (opt.repairSearches > 0) ro.hybrid.searches = opt.repairSearches;
    if (opt.repairStall > 0) ro.hybrid.evolve.stallGenerations = opt.repairStall;
    if (opt.repairOperations) ro.hybrid.fitness.operations = *opt.repairOperations;
    ro.finish.enabled = opt.finish;
    ro.seed = opt.seed;
    ro.method = opt.method;
    ro.detect.estimatedNormals = estimatedNormals;
    const auto t0 = std::chrono::steady_clock::now();
    const Reconstruction rec = reconstruct(scan, ro, {}, RunControl(opt.timeLimit));
    res.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    res.status = statusName(rec.status);
    res.note = scanNote + rec.message;
    if (rec.resolution != opt.resolution) res.note += ", res " + std::to_string(rec.resolution);
    if (rec.boresFromWalls > 0) {
      res.note += ", " + std::to_string(rec.boresFromWalls) + " bores from their walls";
    }
    if (rec.facesFromPoints > 0) {
      res.note += ", " + std::to_string(rec.facesFromPoints) + " faces from their points";
    }
    if (rec.holesFromRims > 0) {
      res.note += ", " + std::to_string(rec.holesFromRims) + " holes from their rims";
    }
    if (rec.sheetEdges > 0) {
      res.note += ", " + std::to_string(rec.sheetEdges) + " rounds made sheet edges";
    }
    if (rec.rimWindows > 0) {
      res.note += ", " + std::to_string(rec.rimWindows) + " windows from their rims";
    }
    if (rec.boreOpening.voxels > 0) {
      res.note += ", " + std::to_string(rec.boreOpening.voxels) + " voxels opened in bores";
    }
    if (const auto* hy = std::get_if<HybridMethodResult>(&rec.result);
        hy != nullptr && hy->repair.holesAdded > 0) {
      res.note += ", " + std::to_string(hy->repair.holesAdded) + " seen holes subtracted";
    }
    if (rec.timeLimitHit) res.note += " (time limit hit)";
    if (!rec.ok()) return res;
    if (!keep.empty()) writeTreeJson(keep / "tree.json", rec.tree);
    res.primitives = long(rec.tree.primitiveCount());
    res.operations = long(rec.tree.operationCount());

    const TriangleMesh mesh = readMesh(path);
    const Aabb meshBox = mesh.bounds();
    std::optional<MeshSolid> solid;
    try {
      solid.emplace(mesh, meshBox.diagonal() / 400.0);
    } catch (const std::invalid_argument& e) {
      res.note = "open mesh, no IoU (" + std::string(e.what()) + "); " + res.note;
      return res;
    }
    Aabb box = meshBox;
    const Aabb treeBox = rec.tree.bounds();
    if (treeBox.isBounded()) {
      box.extend(treeBox);
    } else {
      // Unbounded tree: its volume is infinite anyway; measure near the part.
      box = box.grown(0.1 * meshBox.diagonal());
      res.note = "unbounded tree; " + res.note;
    }
    std::pair<PointCloud, PointCloud> only;  // extra, missing
    const Overlap o = sampledOverlap(
        box, [&](const Vec3& p) { return rec.tree.contains(p); },
        [&](const Vec3& p) { return solid->contains(p); }, opt.iouSamples, 1,
        keep.empty() ? nullptr : &only);
    res.iou = o.iou;
    // The voxel labels against the part, on the same number of samples over
    // the part and the grid: how much of the tree's error the labels hold
    // already (a voxel's width of it on every face is the grid's own).
    const VoxelGrid& grid = rec.grid;
    Aabb labelBox = meshBox;
    for (int corner = 0; corner < 8; ++corner) {
      const Vec3 c((corner & 1) ? grid.dims()[0] : 0, (corner & 2) ? grid.dims()[1] : 0,
                   (corner & 4) ? grid.dims()[2] : 0);
      labelBox.extend(Vec3(grid.origin() + grid.axes() * (c * grid.voxelSize())));
    }
    const auto labelled = [&](const Vec3& p) {
      const std::size_t v = grid.voxelOf(p);
      return v != VoxelGrid::npos && rec.labels.inside.test(v);
    };
    const Overlap l = sampledOverlap(
        labelBox, labelled, [&](const Vec3& p) { return solid->contains(p); }, opt.iouSamples, 1);
    char where[192];
    std::snprintf(where, sizeof where,
                  "; extra %.1f %%, missing %.1f %% of the part's volume; labels IoU %.4f "
                  "(extra %.1f %%, missing %.1f %%)",
                  100.0 * o.onlyA, 100.0 * o.onlyB, l.iou, 100.0 * l.onlyA, 100.0 * l.onlyB);
    res.note += where;
    if (!keep.empty()) {
      writePointCloudPly(keep / "extra.ply", only.first);
      writePointCloudPly(keep / "missing.ply", only.second);
    }
  } catch (const std::exception& e) {
    if (res.seconds < 0.0) res.status = "error";
    res.note = std::string("exception: ") + e.what();
  }
  return res;
}

// One result as a single line for the pipe (the note is last, may hold tabs).
std::string encode(const Result& r) {
  char buf[256];
  std::snprintf(buf, sizeof buf, "%s\t%.6f\t%.6f\t%ld\t%ld\t%.6f\t", r.status.c_str(),
                r.seconds, r.readSeconds, r.primitives, r.operations, r.iou);
  std::string note = r.note;
  std::replace(note.begin(), note.end(), '\n', ' ');
  return buf + note;
}

bool decode(const std::string& line, Result& r) {
  std::istringstream in(line);
  std::string seconds, readSeconds, prims, ops, iou;
  if (!std::getline(in, r.status, '\t') || !std::getline(in, seconds, '\t') ||
      !std::getline(in, readSeconds, '\t') ||
      !std::getline(in, prims, '\t') || !std::getline(in, ops, '\t') ||
      !std::getline(in, iou, '\t')) {
    return false;
  }
  std::getline(in, r.note);
  r.seconds = std::atof(seconds.c_str());
  r.readSeconds = std::atof(readSeconds.c_str());
  r.primitives = std::atol(prims.c_str());
  r.operations = std::atol(ops.c_str());
  r.iou = std::atof(iou.c_str());
  return true;
}

// Runs one model in a child process; the parent never builds anything large
// nor starts TBB's threads, so forking is safe.
Result runIsolated(const Options& opt, const std::string& model, ScanKind kind) {
  int fds[2];
  Result r;
  if (pipe(fds) != 0) {
    r.status = "error";
    r.note = "pipe failed";
    return r;
  }
  std::fflush(stdout);
  const pid_t child = fork();
  if (child < 0) {
    close(fds[0]);
    close(fds[1]);
    r.status = "error";
    r.note = "fork failed";
    return r;
  }
  if (child == 0) {
    close(fds[0]);
    // The solver's own warnings (e.g. a failed Cholesky step during
    // repair search) would bury the table; the row carries what matters.
    const int devNull = open("/dev/null", O_WRONLY);
    if (devNull >= 0) {
      dup2(devNull, STDERR_FILENO);
      close(devNull);
    }
    const std::string line = encode(runModel(opt, model, kind)) + "\n";
    std::size_t done = 0;
    while (done < line.size()) {
      const ssize_t n = write(fds[1], line.data() + done, line.size() - done);
      if (n <= 0) break;
      done += std::size_t(n);
    }
    close(fds[1]);
    _exit(0);
  }
  close(fds[1]);
  const double killAfter = opt.timeLimit > 0.0 ? 3.0 * opt.timeLimit + 60.0 : 0.0;
  const auto start = std::chrono::steady_clock::now();
  std::string text;
  bool killed = false;
  for (;;) {
    int waitMs = -1;
    if (killAfter > 0.0) {
      const double left =
          killAfter -
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      if (left <= 0.0) {
        kill(child, SIGKILL);
        killed = true;
        break;
      }
      waitMs = int(std::ceil(left * 1000.0));
    }
    pollfd pfd{fds[0], POLLIN, 0};
    const int ready = poll(&pfd, 1, waitMs);
    if (ready < 0 && errno == EINTR) continue;
    if (ready <= 0) continue;  // timeout: checked at the top
    char buf[4096];
    const ssize_t n = read(fds[0], buf, sizeof buf);
    if (n <= 0) break;
    text.append(buf, std::size_t(n));
  }
  close(fds[0]);
  int status = 0;
  waitpid(child, &status, 0);
  if (killed) {
    r.status = "killed";
    r.note = "still running after " + std::to_string(int(killAfter)) + " s";
    return r;
  }
  if (!text.empty() && text.back() == '\n') text.pop_back();
  if (decode(text, r)) return r;
  r = Result{};
  r.status = "crashed";
  r.note = WIFSIGNALED(status) ? "killed by signal " + std::to_string(WTERMSIG(status))
                               : "exit code " + std::to_string(WEXITSTATUS(status));
  return r;
}

std::vector<std::string> splitList(const std::string& s) {
  std::vector<std::string> out;
  std::istringstream in(s);
  std::string item;
  while (std::getline(in, item, ',')) {
    if (!item.empty()) out.push_back(item);
  }
  return out;
}

int usage(const char* argv0) {
  std::fprintf(stderr,
               "usage: %s DIR [--points N] [--noise F] [--estimate-normals] [--res R] [--models "
               "011,039,...] "
               "[--samples S] [--time-limit T] [--method hybrid|voxel|gp] [--no-finer-grid] "
               "[--no-unsupported-regions] [--finish] [--repair-searches K] "
               "[--repair-stall S] [--repair-operations minmax|sardf|rfunction] [--seed S] "
               "[--keep OUTDIR] [--scanner [--setups 1|2] "
               "[--depth-noise F] [--outliers F] [--mixed-pixels P] "
               "[--scanner-normals none|scanner] [--registration-shift F] [--registration-turn R] "
               "[--density-variation F] [--scanner-only]]\n",
               argv0);
  return 2;
}

// Reads the command line into `opt`; false when it is not valid.
bool parseArguments(int argc, char** argv, Options& opt) {
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    const bool hasValue = i + 1 < argc;
    if (arg == "--points" && hasValue) {
      opt.points = std::size_t(std::atoll(argv[++i]));
    } else if (arg == "--noise" && hasValue) {
      opt.noise = std::atof(argv[++i]);
    } else if (arg == "--estimate-normals") {
      opt.estimateNormals = true;
    } else if (arg == "--res" && hasValue) {
      opt.resolution = std::atoi(argv[++i]);
    } else if (arg == "--no-finer-grid" || arg == "--no-refine-thin") {
      opt.finerGrid = false;
    } else if (arg == "--no-unsupported-regions") {
      opt.unsupportedRegions = false;
    } else if (arg == "--finish") {
      opt.finish = true;
    } else if ((arg == "--repair-searches" || arg == "--refine-searches") && hasValue) {
      opt.repairSearches = std::size_t(std::max(1, std::atoi(argv[++i])));
    } else if ((arg == "--repair-stall" || arg == "--refine-stall") && hasValue) {
      opt.repairStall = std::size_t(std::max(1, std::atoi(argv[++i])));
    } else if (arg == "--repair-operations" && hasValue) {
      try {
        opt.repairOperations =
            valueNamed<SetOperationKind>(kSetOperationNames, argv[++i], "--repair-operations");
      } catch (const std::invalid_argument& e) {
        std::fprintf(stderr, "%s\n", e.what());
        return false;
      }
    } else if (arg == "--seed" && hasValue) {
      opt.seed = std::strtoull(argv[++i], nullptr, 10);
    } else if (arg == "--models" && hasValue) {
      opt.models = splitList(argv[++i]);
    } else if (arg == "--scanner") {
      opt.scanner = true;
    } else if (arg == "--setups" && hasValue) {
      opt.scan.setups = std::atoi(argv[++i]);
    } else if (arg == "--scanner-only") {
      opt.scanner = true;
      opt.uniform = false;
    } else if (arg == "--density-variation" && hasValue) {
      opt.scan.densityVariation = std::atof(argv[++i]);
    } else if (arg == "--registration-shift" && hasValue) {
      opt.scan.registrationTranslation = std::atof(argv[++i]);
    } else if (arg == "--registration-turn" && hasValue) {
      opt.scan.registrationRotation = std::atof(argv[++i]);
    } else if (arg == "--depth-noise" && hasValue) {
      opt.scan.depthNoise = std::atof(argv[++i]);
    } else if (arg == "--outliers" && hasValue) {
      opt.scan.outliers = std::atof(argv[++i]);
    } else if (arg == "--mixed-pixels" && hasValue) {
      opt.scan.mixedPixels = std::atof(argv[++i]);
    } else if (arg == "--scanner-normals" && hasValue) {
      const std::string name = argv[++i];
      if (name != "none" && name != "scanner") return false;
      opt.scan.normals = name == "none" ? ScannerNormals::None : ScannerNormals::Scanner;
    } else if (arg == "--keep" && hasValue) {
      opt.keep = argv[++i];
    } else if (arg == "--samples" && hasValue) {
      opt.iouSamples = std::atoi(argv[++i]);
    } else if (arg == "--time-limit" && hasValue) {
      opt.timeLimit = std::atof(argv[++i]);
    } else if (arg == "--method" && hasValue) {
      try {
        opt.method = methodFromName(argv[++i]);
      } catch (const std::invalid_argument&) {
        return false;
      }
    } else if (!arg.empty() && arg[0] != '-' && opt.dir.empty()) {
      opt.dir = arg;
    } else {
      return false;
    }
  }
  try {
    opt.scan.validate();
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "scanner: %s\n", e.what());
    return false;
  }
  return !(opt.dir.empty() || opt.points == 0 || opt.resolution <= 0 || opt.iouSamples <= 0 ||
           opt.noise < 0.0 || opt.timeLimit < 0.0);
}

// The run's settings and the table's heading.
void printHeading(const Options& opt) {
  char limitText[32] = "none";
  if (opt.timeLimit > 0.0) std::snprintf(limitText, sizeof limitText, "%g s", opt.timeLimit);
  std::printf(
      "InverseCSG benchmark %s: %zu models, %zu points per mesh, noise %.4f D, res %d, "
      "method %s, time limit %s%s%s\n",
      opt.dir.string().c_str(), opt.models.size(), opt.points, opt.noise, opt.resolution,
      std::string(methodName(opt.method)).c_str(), limitText,
      opt.finerGrid ? ", finer grid where thin" : "", opt.finish ? ", finish" : "");
  if (opt.estimateNormals) std::printf("uniform scans: normals estimated from x y z\n");
  if (opt.seed != 1) std::printf("reconstruction seed: %llu\n", (unsigned long long)opt.seed);
  if (opt.scanner) {
    std::printf(
        "scanner rows: %d setup(s), %d views x %zu elevations, depth noise %.4f D, outliers "
        "%.4f, mixed pixels %.2f, registration %.4f D and %.4f rad, density variation %g, "
        "normals %s\n",
        opt.scan.setups, opt.scan.views, opt.scan.elevations.size(), opt.scan.depthNoise,
        opt.scan.outliers, opt.scan.mixedPixels, opt.scan.registrationTranslation,
        opt.scan.registrationRotation, opt.scan.densityVariation,
        opt.scan.normals == ScannerNormals::None ? "estimated" : "scanner's");
  }
  if (opt.repairSearches > 0 || opt.repairStall > 0)
    std::printf("hybrid searches per region: %zu, stall: %zu generations (0: the default)\n",
                opt.repairSearches, opt.repairStall);
  if (opt.repairOperations)
    std::printf(
        "hybrid repair operations: %s\n",
        std::string(nameOf<SetOperationKind>(kSetOperationNames, *opt.repairOperations)).c_str());
  std::printf(
      "time_s: wall time of reconstruct(); read_s: of the reading step before it (outliers "
      "removed, normals estimated and oriented: raw scans only); prims/ops: our tree | "
      "InverseCSG's; IoU: "
      "tree vs mesh solid, %d random points of the joint box (-: not measured)\n",
      opt.iouSamples);
  std::printf("load average at start: %.2f\n", loadAverage());
  std::printf("%-6s %-7s %6s %-13s %8s %6s %5s %5s %5s %5s %7s  %s\n", "model", "scan",
              "faces", "status", "time_s", "read_s", "prims", "ics_p", "ops", "ics_o", "IoU",
              "note");
}

// A model's row of the table: our result next to InverseCSG's `r`.
void printRow(const std::string& model, ScanKind kind, const Reference& r, const Result& res) {
  std::printf("%-6s %-7s %6zu %-13s %8.2f %6.2f %5ld %5zu %5ld %5zu ", model.c_str(),
              scanKindName(kind), r.faces, res.status.c_str(), res.seconds, res.readSeconds,
              res.primitives, r.primitives, res.operations, r.operations);
  if (res.iou >= 0.0) {
    std::printf("%7.4f", res.iou);
  } else {
    std::printf("%7s", "-");
  }
  std::printf("  %s\n", res.note.c_str());
  std::fflush(stdout);
}

// The summary's counts over the models run.
struct Tally {
  std::size_t ok = 0, withIou = 0, iou95 = 0, iou99 = 0, notLarger = 0;
  long ourPrims = 0, theirPrims = 0;
  std::vector<double> times, totals, ious;  // totals: read + reconstruct

  // Counts a model's result `res` against InverseCSG's `r` (`known`: the
  // CSV has the model).
  void add(const Result& res, const Reference& r, bool known) {
    if (res.seconds >= 0.0) {
      times.push_back(res.seconds);
      totals.push_back(res.totalSeconds());
    }
    if (res.status != "Ok") return;
    ++ok;
    ourPrims += res.primitives;
    theirPrims += long(r.primitives);
    if (known && res.primitives <= long(r.primitives)) ++notLarger;
    if (res.iou >= 0.0) {
      ++withIou;
      ious.push_back(res.iou);
      iou95 += res.iou >= 0.95;
      iou99 += res.iou >= 0.99;
    }
  }
};

// The summary of the run.
void printSummary(const Options& opt, ScanKind kind, const Tally& t) {
  const std::size_t n = opt.models.size();
  std::printf("\nsummary (%zu models, %s scans, %zu points, noise %.4f D, res %d, method %s)\n", n,
              scanKindName(kind), opt.points, kind == ScanKind::Uniform ? opt.noise : 0.0,
              opt.resolution, std::string(methodName(opt.method)).c_str());
  std::printf("  reconstructed (Ok):            %zu / %zu\n", t.ok, n);
  std::printf("  IoU measured:                  %zu (closed meshes among the reconstructed)\n",
              t.withIou);
  std::printf("  IoU >= 0.95:                   %zu / %zu\n", t.iou95, t.withIou);
  std::printf("  IoU >= 0.99:                   %zu / %zu\n", t.iou99, t.withIou);
  std::printf("  median IoU:                    %.4f\n", median(t.ious));
  std::printf("  primitives <= InverseCSG's:    %zu / %zu (total %ld vs %ld over those models)\n",
              t.notLarger, t.ok, t.ourPrims, t.theirPrims);
  std::printf("  reconstruct time, median/max:  %.2f / %.2f s (%zu runs)\n", median(t.times),
              t.times.empty() ? -1.0 : *std::max_element(t.times.begin(), t.times.end()),
              t.times.size());
  std::printf("  read + reconstruct, median/max: %.2f / %.2f s\n", median(t.totals),
              t.totals.empty() ? -1.0 : *std::max_element(t.totals.begin(), t.totals.end()));
  std::printf("  load average at end:           %.2f\n", loadAverage());
}

}  // namespace

int main(int argc, char** argv) {
  Options opt;
  if (!parseArguments(argc, argv, opt)) return usage(argv[0]);

  std::map<std::string, Reference> refs;
  try {
    refs = readReferences(opt.dir / "inversecsg-results.csv");
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 1;
  }
  if (opt.models.empty()) {
    for (const auto& [name, ref] : refs) opt.models.push_back(name);
  }

  printHeading(opt);
  std::vector<ScanKind> kinds;
  if (opt.uniform) kinds.push_back(ScanKind::Uniform);
  if (opt.scanner) kinds.push_back(ScanKind::Scanner);
  std::map<ScanKind, Tally> tally;
  // Read + reconstruct of each model's scanner row over its uniform row's.
  std::vector<double> timeRatios;
  for (const std::string& model : opt.models) {
    const auto ref = refs.find(model);
    const Reference r = ref != refs.end() ? ref->second : Reference{};
    double uniformTotal = -1.0;
    for (ScanKind kind : kinds) {
      const Result res = runIsolated(opt, model, kind);
      printRow(model, kind, r, res);
      tally[kind].add(res, r, ref != refs.end());
      const double total = res.totalSeconds();
      if (kind == ScanKind::Uniform) uniformTotal = total;
      if (kind == ScanKind::Scanner && uniformTotal > 0.0 && total >= 0.0)
        timeRatios.push_back(total / uniformTotal);
    }
  }
  for (ScanKind kind : kinds) printSummary(opt, kind, tally[kind]);
  if (!timeRatios.empty()) {
    const std::size_t above = std::size_t(std::count_if(
        timeRatios.begin(), timeRatios.end(), [](double x) { return x > 1.5; }));
    std::printf(
        "\nscanner row over uniform row, read + reconstruct: median %.2f, above 1.5 on %zu of "
        "%zu models\n",
        median(timeRatios), above, timeRatios.size());
  }
  return 0;
}
