#include "render/preview.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wunused-function"
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"
#include <stb_easy_font.h>
#pragma GCC diagnostic pop

namespace csgvox {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr int kStrip = 44;  // rows under the panels for the captions and the colour bar

// Depth and facet normal of the nearest triangle at each pixel centre.
struct DepthBuffer {
  int width = 0, height = 0;
  std::vector<double> depth;  // kInf where nothing covers the pixel
  std::vector<Vec3> normal;   // outward facet normal

  DepthBuffer(int w, int h)
      : width(w), height(h), depth(std::size_t(w) * h, kInf), normal(std::size_t(w) * h) {}
  std::size_t index(int x, int y) const { return std::size_t(y) * width + x; }
};

DepthBuffer rasterize(const TriangleMesh& mesh, const PreviewView& view) {
  DepthBuffer buf(view.width, view.height);
  std::vector<Vec3> projected(mesh.vertices.size());
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i)
    projected[i] = view.project(mesh.vertices[i]);
  for (const auto& t : mesh.triangles) {
    const Vec3& a = projected[t[0]];
    const Vec3& b = projected[t[1]];
    const Vec3& c = projected[t[2]];
    const double area = (b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x());
    if (std::abs(area) < 1e-12) continue;
    const int x0 = std::max(0, int(std::ceil(std::min({a.x(), b.x(), c.x()}))));
    const int x1 = std::min(view.width - 1, int(std::floor(std::max({a.x(), b.x(), c.x()}))));
    const int y0 = std::max(0, int(std::ceil(std::min({a.y(), b.y(), c.y()}))));
    const int y1 = std::min(view.height - 1, int(std::floor(std::max({a.y(), b.y(), c.y()}))));
    if (x0 > x1 || y0 > y1) continue;
    const Vec3& pa = mesh.vertices[t[0]];
    const Vec3 n = (mesh.vertices[t[1]] - pa).cross(mesh.vertices[t[2]] - pa).normalized();
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) {
        // Barycentric weights of the pixel centre (x, y).
        const double wa = ((b.x() - x) * (c.y() - y) - (b.y() - y) * (c.x() - x)) / area;
        const double wb = ((c.x() - x) * (a.y() - y) - (c.y() - y) * (a.x() - x)) / area;
        const double wc = 1.0 - wa - wb;
        if (wa < 0.0 || wb < 0.0 || wc < 0.0) continue;
        const double d = wa * a.z() + wb * b.z() + wc * c.z();
        const std::size_t k = buf.index(x, y);
        if (d < buf.depth[k]) {
          buf.depth[k] = d;
          buf.normal[k] = n;
        }
      }
    }
  }
  return buf;
}

std::uint8_t channel(double v) { return std::uint8_t(std::clamp(v, 0.0, 250.0) + 0.5); }

// Shades the solid: the exact field's normal at each covered pixel, two
// lights, dark lines where the normal or the depth jumps (the part's edges).
void drawSolid(RgbImage& image, const CsgTree& tree, const DepthBuffer& buf,
               const PreviewView& view, const PreviewOptions& options) {
  std::vector<Vec3> normals(buf.normal.size(), Vec3::Zero());
  tbb::parallel_for(0, view.height, [&](int y) {
    for (int x = 0; x < view.width; ++x) {
      const std::size_t k = buf.index(x, y);
      if (buf.depth[k] == kInf) continue;
      const Vec3 p = view.rayOrigin(x, y) - buf.depth[k] * view.toEye;
      Vec3 n = -tree.evaluate(p).gradient;
      n = n.norm() > 0.5 ? n.normalized() : buf.normal[k];
      if (n.dot(view.toEye) < 0.0) n = buf.normal[k];
      normals[k] = n;
    }
  });
  const Vec3 key = (0.4 * view.toEye + 0.55 * view.up - 0.45 * view.right).normalized();
  const Vec3 fill = (view.toEye + 0.6 * view.right - 0.2 * view.up).normalized();
  const Vec3 half = (key + view.toEye).normalized();
  const Vec3 base(0.60, 0.68, 0.78);
  for (int y = 0; y < view.height; ++y) {
    for (int x = 0; x < view.width; ++x) {
      const std::size_t k = buf.index(x, y);
      if (buf.depth[k] == kInf) continue;
      const Vec3& n = normals[k];
      bool edge = false;
      for (const auto& [dx, dy] :
           {std::pair{1, 0}, std::pair{0, 1}, std::pair{-1, 0}, std::pair{0, -1}}) {
        const int u = x + dx, v = y + dy;
        if (u < 0 || v < 0 || u >= view.width || v >= view.height) continue;
        const std::size_t j = buf.index(u, v);
        if (buf.depth[j] == kInf) continue;
        if (normals[j].dot(n) < 0.85 ||
            std::abs(buf.depth[j] - buf.depth[k]) > 4 * view.pixelSize) {
          edge = true;
        }
      }
      const double light =
          0.28 + 0.62 * std::max(0.0, n.dot(key)) + 0.22 * std::max(0.0, n.dot(fill));
      const double spec = 0.18 * std::pow(std::max(0.0, n.dot(half)), 40.0);
      Vec3 c = (light * base + Vec3::Constant(spec)) * 255.0;
      if (edge) c *= 0.55;
      Rgb rgb = {channel(c.x()), channel(c.y()), channel(c.z())};
      if (rgb == options.background) rgb[0] = std::uint8_t(rgb[0] ^ 1);
      image.set(x, y, rgb);
    }
  }
}

// A blue-green-yellow-red scale for t in [0, 1].
Rgb scaleColour(double t) {
  static const Vec3 stops[] = {{0.19, 0.27, 0.85},
                               {0.10, 0.70, 0.85},
                               {0.25, 0.80, 0.30},
                               {0.95, 0.85, 0.15},
                               {0.88, 0.18, 0.12}};
  t = std::clamp(t, 0.0, 1.0) * 4.0;
  const int i = std::min(3, int(t));
  const Vec3 c = stops[i] + (t - i) * (stops[i + 1] - stops[i]);
  return {channel(255 * c.x()), channel(255 * c.y()), channel(255 * c.z())};
}

// The smallest of 1, 2, 2.5, 5 x 10^k at least v.
double niceCeil(double v) {
  const double p = std::pow(10.0, std::floor(std::log10(v)));
  for (double m : {1.0, 2.0, 2.5, 5.0, 10.0}) {
    if (m * p >= v * (1.0 - 1e-12)) return m * p;
  }
  return 10.0 * p;
}

std::string percent(double fraction) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%g", 100.0 * fraction);
  return buf;
}

void text(RgbImage& image, int x, int y, const std::string& s, Rgb colour, int scale = 2) {
  std::vector<char> chars(s.begin(), s.end());
  chars.push_back('\0');
  std::vector<char> vertices(16 * 4 * 600);
  unsigned char rgba[4] = {colour[0], colour[1], colour[2], 255};
  const int quads =
      stb_easy_font_print(0, 0, chars.data(), rgba, vertices.data(), int(vertices.size()));
  for (int q = 0; q < quads; ++q) {
    const float* v0 = reinterpret_cast<const float*>(&vertices[std::size_t(q) * 64]);
    const float* v2 = reinterpret_cast<const float*>(&vertices[std::size_t(q) * 64 + 32]);
    for (int py = int(v0[1]) * scale; py < int(v2[1]) * scale; ++py) {
      for (int px = int(v0[0]) * scale; px < int(v2[0]) * scale; ++px) {
        image.set(x + px, y + py, colour);
      }
    }
  }
}

int textWidth(const std::string& s, int scale = 2) {
  std::vector<char> chars(s.begin(), s.end());
  chars.push_back('\0');
  return stb_easy_font_width(chars.data()) * scale;
}

// The scan's points, seen from the view, coloured by their distance to the
// solid; returns the top of the scale (fraction of D).
double drawScan(RgbImage& image, int offsetX, const CsgTree& tree, const PointCloud& scan,
                double surfaceArea, const PreviewView& view, const PreviewOptions& options) {
  const double diagonal = std::max(scan.diagonal(), 1e-300);
  std::vector<double> dist(scan.size());
  tree.values(scan.points, dist);
  for (double& d : dist) d = std::abs(d) / diagonal;
  std::vector<double> sorted = dist;
  const std::size_t q = std::min(sorted.size() - 1, std::size_t(0.95 * double(sorted.size())));
  std::nth_element(sorted.begin(), sorted.begin() + std::ptrdiff_t(q), sorted.end());
  const double top = niceCeil(std::max(options.minScale, sorted[q]));

  // Splats about as wide as the spacing of the points on the surface.
  const double spacing = std::sqrt(surfaceArea / double(scan.size())) / view.pixelSize;
  const double radius = std::clamp(0.7 * spacing, 0.7, 4.0);
  const int reach = int(std::ceil(radius));
  std::vector<double> depth(std::size_t(view.width) * view.height, kInf);
  for (std::size_t i = 0; i < scan.size(); ++i) {
    double shade = 1.0;
    if (scan.hasNormals()) {
      const double facing = scan.normals[i].dot(view.toEye);
      if (facing < -0.05) continue;  // on the far side
      shade = 0.62 + 0.38 * std::max(0.0, facing);
    }
    const Vec3 p = view.project(scan.points[i]);
    const Rgb c0 = scaleColour(dist[i] / top);
    const Rgb c = {channel(c0[0] * shade), channel(c0[1] * shade), channel(c0[2] * shade)};
    const int cx = int(std::lround(p.x())), cy = int(std::lround(p.y()));
    for (int y = cy - reach; y <= cy + reach; ++y) {
      for (int x = cx - reach; x <= cx + reach; ++x) {
        if (x < 0 || y < 0 || x >= view.width || y >= view.height) continue;
        if ((x - p.x()) * (x - p.x()) + (y - p.y()) * (y - p.y()) > radius * radius + 0.25)
          continue;
        double& d = depth[std::size_t(y) * view.width + x];
        if (p.z() >= d) continue;
        d = p.z();
        image.set(offsetX + x, y, c);
      }
    }
  }
  return top;
}

void drawColourBar(RgbImage& image, int x0, int width, int y0, double top) {
  const Rgb ink = {60, 60, 60};
  const int barW = width - 2 * 24, barH = 10, bx = x0 + 24, by = y0 + 4;
  for (int x = 0; x < barW; ++x) {
    const Rgb c = scaleColour(double(x) / (barW - 1));
    for (int y = 0; y < barH; ++y) image.set(bx + x, by + y, c);
  }
  for (int i = 0; i <= 4; ++i) {
    const int x = bx + (barW - 1) * i / 4;
    for (int y = by + barH; y < by + barH + 4; ++y) image.set(x, y, ink);
    if (i % 2) continue;
    std::string label = percent(top * i / 4.0);
    if (i == 4) label = ">= " + label + " % of D";
    const int w = textWidth(label);
    text(image, std::clamp(x - (i == 4 ? w - 8 : w / 2), x0 + 2, x0 + width - w - 2), by + barH + 6,
         label, ink);
  }
}

}  // namespace

Preview renderPreview(const CsgTree& tree, const TriangleMesh& mesh, const PointCloud* scan,
                      const PreviewOptions& options) {
  if (mesh.triangles.empty()) throw std::invalid_argument("the preview needs a non-empty mesh");
  if (options.panelSize < 64 || options.panelSize > 4096) {
    throw std::invalid_argument("preview panel size must be between 64 and 4096 pixels");
  }
  const bool withScan = scan != nullptr && !scan->empty();
  const int s = options.panelSize;
  Aabb bounds = mesh.bounds();
  if (withScan) bounds.extend(scan->bounds());
  Preview out;
  out.view = PreviewView::framing(bounds, s, s);
  out.image = RgbImage::filled(withScan ? 2 * s : s, s + kStrip, options.background);

  const DepthBuffer buf = rasterize(mesh, out.view);
  drawSolid(out.image, tree, buf, out.view, options);
  const Rgb ink = {60, 60, 60};
  const std::string caption = "CSG tree: " + std::to_string(tree.primitiveCount()) +
                              " primitives, " + std::to_string(tree.operationCount()) +
                              " operations";
  text(out.image, std::max(2, (s - textWidth(caption)) / 2), s + 12, caption, ink);
  if (withScan) {
    out.scaleTop = drawScan(out.image, s, tree, *scan, mesh.area(), out.view, options);
    text(out.image, s + 8, 8, "scan: distance to the tree", ink);
    for (int y = 0; y < s + kStrip; ++y) out.image.set(s, y, {200, 200, 200});
    drawColourBar(out.image, s, s, s + 2, out.scaleTop);
  }
  return out;
}

}  // namespace csgvox
