// csgvox import-gp FIT EXPR -o OUT [--scan SCAN]

#include <cstdio>
#include <filesystem>
#include <map>

#include "app/commands.h"
#include "io/file_util.h"
#include "io/gp_files.h"
#include "io/output_set.h"
#include "io/report.h"
#include "io/scad_export.h"
#include "io/scan_reader.h"
#include "io/text_export.h"
#include "io/tree_json.h"
#include "job/console.h"

namespace csgvox::app {

namespace fs = std::filesystem;

namespace {

struct ImportGpOptions {
  std::string fit;
  std::string expression;
  std::string output;
  std::string scan;
};

constexpr const char* kFooter =
    "Reads the files of the genetic-programming baseline (Fayolle & Pasko 2016) into a csgvox\n"
    "tree. FIT: one primitive per line, its index is its line number from 0, f >= 0 inside:\n"
    "  plane nx ny nz d                      f = d - n.x\n"
    "  sphere cx cy cz r                     f = r - |x - c|\n"
    "  cylinder ax ay az px py pz r          axis a through p\n"
    "  cone ax ay az cx cy cz angle          apex c, axis a, half-angle in radians\n"
    "  torus nx ny nz cx cy cz r_minor r_major   axis n through centre c\n"
    "EXPR: union[A,B] (max), intersection[A,B] (min), subtraction[A,B] (min(A,-B)),\n"
    "negation[A] (-A); leaves TYPE+index (plane0, cylinder7).\n\n"
    "The baseline's primitives are unbounded: each leaf is made exact inside a clip box (the\n"
    "scan's box grown by 5 % of its diagonal with --scan, otherwise the box of the primitives'\n"
    "reference points grown by 10 %), and the tree is intersected with that box (leaf\n"
    "clip_box), so that render and eval accept it.\n\n"
    "Writes: with -o FILE.json, that tree.json file; with -o FOLDER, tree.json, tree.scad\n"
    "(OpenSCAD) and tree.txt (expression) in it. See README.md, \"Importing the GP baseline's\n"
    "trees\".";

std::string describePrimitives(const std::vector<GpPrimitive>& primitives) {
  std::map<std::string, std::size_t> counts;
  for (const GpPrimitive& p : primitives) {
    ++counts[std::string(surfaceTypeName(static_cast<SurfaceType>(p.shape.index())))];
  }
  std::string out = std::to_string(primitives.size()) + " primitives (";
  bool first = true;
  for (const auto& [name, count] : counts) {
    out += (first ? "" : ", ") + std::to_string(count) + " " + name + (count == 1 ? "" : "s");
    first = false;
  }
  return out + ")";
}

std::string describeBox(const Aabb& box) {
  char buf[256];
  std::snprintf(buf, sizeof(buf), "[%.6g, %.6g] x [%.6g, %.6g] x [%.6g, %.6g]", box.min.x(),
                box.max.x(), box.min.y(), box.max.y(), box.min.z(), box.max.z());
  return buf;
}

}  // namespace

Command setupImportGp(CLI::App& app, CommonOptions& common) {
  auto opt = std::make_shared<ImportGpOptions>();
  app.footer(kFooter);
  app.add_option("FIT", opt->fit, "The baseline's primitive file (.fit)")->required();
  app.add_option("EXPR", opt->expression, "The baseline's tree expression (*_expr.txt)")
      ->required();
  app.add_option("-o,--output", opt->output,
                 "tree.json file to write (a name ending in .json), or a folder for tree.json, "
                 "tree.scad and tree.txt")
      ->required();
  app.add_option("--scan", opt->scan,
                 "The scan the tree was made for: its box, grown by 5 % of its diagonal, is the "
                 "clip box");
  return [opt, &common]() -> int {
    Console console(common.quiet);
    common.subject = opt->fit;
    const fs::path fitPath(opt->fit), exprPath(opt->expression), outPath(opt->output);
    std::vector<fs::path> inputs = {fitPath, exprPath};
    GpImportOptions io;
    if (!opt->scan.empty()) {
      common.subject = opt->scan;
      const Scan scan = readScan(fs::path(opt->scan));
      console.info("read " + opt->scan + ": " + describeScan(scan));
      io.box = gpScanClipBox(scan.cloud.bounds());
      inputs.emplace_back(opt->scan);
      common.subject = opt->fit;
    }
    const bool single = lowerExtension(outPath) == "json";
    // Outputs are checked against the inputs before anything is read further.
    std::unique_ptr<OutputSet> output;
    if (single) {
      for (const fs::path& in : inputs) requireNotInput(outPath, in);
    } else {
      output = std::make_unique<OutputSet>(
          outPath, std::vector<std::string>{"tree.json", "tree.scad", "tree.txt"}, inputs);
    }
    const GpImport imported = importGp(fitPath, exprPath, io);
    console.info("read " + opt->fit + ": " + describePrimitives(imported.primitives));
    console.info("clip box " + describeBox(imported.box) +
                 (opt->scan.empty() ? " (from the primitives)" : " (from the scan)"));
    const CsgTree& tree = imported.tree;
    console.info("tree: " + std::to_string(tree.primitiveCount()) + " leaves (with clip_box), " +
                 std::to_string(tree.operationCount()) + " operations, depth " +
                 std::to_string(tree.depth()));
    if (single) {
      writeTreeJson(outPath, tree);
      console.info("wrote " + outPath.string());
    } else {
      writeTreeJson(output->path("tree.json"), tree);
      writeScad(output->path("tree.scad"), tree);
      writeTreeText(output->path("tree.txt"), tree);
      output->commit();
      console.info("wrote tree.json, tree.scad, tree.txt in " + outPath.string());
    }
    return 0;
  };
}

}  // namespace csgvox::app
