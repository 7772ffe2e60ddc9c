#include "mesh/surface_sampler.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>
#include <vector>

namespace csgvox {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;
using Rng = std::mt19937_64;

double uniform(Rng& rng) { return std::uniform_real_distribution<double>(0.0, 1.0)(rng); }

// A piece of a primitive's surface near the solid, for primitives much
// larger than the solid (a nearly flat face fitted as a cylinder of radius
// 4000 on a part 10 across): sampling their whole surface would almost
// never hit the solid. Each piece is a superset of the surface's part
// within the window (a ball around the solid's bounds) and is sampled
// uniformly; points off the primitive's surface are rejected like every
// point off the solid's boundary, so the density stays uniform.
struct Piece {
  enum class Kind { Parallelogram, CylinderSide, ConeSide, SphereCap } kind = Kind::Parallelogram;
  double area = 0.0;
  Vec3 origin = Vec3::Zero(), u = Vec3::Zero(), v = Vec3::Zero();  // origin + s u + t v
  Mat3 frame = Mat3::Identity();        // cylinder / sphere cap: third axis = axis or cap direction
  double radius = 0.0;                  // cylinder side, sphere cap; cone side: at height0
  double radius1 = 0.0;                 // cone side: the radius at height1
  double angle0 = 0.0, angle1 = 0.0;    // cylinder, cone side: angles in the frame's first two axes
  double height0 = 0.0, height1 = 0.0;  // cylinder, cone side: along the axis, from origin
  double cosCap = -1.0;                 // sphere cap: cosine of its angular radius
};

// The part of one primitive's surface that is sampled, with its area.
struct SurfaceDomain {
  const Primitive* primitive = nullptr;
  double area = 0.0;
  // Half-spaces: a rectangle in the plane covering the tree's bounds.
  Vec3 origin = Vec3::Zero(), u = Vec3::Zero(), v = Vec3::Zero();
  // Primitives reaching far past the solid: pieces near it (else empty).
  std::vector<Piece> pieces;
};

// The ball every boundary point of the solid lies in.
struct Window {
  Vec3 center;
  double radius;
};

// Rectangle [lo, hi] of a plane (origin, unit axes a, b) as a piece.
void addRectangle(std::vector<Piece>& pieces, const Vec3& origin, const Vec3& a, const Vec3& b,
                  double alo, double ahi, double blo, double bhi) {
  if (!(ahi > alo) || !(bhi > blo)) return;
  Piece p;
  p.origin = origin + alo * a + blo * b;
  p.u = (ahi - alo) * a;
  p.v = (bhi - blo) * b;
  p.area = (ahi - alo) * (bhi - blo);
  pieces.push_back(p);
}

// A face or cap in the plane through `centre` with unit in-plane axes a, b
// and normal n, of half extents ha, hb: the part within the window.
void addClippedFace(std::vector<Piece>& pieces, const Window& w, const Vec3& centre, const Vec3& a,
                    const Vec3& b, const Vec3& n, double ha, double hb) {
  const Vec3 q = w.center - centre;
  if (std::abs(q.dot(n)) > w.radius) return;
  const double qa = q.dot(a), qb = q.dot(b);
  addRectangle(pieces, centre, a, b, std::max(-ha, qa - w.radius), std::min(ha, qa + w.radius),
               std::max(-hb, qb - w.radius), std::min(hb, qb + w.radius));
}

// Half the angle of a circle of radius r about an axis at distance d from the
// window's centre (measured across the axis) that can lie within the
// window; pi when all of it can, a negative number when none can.
double halfAngleNear(double r, double d, double windowRadius) {
  if (!(d > 0.0) || !(r > 0.0)) return std::numbers::pi;
  const double cosHalf = (r * r + d * d - windowRadius * windowRadius) / (2.0 * r * d);
  if (cosHalf > 1.0) return -1.0;
  return cosHalf > -1.0 ? std::acos(cosHalf) : std::numbers::pi;
}

std::vector<Piece> piecesNear(const Primitive& prim, const Window& w) {
  std::vector<Piece> pieces;
  if (const auto* b = prim.as<Box>()) {
    for (int axis = 0; axis < 3; ++axis) {
      const int i = (axis + 1) % 3, j = (axis + 2) % 3;
      for (const double side : {-1.0, 1.0}) {
        addClippedFace(pieces, w, b->center + side * b->halfSize[axis] * b->axes.col(axis),
                       b->axes.col(i), b->axes.col(j), b->axes.col(axis), b->halfSize[i],
                       b->halfSize[j]);
      }
    }
  } else if (const auto* c = prim.as<Cylinder>()) {
    const Mat3 f = frameFromAxis(c->axis);
    for (const double side : {-1.0, 1.0}) {
      addClippedFace(pieces, w, c->center + side * 0.5 * c->height * c->axis, f.col(0), f.col(1),
                     c->axis, c->radius, c->radius);
    }
    // Side: the angles whose points can be within the window's radius of
    // its centre, and the heights along the axis within it.
    const Vec3 q = w.center - c->center;
    const double t = q.dot(c->axis);
    const Vec3 radial = q - t * c->axis;
    const double d = radial.norm();
    const double half = halfAngleNear(c->radius, d, w.radius);
    const double h0 = std::max(-0.5 * c->height, t - w.radius);
    const double h1 = std::min(0.5 * c->height, t + w.radius);
    if (half > 0.0 && h1 > h0) {
      Piece p;
      p.kind = Piece::Kind::CylinderSide;
      p.origin = c->center;
      p.frame = f;
      p.radius = c->radius;
      const double phi = std::atan2(radial.dot(f.col(1)), radial.dot(f.col(0)));
      p.angle0 = phi - half;
      p.angle1 = phi + half;
      p.height0 = h0;
      p.height1 = h1;
      p.area = c->radius * 2.0 * half * (h1 - h0);
      pieces.push_back(p);
    }
  } else if (const auto* cone = prim.as<Cone>()) {
    const Mat3 f = frameFromAxis(cone->axis);
    const double H = cone->height;
    addClippedFace(pieces, w, cone->center - 0.5 * H * cone->axis, f.col(0), f.col(1), cone->axis,
                   cone->radiusBottom, cone->radiusBottom);
    addClippedFace(pieces, w, cone->center + 0.5 * H * cone->axis, f.col(0), f.col(1), cone->axis,
                   cone->radiusTop, cone->radiusTop);
    const Vec3 q = w.center - cone->center;
    const double t = q.dot(cone->axis);
    const Vec3 radial = q - t * cone->axis;
    const double d = radial.norm();
    const double h0 = std::max(-0.5 * H, t - w.radius);
    const double h1 = std::min(0.5 * H, t + w.radius);
    const auto radiusAt = [&](double h) {
      return cone->radiusBottom + (cone->radiusTop - cone->radiusBottom) * (h / H + 0.5);
    };
    if (h1 > h0) {
      const double r0 = radiusAt(h0), r1 = radiusAt(h1);
      // The widest angle over the radii between r0 and r1: at either end
      // or where r^2 = d^2 - w^2 (the circle tangent to the window).
      double half = std::max(halfAngleNear(r0, d, w.radius), halfAngleNear(r1, d, w.radius));
      const double tangent2 = d * d - w.radius * w.radius;
      if (tangent2 > 0.0) {
        const double rt = std::sqrt(tangent2);
        if (rt > std::min(r0, r1) && rt < std::max(r0, r1)) {
          half = std::max(half, halfAngleNear(rt, d, w.radius));
        }
      }
      if (half > 0.0) {
        Piece p;
        p.kind = Piece::Kind::ConeSide;
        p.origin = cone->center;
        p.frame = f;
        p.radius = r0;
        p.radius1 = r1;
        const double phi = std::atan2(radial.dot(f.col(1)), radial.dot(f.col(0)));
        p.angle0 = phi - half;
        p.angle1 = phi + half;
        p.height0 = h0;
        p.height1 = h1;
        const double slope = (r1 - r0) / (h1 - h0);
        p.area = 2.0 * half * 0.5 * (r0 + r1) * (h1 - h0) * std::sqrt(1.0 + slope * slope);
        if (p.area > 0.0) pieces.push_back(p);
      }
    }
  } else if (const auto* sp = prim.as<Sphere>()) {
    const Vec3 q = w.center - sp->center;
    const double d = q.norm();
    Piece p;
    p.kind = Piece::Kind::SphereCap;
    p.origin = sp->center;
    p.radius = sp->radius;
    p.frame = frameFromAxis(d > 0.0 ? Vec3(q / d) : Vec3::UnitZ());
    p.cosCap = -1.0;
    if (d > 0.0) {
      p.cosCap = std::clamp(
          (sp->radius * sp->radius + d * d - w.radius * w.radius) / (2.0 * sp->radius * d), -1.0,
          1.0);
    }
    p.area = 2.0 * std::numbers::pi * sp->radius * sp->radius * (1.0 - p.cosCap);
    if (p.area > 0.0) pieces.push_back(p);
  }
  return pieces;
}

SurfaceDomain makeDomain(const Primitive& p, const Aabb& bounds) {
  SurfaceDomain d;
  d.primitive = &p;
  // A primitive within the solid's bounds (the usual case) is sampled whole.
  const Aabb own = p.bounds();
  const bool within = (own.min.array() >= bounds.min.array()).all() &&
                      (own.max.array() <= bounds.max.array()).all();
  if (!within && !p.as<HalfSpace>()) {
    const Window window{bounds.center(), 0.5 * bounds.diagonal()};
    d.pieces = piecesNear(p, window);
    if (!d.pieces.empty()) {
      for (const Piece& piece : d.pieces) d.area += piece.area;
      // Only where it saves much: most primitives are sampled as before.
      if (d.area < 0.5 * p.surfaceArea()) return d;
      d.pieces.clear();
      d.area = 0.0;
    } else if (p.as<Box>() || p.as<Cylinder>() || p.as<Cone>() || p.as<Sphere>()) {
      return d;  // its surface does not reach the solid
    }
  }
  if (const auto* h = p.as<HalfSpace>()) {
    const Mat3 frame = frameFromAxis(h->normal);
    const Vec3 onPlane = h->offset * h->normal;
    double umin = 1e300, umax = -1e300, vmin = 1e300, vmax = -1e300;
    for (int c = 0; c < 8; ++c) {
      const Vec3 corner((c & 1) ? bounds.max.x() : bounds.min.x(),
                        (c & 2) ? bounds.max.y() : bounds.min.y(),
                        (c & 4) ? bounds.max.z() : bounds.min.z());
      const double cu = (corner - onPlane).dot(frame.col(0));
      const double cv = (corner - onPlane).dot(frame.col(1));
      umin = std::min(umin, cu), umax = std::max(umax, cu);
      vmin = std::min(vmin, cv), vmax = std::max(vmax, cv);
    }
    d.origin = onPlane + umin * frame.col(0) + vmin * frame.col(1);
    d.u = (umax - umin) * frame.col(0);
    d.v = (vmax - vmin) * frame.col(1);
    d.area = (umax - umin) * (vmax - vmin);
  } else {
    d.area = p.surfaceArea();
  }
  return d;
}

// A point on the circle of radius r in the plane of `frame`'s first two axes.
Vec3 onDisc(const Mat3& frame, double r, Rng& rng) {
  const double rad = r * std::sqrt(uniform(rng));
  const double a = kTwoPi * uniform(rng);
  return rad * (std::cos(a) * frame.col(0) + std::sin(a) * frame.col(1));
}

// A uniformly distributed point on a piece.
Vec3 samplePiece(const Piece& p, Rng& rng) {
  switch (p.kind) {
    case Piece::Kind::Parallelogram:
      return p.origin + uniform(rng) * p.u + uniform(rng) * p.v;
    case Piece::Kind::CylinderSide: {
      const double a = p.angle0 + (p.angle1 - p.angle0) * uniform(rng);
      const double t = p.height0 + (p.height1 - p.height0) * uniform(rng);
      return p.origin + p.radius * (std::cos(a) * p.frame.col(0) + std::sin(a) * p.frame.col(1)) +
             t * p.frame.col(2);
    }
    case Piece::Kind::ConeSide: {
      // The area at height t grows as the radius: the radius's square is
      // uniform between the ends'.
      const double a = p.angle0 + (p.angle1 - p.angle0) * uniform(rng);
      const double r0 = p.radius, r1 = p.radius1;
      double t = p.height0 + (p.height1 - p.height0) * uniform(rng);
      if (std::abs(r1 - r0) > 1e-12 * std::max(r0, r1)) {
        const double r = std::sqrt(r0 * r0 + (r1 * r1 - r0 * r0) * uniform(rng));
        t = p.height0 + (r - r0) / (r1 - r0) * (p.height1 - p.height0);
      }
      const double r = r0 + (r1 - r0) * (t - p.height0) / (p.height1 - p.height0);
      return p.origin + r * (std::cos(a) * p.frame.col(0) + std::sin(a) * p.frame.col(1)) +
             t * p.frame.col(2);
    }
    case Piece::Kind::SphereCap: {
      // Archimedes: the height along the cap's axis is uniform.
      const double z = p.cosCap + (1.0 - p.cosCap) * uniform(rng);
      const double a = kTwoPi * uniform(rng);
      const double rho = std::sqrt(std::max(0.0, 1.0 - z * z));
      return p.origin +
             p.radius * (rho * (std::cos(a) * p.frame.col(0) + std::sin(a) * p.frame.col(1)) +
                         z * p.frame.col(2));
    }
  }
  return p.origin;
}

// A uniformly distributed point on the primitive's (clipped) surface.
Vec3 samplePoint(const SurfaceDomain& d, Rng& rng) {
  if (!d.pieces.empty()) {
    double pick = uniform(rng) * d.area;
    std::size_t k = 0;
    while (k + 1 < d.pieces.size() && pick > d.pieces[k].area) pick -= d.pieces[k++].area;
    return samplePiece(d.pieces[k], rng);
  }
  const Primitive& p = *d.primitive;
  switch (p.type()) {
    case PrimitiveType::HalfSpace:
      return d.origin + uniform(rng) * d.u + uniform(rng) * d.v;
    case PrimitiveType::Box: {
      const Box& b = *p.as<Box>();
      const Vec3& h = b.halfSize;
      const double areas[3] = {h.y() * h.z(), h.x() * h.z(), h.x() * h.y()};
      double pick = uniform(rng) * (areas[0] + areas[1] + areas[2]);
      int axis = 0;
      while (axis < 2 && pick > areas[axis]) pick -= areas[axis++];
      Vec3 local(h.x() * (2 * uniform(rng) - 1), h.y() * (2 * uniform(rng) - 1),
                 h.z() * (2 * uniform(rng) - 1));
      local[axis] = uniform(rng) < 0.5 ? -h[axis] : h[axis];
      return b.center + b.axes * local;
    }
    case PrimitiveType::Cylinder: {
      const Cylinder& c = *p.as<Cylinder>();
      const Mat3 f = frameFromAxis(c.axis);
      const double side = c.height, cap = 0.5 * c.radius;  // areas / (2 pi r)
      const double pick = uniform(rng) * (side + 2 * cap);
      if (pick < side) {
        const double a = kTwoPi * uniform(rng);
        return c.center + c.radius * (std::cos(a) * f.col(0) + std::sin(a) * f.col(1)) +
               (uniform(rng) - 0.5) * c.height * c.axis;
      }
      const double z = pick < side + cap ? -0.5 * c.height : 0.5 * c.height;
      return c.center + z * c.axis + onDisc(f, c.radius, rng);
    }
    case PrimitiveType::Cone: {
      const Cone& c = *p.as<Cone>();
      const Mat3 f = frameFromAxis(c.axis);
      const double r0 = c.radiusBottom, r1 = c.radiusTop;
      const double lateral = std::numbers::pi * (r0 + r1) * std::hypot(r0 - r1, c.height);
      const double cap0 = std::numbers::pi * r0 * r0, cap1 = std::numbers::pi * r1 * r1;
      const double pick = uniform(rng) * (lateral + cap0 + cap1);
      if (pick < lateral) {
        // Lateral area density is proportional to the local radius.
        const double rmax = std::max(r0, r1);
        double t = 0.0;
        do {
          t = uniform(rng);
        } while (uniform(rng) * rmax > r0 + (r1 - r0) * t);
        const double r = r0 + (r1 - r0) * t;
        const double a = kTwoPi * uniform(rng);
        return c.center + (t - 0.5) * c.height * c.axis +
               r * (std::cos(a) * f.col(0) + std::sin(a) * f.col(1));
      }
      if (pick < lateral + cap0) return c.center - 0.5 * c.height * c.axis + onDisc(f, r0, rng);
      return c.center + 0.5 * c.height * c.axis + onDisc(f, r1, rng);
    }
    case PrimitiveType::Sphere: {
      const Sphere& s = *p.as<Sphere>();
      std::normal_distribution<double> g;
      Vec3 dir;
      do {
        dir = Vec3(g(rng), g(rng), g(rng));
      } while (dir.norm() < 1e-12);
      return s.center + s.radius * dir.normalized();
    }
    case PrimitiveType::Torus: {
      const Torus& t = *p.as<Torus>();
      const Mat3 f = frameFromAxis(t.axis);
      const double R = t.majorRadius, r = t.minorRadius;
      double theta = 0.0;
      do {
        theta = kTwoPi * uniform(rng);
      } while (uniform(rng) * (R + r) > R + r * std::cos(theta));
      const double phi = kTwoPi * uniform(rng);
      const Vec3 radial = std::cos(phi) * f.col(0) + std::sin(phi) * f.col(1);
      return t.center + (R + r * std::cos(theta)) * radial + r * std::sin(theta) * t.axis;
    }
  }
  return Vec3::Zero();
}

struct Candidate {
  Vec3 point;
  Vec3 normal;  // outward normal of the solid (valid when accepted)
  int domain = 0;
  bool accepted = false;
};

}  // namespace

SurfaceSample sampleSurface(const CsgTree& tree, const SampleOptions& options) {
  if (tree.empty()) throw std::invalid_argument("cannot sample an empty tree");
  const Aabb bounds = tree.bounds();
  if (bounds.isEmpty()) throw std::invalid_argument("the solid is empty");
  if (!bounds.isBounded()) {
    throw std::invalid_argument("the solid is unbounded (a half-space or complement not clipped)");
  }
  if (options.points == 0) throw std::invalid_argument("the number of points must be > 0");
  if (!(options.noise >= 0.0) || !std::isfinite(options.noise)) {
    throw std::invalid_argument("noise must be a finite number >= 0");
  }
  if (options.dropPatches < 0 || !(options.patchRadius > 0.0) ||
      !std::isfinite(options.patchRadius)) {
    throw std::invalid_argument("drop patches must be >= 0 and the patch radius > 0");
  }
  const double diag = bounds.diagonal();
  const double step = 1e-6 * diag;  // probe distance across the surface
  const double onSurface = 1e-9 * diag;

  std::vector<SurfaceDomain> domains;
  for (const Node* leaf : tree.leaves()) domains.push_back(makeDomain(leaf->primitive, bounds));
  std::vector<double> cumulative;
  double totalArea = 0.0;
  for (const SurfaceDomain& d : domains) cumulative.push_back(totalArea += d.area);

  Rng rng(options.seed);
  std::vector<Vec3> patchCentres;
  const double patchR2 = std::pow(options.patchRadius * diag, 2);
  std::vector<std::size_t> tried(domains.size(), 0), kept(domains.size(), 0);
  SurfaceSample out;
  out.diagonal = diag;
  std::size_t batch = std::max<std::size_t>(4096, options.points);
  std::size_t totalTried = 0;
  const std::size_t maxTried = std::max<std::size_t>(50'000'000, 200 * options.points);
  std::vector<Candidate> cands;
  while (out.cloud.size() < options.points) {
    if (totalTried >= maxTried) {
      throw std::invalid_argument("the solid has no boundary to sample (is it empty?)");
    }
    cands.resize(batch);
    for (Candidate& c : cands) {
      const double pick = uniform(rng) * totalArea;
      c.domain =
          int(std::upper_bound(cumulative.begin(), cumulative.end(), pick) - cumulative.begin());
      c.domain = std::min<int>(c.domain, int(domains.size()) - 1);
      c.point = samplePoint(domains[c.domain], rng);
      c.accepted = false;
    }
    tbb::parallel_for(std::size_t(0), cands.size(), [&](std::size_t i) {
      Candidate& c = cands[i];
      if (!bounds.contains(c.point)) return;
      if (std::abs(tree.value(c.point)) > onSurface) return;
      const SurfaceDomain& domain = domains[c.domain];
      if (!domain.pieces.empty() && std::abs(domain.primitive->value(c.point)) > onSurface) return;
      Vec3 g;
      domains[c.domain].primitive->valueAndGradient(c.point, g);
      const double len = g.norm();
      if (!(len > 0.5)) return;  // on an edge or an axis: no well-defined normal
      const Vec3 n = -g / len;   // the primitive's outward normal
      const double ahead = tree.value(c.point + step * n);
      const double behind = tree.value(c.point - step * n);
      if (ahead < 0.0 && behind > 0.0) {
        c.normal = n;
        c.accepted = true;
      } else if (ahead > 0.0 && behind < 0.0) {
        c.normal = -n;  // a subtracted primitive: the solid lies outside it
        c.accepted = true;
      }
    });
    totalTried += cands.size();
    for (const Candidate& c : cands) ++tried[c.domain];
    // Hole centres are drawn from the first accepted points.
    if (patchCentres.empty() && options.dropPatches > 0) {
      std::vector<const Candidate*> acc;
      for (const Candidate& c : cands) {
        if (c.accepted) acc.push_back(&c);
      }
      for (int k = 0; k < options.dropPatches && !acc.empty(); ++k) {
        patchCentres.push_back(acc[std::size_t(uniform(rng) * acc.size()) % acc.size()]->point);
      }
    }
    for (const Candidate& c : cands) {
      if (!c.accepted) continue;
      ++kept[c.domain];
      bool inHole = false;
      for (const Vec3& centre : patchCentres) inHole |= (c.point - centre).squaredNorm() < patchR2;
      if (inHole || out.cloud.size() >= options.points) continue;
      out.cloud.points.push_back(c.point);
      out.cloud.normals.push_back(c.normal);
      out.source.push_back(std::uint32_t(c.domain));
    }
    // Aim the next batch at what is missing, from the acceptance seen so far.
    std::size_t keptTotal = 0;
    for (std::size_t k : kept) keptTotal += k;
    const double rate = std::max(1e-4, double(keptTotal) / double(totalTried));
    const double missing = double(options.points - std::min(options.points, out.cloud.size()));
    batch = std::clamp<std::size_t>(std::size_t(1.2 * missing / rate) + 1024, 4096, 4'000'000);
  }
  for (std::size_t i = 0; i < domains.size(); ++i) {
    if (tried[i] > 0) out.surfaceArea += domains[i].area * double(kept[i]) / double(tried[i]);
  }
  if (options.noise > 0.0) {
    std::normal_distribution<double> g(0.0, options.noise * diag);
    for (Vec3& p : out.cloud.points) p += Vec3(g(rng), g(rng), g(rng));
  }
  return out;
}

}  // namespace csgvox
