// csgvox: from a 3D scan of a mechanical part to a compact, editable CSG tree.

#include <tbb/global_control.h>

#include <cstdio>
#include <cstring>
#include <memory>
#include <new>
#include <string>

#include "app/commands.h"
#include "app/options.h"
#include "io/errors.h"
#include "primitives/solver_log.h"

namespace {

constexpr const char* kDescription =
    "csgvox turns a 3D scan of a mechanical part into a compact, editable CSG tree.\n\n"
    "Usage:\n"
    "  csgvox SCAN [--res N] [-o OUTDIR] [--seed S] [--threads T] [--quiet]\n"
    "  csgvox detect SCAN -o OUTDIR [--epsilon E] [--min-points M] [--res N] ...\n"
    "  csgvox sample TREE.json -o SCAN.ply [--points N] [--noise R] [--drop K] [--seed S]\n"
    "  csgvox render TREE.json -o OUT.{ply,stl,obj,scad,txt,json} [--res N]\n"
    "  csgvox eval TREE.json SCAN [--json]\n"
    "  csgvox import-gp FIT EXPR -o {TREE.json,OUTDIR} [--scan SCAN]\n"
    "  csgvox compare SCAN [--methods voxel,gp] [--import-gp FIT EXPR] [-o OUTDIR]\n"
    "  csgvox batch INPUT... -o OUTDIR [--jobs N] [--resume] [main-job options]\n\n"
    "Run 'csgvox <command> --help' for a command's options. Progress and timings go to\n"
    "stderr, results to files. Exit codes: 0 success, 1 bad input or failure, 2 bad usage.";

bool isCommand(const char* arg) {
  for (const char* c : {"detect", "sample", "render", "eval", "import-gp", "compare", "batch"}) {
    if (std::strcmp(arg, c) == 0) return true;
  }
  return false;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace csgvox;
  app::CommonOptions common;
  // The main job takes a scan as its first argument; everything else is a
  // named sub-command.
  const bool sub = argc > 1 && isCommand(argv[1]);
  CLI::App cli(kDescription, "csgvox");
  cli.set_version_flag("--version", "csgvox 0.1.0");
  cli.add_flag("-q,--quiet", common.quiet, "No progress lines on stderr");
  cli.add_option("--threads", common.threads, "Worker threads (0 = all cores)")
      ->check(app::inRange(0, 1024));
  app::Command run;
  if (sub) {
    CLI::App* cmd = nullptr;
    if (std::strcmp(argv[1], "sample") == 0) {
      cmd = cli.add_subcommand("sample", "Sample a synthetic scan on the surface of a CSG tree");
      run = app::setupSample(*cmd, common);
    } else if (std::strcmp(argv[1], "detect") == 0) {
      cmd = cli.add_subcommand("detect",
                               "Detect surfaces and build the primitive hypotheses of a scan");
      run = app::setupDetect(*cmd, common);
    } else if (std::strcmp(argv[1], "render") == 0) {
      cmd = cli.add_subcommand("render", "Export a CSG tree as a mesh, OpenSCAD, text or JSON");
      run = app::setupRender(*cmd, common);
    } else if (std::strcmp(argv[1], "compare") == 0) {
      cmd = cli.add_subcommand("compare",
                               "Run several methods on one detection and compare their trees");
      run = app::setupCompare(*cmd, common);
    } else if (std::strcmp(argv[1], "batch") == 0) {
      cmd = cli.add_subcommand("batch", "Run the main job on many scans, a summary row per scan");
      run = app::setupBatch(*cmd, common);
    } else if (std::strcmp(argv[1], "import-gp") == 0) {
      cmd = cli.add_subcommand("import-gp",
                               "Read the GP baseline's primitive and expression files into a tree");
      run = app::setupImportGp(*cmd, common);
    } else {
      cmd = cli.add_subcommand("eval", "Fit metrics of a CSG tree against a scan");
      run = app::setupEval(*cmd, common);
    }
    cmd->fallthrough();
    cli.require_subcommand(1);
  } else {
    run = app::setupReconstruct(cli, common);
  }
  try {
    cli.parse(argc, argv);
  } catch (const CLI::Success& e) {
    return cli.exit(e);
  } catch (const CLI::ParseError& e) {
    const int code = cli.exit(e);
    return code == 0 ? 0 : 2;
  }

  // Ceres logs a warning through glog for every step it cannot take (an
  // ill-conditioned fit it then recovers from): noise between our progress
  // lines, not news for the user. Errors still get through.
  setSolverLog(common.quiet ? SolverLog::None : SolverLog::Errors);

  std::unique_ptr<tbb::global_control> threads;
  if (common.threads > 0) {
    threads = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                    std::size_t(common.threads));
  }
  // One line naming the input and the problem. Library messages that do
  // not name the input get it in front.
  const auto fail = [&](std::string message) {
    if (!common.subject.empty() && message.find(common.subject) == std::string::npos) {
      message = common.subject + ": " + message;
    }
    std::fprintf(stderr, "csgvox: error: %s\n", message.c_str());
    return 1;
  };
  try {
    return run();
  } catch (const std::bad_alloc&) {
    return fail("out of memory");
  } catch (const std::exception& e) {
    return fail(e.what());
  }
}
