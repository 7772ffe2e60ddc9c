// step_check TREE.json STEP...: reads each STEP file with OpenCASCADE's
// reader and prints one line: solids, valid, closed, volume against the
// tree's (sampled, 160³ stratified points), and OK when the file is one
// valid closed solid within 0.5 % of the tree's volume. Exit 1 when any is
// not OK. With one argument, TREE.json's sibling tree.step is checked.

#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>

#include "cad/step_export.h"
#include "core/export_extent.h"
#include "core/solid_sampling.h"
#include "io/tree_json.h"

int main(int argc, char** argv) {
  namespace fs = std::filesystem;
  if (argc < 2) {
    std::fprintf(stderr, "usage: step_check TREE.json [STEP...]\n");
    return 2;
  }
  try {
    const csgvox::CsgTree tree = csgvox::readTreeJson(argv[1]);
    const csgvox::Aabb extent = csgvox::exportExtent(tree);
    const double sampled =
        csgvox::sampledVolume(tree, extent.grown(0.01 * extent.diagonal()), 160, 7);
    std::vector<fs::path> files;
    for (int i = 2; i < argc; ++i) files.emplace_back(argv[i]);
    if (files.empty()) files.push_back(fs::path(argv[1]).parent_path() / "tree.step");
    bool allOk = true;
    for (const fs::path& f : files) {
      if (!fs::exists(f)) {
        std::printf("%s: missing\n", f.c_str());
        allOk = false;
        continue;
      }
      const csgvox::BrepSummary s = csgvox::readStepSummary(f);
      const double error = s.volume / sampled - 1.0;
      const bool ok = s.solids == 1 && s.valid && s.closed && std::abs(error) <= 0.005;
      allOk = allOk && ok;
      std::printf(
          "%s: %zu solid(s), %s, %s, %zu faces, volume %.6g vs sampled %.6g (%+.3f %%) %s\n",
          f.c_str(), s.solids, s.valid ? "valid" : "INVALID", s.closed ? "closed" : "OPEN", s.faces,
          s.volume, sampled, 100 * error, ok ? "OK" : "FAIL");
    }
    return allOk ? 0 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "step_check: %s\n", e.what());
    return 1;
  }
}
