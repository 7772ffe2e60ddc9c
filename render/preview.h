#pragma once
/// preview.png: the tree's solid shaded from a three-quarter view and, beside
/// it, the scan's points seen from the same view and coloured by their
/// distance to the solid's surface, with a colour bar in % of the scan's
/// diagonal D. Drawn in memory: the solid's mesh is rasterised with a depth
/// buffer and shaded with the exact field's normals; no display is needed.

#include "core/csg_tree.h"
#include "core/point_cloud.h"
#include "core/rgb_image.h"
#include "core/triangle_mesh.h"
#include "render/view.h"

namespace csgvox {

/// Options of renderPreview().
struct PreviewOptions {
  int panelSize = 480;               ///< width and height of each panel, pixels (64..4096)
  double minScale = 0.001;           ///< the colour bar spans at least this fraction of D
  Rgb background = {255, 255, 255};  ///< colour of every pixel that shows nothing
};

/// The picture and the view both panels share.
struct Preview {
  RgbImage image;         ///< the solid's panel on the left, the scan's on the right (with a scan)
  PreviewView view;       ///< the solid's panel is image pixels [0, view.width) x [0, view.height)
  double scaleTop = 0.0;  ///< distance at the top of the colour bar, fraction of D (with a scan)
};

/// Draws the preview of `tree`, whose closed surface is `mesh` (meshTree()),
/// with the points of `scan` when it is given (and not empty). Pixels of the
/// solid's panel are the background colour exactly where the mesh covers no
/// pixel centre.
/// @throw std::invalid_argument when the mesh is empty or panelSize is out
///        of range.
Preview renderPreview(const CsgTree& tree, const TriangleMesh& mesh, const PointCloud* scan,
                      const PreviewOptions& options = {});

}  // namespace csgvox
