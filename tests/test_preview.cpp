// preview.png: the solid's panel shows the solid exactly where a ray through
// the pixel hits the tree's solid (found here by sphere tracing its exact
// field), for several bundled parts; the scan's panel and colour bar are
// drawn; the PNG reads back as written.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "io/errors.h"
#include "io/png_file.h"
#include "io/scan_reader.h"
#include "io/tree_json.h"
#include "mesh/mesh_export.h"
#include "part_list.h"
#include "render/preview.h"
#include "temp_dir_test.h"

namespace csgvox {
namespace {

// True when the ray through pixel (x, y) of the view meets the solid:
// sphere tracing, each step the field's value (a lower bound of the
// distance to the surface for min/max trees of exact distances).
bool rayHits(const CsgTree& tree, const PreviewView& view, int x, int y) {
  const Vec3 origin = view.rayOrigin(x, y);
  const double floor = 1e-4 * view.pixelSize;
  for (double t = 0.0; t < 2.5 * view.reach;) {
    const double f = tree.value(origin - t * view.toEye);
    if (f >= 0.0) return true;
    t += std::max(-f, floor);
  }
  return false;
}

class PreviewTest : public test::TempDirTest {};

TEST_F(PreviewTest, TheSolidsPanelShowsTheSolidWhereRaysHitIt) {
  for (const std::string part : {"flange", "housing_complex", "knob", "wedge_block"}) {
    SCOPED_TRACE(part);
    const CsgTree tree = readTreeJson(test::dataDir() / part / "tree.json");
    MeshOptions mo;
    mo.resolution = 128;
    const TriangleMesh mesh = meshTree(tree, mo);
    const Scan scan = readScan(test::dataDir() / part / "scan.ply");
    PreviewOptions po;
    po.panelSize = 160;
    const Preview preview = renderPreview(tree, mesh, &scan.cloud, po);
    const auto path = dir_ / (part + ".png");
    writePng(path, preview.image);
    const RgbImage png = readPng(path);
    ASSERT_EQ(png.width, 2 * po.panelSize);
    ASSERT_GT(png.height, po.panelSize);
    EXPECT_EQ(png.rgb, preview.image.rgb);

    std::size_t both = 0, either = 0, solidPixels = 0;
    for (int y = 0; y < preview.view.height; ++y) {
      for (int x = 0; x < preview.view.width; ++x) {
        const bool shown = png.at(x, y) != po.background;
        const bool hit = rayHits(tree, preview.view, x, y);
        both += shown && hit;
        either += shown || hit;
        solidPixels += hit;
      }
    }
    const double iou = double(both) / double(either);
    std::printf("[ preview ] %-16s silhouette IoU %.4f (%zu pixels differ of %zu)\n", part.c_str(),
                iou, either - both, solidPixels);
    EXPECT_GT(solidPixels, std::size_t(0.1 * po.panelSize * po.panelSize));
    EXPECT_GE(iou, 0.98);

    // The scan's panel shows points, the colour bar spans the scale.
    std::size_t scanPixels = 0;
    for (int y = 20; y < po.panelSize; ++y) {
      for (int x = po.panelSize + 2; x < 2 * po.panelSize; ++x)
        scanPixels += png.at(x, y) != po.background;
    }
    EXPECT_GT(scanPixels, std::size_t(0.05 * po.panelSize * po.panelSize));
    EXPECT_GE(preview.scaleTop, po.minScale);
  }
}

TEST_F(PreviewTest, WithoutAScanThePictureIsTheSolidAlone) {
  const CsgTree tree = CsgTree::leaf(Sphere{Vec3(1, 2, 3), 2.0});
  MeshOptions mo;
  mo.resolution = 64;
  PreviewOptions po;
  po.panelSize = 100;
  const Preview p = renderPreview(tree, meshTree(tree, mo), nullptr, po);
  EXPECT_EQ(p.image.width, 100);
  // A sphere's silhouette is a disc: the centre pixel is shaded, the corners are not.
  EXPECT_NE(p.image.at(50, 50), po.background);
  EXPECT_EQ(p.image.at(2, 2), po.background);
  EXPECT_EQ(p.scaleTop, 0.0);
}

TEST_F(PreviewTest, BadInputIsRefused) {
  EXPECT_THROW(renderPreview(CsgTree::leaf(Sphere{}), TriangleMesh{}, nullptr),
               std::invalid_argument);
  EXPECT_THROW(writePng(dir_ / "x.png", RgbImage{}), std::invalid_argument);
  EXPECT_THROW(readPng(write("bad.png", "not a png")), ParseError);
}

}  // namespace
}  // namespace csgvox
