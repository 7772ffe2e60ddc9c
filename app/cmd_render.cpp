// csgvox render TREE.json -o OUT.{ply,stl,obj,scad,txt,json,csg,step,png} [--res N] [--scan SCAN]

#include <cstdio>
#include <optional>

#include "app/commands.h"
#include "app/options.h"
#include "app/tree_command.h"
#include "cad/step_export.h"
#include "design/designed_tree.h"
#include "io/csg_writer.h"
#include "io/design_json.h"
#include "io/design_scad.h"
#include "io/errors.h"
#include "io/freecad_macro.h"
#include "io/file_util.h"
#include "io/mesh_files.h"
#include "io/png_file.h"
#include "io/scad_export.h"
#include "io/scan_reader.h"
#include "io/text_export.h"
#include "io/tree_json.h"
#include "job/console.h"
#include "mesh/mesh_export.h"
#include "render/preview.h"

namespace csgvox::app {

namespace {

struct RenderOptions {
  std::string tree;
  std::string output;
  int resolution = MeshOptions{}.resolution;
  int facets = ScadOptions{}.facets;
  std::string scan;
  int panelSize = PreviewOptions{}.panelSize;
  bool rawValues = false;
};

// The designed form of the tree, in the frame its tree.json records (else
// one chosen from the tree).
DesignedTree designedFromFile(const CsgTree& tree, const std::string& path) {
  if (const std::optional<PartFrame> frame = readTreeFrame(path)) {
    return designTree(tree, *frame, {});
  }
  return designTree(tree);
}

}  // namespace

Command setupRender(CLI::App& app, CommonOptions& common) {
  auto opt = std::make_shared<RenderOptions>();
  app.add_option("TREE", opt->tree, "CSG tree (tree.json)")->required();
  app.add_option("-o,--output", opt->output,
                 "Output file; its extension picks the format: .ply .stl .obj (mesh), "
                 ".scad (OpenSCAD), .txt (expression), .json (tree), .step (exact B-rep), "
                 ".csg (OpenSCAD CSG, for FreeCAD), .FCMacro (parametric FreeCAD model), .png (preview "
                 "picture)")
      ->required();
  app.add_option("--res", opt->resolution,
                 "Mesh resolution: grid cells along the longest side of the part")
      ->check(inRange(8, 2048));
  app.add_option(
         "--fn", opt->facets,
         "OpenSCAD $fn for every curved primitive (default: chosen per primitive from its size)")
      ->check(inRange(3, 1000));
  app.add_option("--scan", opt->scan,
                 ".png: also draw this scan's points coloured by their distance to the tree");
  app.add_option("--size", opt->panelSize, ".png: width and height of each panel, pixels")
      ->check(inRange(64, 4096));
  app.add_flag("--raw-values", opt->rawValues,
               ".scad, .txt, .json: write the tree's values as they are (by default: the part's "
               "frame, designed values, parameters and patterns)");
  return [opt, &common]() -> int {
    Console console(common.quiet);
    const auto [tree, ext] = readTreeCommand(common, opt->tree, opt->output);
    Stopwatch watch;
    if (ext == "ply" || ext == "stl" || ext == "obj") {
      MeshOptions mo;
      mo.resolution = opt->resolution;
      const TriangleMesh mesh = meshTree(tree, mo, RunControl(0.0, console.progress()));
      char buf[256];
      std::snprintf(buf, sizeof(buf), "meshed at res %d: %zu vertices, %zu triangles in %.2f s",
                    opt->resolution, mesh.vertices.size(), mesh.triangles.size(), watch.seconds());
      console.info(buf);
      writeMesh(opt->output, mesh);
    } else if (ext == "scad") {
      ScadOptions so;
      so.facets = opt->facets;
      if (opt->rawValues) {
        writeScad(std::filesystem::path(opt->output), tree, so);
      } else {
        writeDesignedScad(std::filesystem::path(opt->output), designedFromFile(tree, opt->tree), so);
      }
    } else if (ext == "txt") {
      if (opt->rawValues) {
        writeTreeText(std::filesystem::path(opt->output), tree);
      } else {
        writeTreeText(std::filesystem::path(opt->output), designedFromFile(tree, opt->tree));
      }
    } else if (ext == "json") {
      if (opt->rawValues) {
        writeTreeJson(std::filesystem::path(opt->output), tree);
      } else {
        writeDesignedTreeJson(std::filesystem::path(opt->output), designedFromFile(tree, opt->tree));
      }
    } else if (ext == "fcmacro") {
      writeFreecadMacro(std::filesystem::path(opt->output), designedFromFile(tree, opt->tree));
    } else if (ext == "csg") {
      writeCsg(std::filesystem::path(opt->output), tree);
    } else if (ext == "step" || ext == "stp") {
      const BrepSummary s = writeStep(std::filesystem::path(opt->output), tree);
      char buf[256];
      std::snprintf(buf, sizeof(buf), "exact solid: %zu solid(s), %zu faces, volume %.6g in %.2f s",
                    s.solids, s.faces, s.volume, watch.seconds());
      console.info(buf);
    } else if (ext == "png") {
      std::optional<Scan> scan;
      if (!opt->scan.empty()) {
        requireNotInput(opt->output, opt->scan);
        scan = readScan(std::filesystem::path(opt->scan));
      }
      MeshOptions mo;
      mo.resolution = opt->resolution;
      const TriangleMesh mesh = meshTree(tree, mo, RunControl(0.0, console.progress()));
      PreviewOptions po;
      po.panelSize = opt->panelSize;
      writePng(std::filesystem::path(opt->output),
               renderPreview(tree, mesh, scan ? &scan->cloud : nullptr, po).image);
    } else {
      throw IoError(opt->output +
                    ": unsupported output format (use .ply, .stl, .obj, .scad, .txt, .json, .csg, "
                    ".step, .FCMacro or .png)");
    }
    console.info("wrote " + opt->output);
    return 0;
  };
}

}  // namespace csgvox::app
