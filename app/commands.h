#pragma once
/// The csgvox sub-commands. Each registers its options on a CLI11 app and
/// runs when that app is parsed. Exit codes: 0 success, 1 bad input or a
/// failed step (one line on stderr), 2 bad command line.

#include <CLI/CLI.hpp>
#include <functional>
#include <string>

namespace csgvox::app {

/// Options shared by every command.
struct CommonOptions {
  bool quiet = false;   ///< no progress lines on stderr
  int threads = 0;      ///< worker threads, 0 = all cores
  std::string subject;  ///< the input being worked on, put in front of error messages not naming it
};

/// A command: sets up its options on `app` and returns the function that runs it.
using Command = std::function<int()>;

Command setupReconstruct(CLI::App& app, CommonOptions& common);
Command setupSample(CLI::App& app, CommonOptions& common);
Command setupRender(CLI::App& app, CommonOptions& common);
Command setupEval(CLI::App& app, CommonOptions& common);
Command setupDetect(CLI::App& app, CommonOptions& common);
Command setupImportGp(CLI::App& app, CommonOptions& common);
Command setupCompare(CLI::App& app, CommonOptions& common);
Command setupBatch(CLI::App& app, CommonOptions& common);

}  // namespace csgvox::app
