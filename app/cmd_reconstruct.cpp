// The main job: csgvox SCAN [--res N] [-o OUTDIR] ...

#include "app/commands.h"
#include "app/console.h"
#include "app/report.h"
#include "io/errors.h"
#include "io/file_util.h"
#include "io/scan_reader.h"

#include <filesystem>

namespace csgvox::app {

namespace fs = std::filesystem;

namespace {

struct ReconstructOptions {
  std::string scan;
  std::string outDir;
  int resolution = 64;
  std::uint64_t seed = 1;
};

}  // namespace

Command setupReconstruct(CLI::App& app, CommonOptions& common) {
  auto opt = std::make_shared<ReconstructOptions>();
  app.add_option("SCAN", opt->scan,
                 "Scan to reconstruct: PLY, XYZ, XYZN point cloud, or OFF/OBJ/STL/PLY mesh")
      ->required();
  app.add_option("-o,--output", opt->outDir,
                 "Output directory (default: <scan folder>/<scan name>-csgvox/)");
  app.add_option("--res", opt->resolution, "Voxels along the longest side of the part")
      ->check(CLI::Range(8, 1024));
  app.add_option("--seed", opt->seed, "Random seed; the same seed gives the same tree");
  return [opt, &common]() -> int {
    Console console(common.quiet);
    const fs::path scanPath(opt->scan);
    Stopwatch readTime;
    ReadOptions ro;
    ro.seed = opt->seed;
    const Scan scan = readScan(scanPath, ro);
    const double readSeconds = readTime.seconds();
    console.info("read " + scanPath.string() + ": " + describeScan(scan));

    fs::path out = opt->outDir.empty()
                       ? scanPath.parent_path() / (scanPath.stem().string() + "-csgvox")
                       : fs::path(opt->outDir);
    std::error_code ec;
    fs::create_directories(out, ec);
    if (ec || !fs::is_directory(out)) {
      throw IoError(out.string() + ": cannot create the output directory");
    }
    Report report;
    report.json["status"] = "scan-only";
    report.json["message"] =
        "the reconstruction stages (detection, voxel optimisation, evolution) are not part of "
        "this build yet; the scan was read and described";
    report.json["input"] = scanJson(scanPath, scan);
    report.json["parameters"] = {{"res", opt->resolution}, {"seed", opt->seed}};
    report.json["timings_s"] = {{"read", readSeconds}};
    report.write(out / "report.json");
    console.info("reconstruction stages are not implemented yet: wrote only " +
                 (out / "report.json").string());
    return 0;
  };
}

}  // namespace csgvox::app
