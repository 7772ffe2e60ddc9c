// csgvox render TREE.json -o OUT.{ply,stl,obj,scad,txt,json} [--res N]

#include <cstdio>

#include "app/commands.h"
#include "app/console.h"
#include "app/options.h"
#include "io/errors.h"
#include "io/file_util.h"
#include "io/mesh_files.h"
#include "io/scad_export.h"
#include "io/text_export.h"
#include "io/tree_json.h"
#include "mesh/mesh_export.h"

namespace csgvox::app {

namespace {

struct RenderOptions {
  std::string tree;
  std::string output;
  int resolution = MeshOptions{}.resolution;
  int facets = ScadOptions{}.facets;
};

}  // namespace

Command setupRender(CLI::App& app, CommonOptions& common) {
  auto opt = std::make_shared<RenderOptions>();
  app.add_option("TREE", opt->tree, "CSG tree (tree.json)")->required();
  app.add_option("-o,--output", opt->output,
                 "Output file; its extension picks the format: .ply .stl .obj (mesh), "
                 ".scad (OpenSCAD), .txt (expression), .json (tree)")
      ->required();
  app.add_option("--res", opt->resolution,
                 "Mesh resolution: grid cells along the longest side of the part")
      ->check(inRange(8, 2048));
  app.add_option("--fn", opt->facets, "OpenSCAD $fn for curved primitives")
      ->check(inRange(3, 1000));
  return [opt, &common]() -> int {
    Console console(common.quiet);
    common.subject = opt->tree;
    const CsgTree tree = readTreeJson(std::filesystem::path(opt->tree));
    const std::string ext = lowerExtension(opt->output);
    requireNotInput(opt->output, opt->tree);
    Stopwatch watch;
    if (ext == "ply" || ext == "stl" || ext == "obj") {
      MeshOptions mo;
      mo.resolution = opt->resolution;
      const TriangleMesh mesh = meshTree(tree, mo, console.progress());
      char buf[256];
      std::snprintf(buf, sizeof(buf), "meshed at res %d: %zu vertices, %zu triangles in %.2f s",
                    opt->resolution, mesh.vertices.size(), mesh.triangles.size(), watch.seconds());
      console.info(buf);
      writeMesh(opt->output, mesh);
    } else if (ext == "scad") {
      ScadOptions so;
      so.facets = opt->facets;
      writeScad(std::filesystem::path(opt->output), tree, so);
    } else if (ext == "txt") {
      writeTreeText(std::filesystem::path(opt->output), tree);
    } else if (ext == "json") {
      writeTreeJson(std::filesystem::path(opt->output), tree);
    } else {
      throw IoError(opt->output +
                    ": unsupported output format (use .ply, .stl, .obj, .scad, .txt or .json)");
    }
    console.info("wrote " + opt->output);
    return 0;
  };
}

}  // namespace csgvox::app
