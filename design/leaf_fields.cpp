#include "design/leaf_fields.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace csgvox {
namespace {

constexpr double kDeg = 180.0 / std::numbers::pi;
const char* const kAxisLetter[3] = {"x", "y", "z"};
// A point lies on a cap (not on the side) of a cylinder or cone when its
// gradient is this close to the axis: caps' gradients are the axis itself,
// sides' are across it (a cone's tilted by its half-angle).
constexpr double kCapCosine = 0.99;

bool aligned(const Vec3& d, double tol, int& axis) {
  d.cwiseAbs().maxCoeff(&axis);
  return std::abs(d[axis]) >= std::cos(tol);
}

// The leaf's form from its frame-coordinate primitive.
void classifyLeafImpl(DesignedLeaf& leaf, const Primitive& p, double tol) {
  leaf.type = p.type();
  leaf.local = p;
  leaf.form = LeafForm::Free;
  int a = 2;
  if (const auto* b = p.as<Box>()) {
    bool all = true;
    for (int j = 0; j < 3; ++j) all = all && aligned(b->axes.col(j), tol, a);
    if (all) {
      leaf.form = LeafForm::AlignedBox;
    } else {
      for (int j = 0; j < 3; ++j) {
        if (std::abs(b->axes(2, j)) >= std::cos(tol)) leaf.form = LeafForm::TurnedBox;
      }
    }
  } else if (const auto* h = p.as<HalfSpace>()) {
    if (aligned(h->normal, tol, a)) {
      leaf.form = LeafForm::AlignedHalfSpace;
      leaf.axis = a;
      leaf.flipped = h->normal[a] < 0.0;
    } else {
      leaf.form = LeafForm::TiltedHalfSpace;
    }
  } else if (p.type() == PrimitiveType::Sphere) {
    leaf.form = LeafForm::Sphere;
  } else {
    Vec3 axis = Vec3::UnitZ();
    if (const auto* c = p.as<Cylinder>()) axis = c->axis;
    if (const auto* c = p.as<Cone>()) axis = c->axis;
    if (const auto* t = p.as<Torus>()) axis = t->axis;
    if (aligned(axis, tol, a)) {
      leaf.form = LeafForm::Axial;
      leaf.axis = a;
    }
  }
}

// The fields of a classified leaf, with their fitted values.
std::vector<LeafField> leafFieldsImpl(DesignedLeaf& leaf) {
  std::vector<LeafField> f;
  const Primitive& p = leaf.local;
  const int a = leaf.axis;
  const auto pos = [&](Expression& e, int axis, const std::string& name, double v, bool cross) {
    f.push_back({&e, positionAlong(axis), name, v, cross, axis});
  };
  switch (leaf.form) {
    case LeafForm::AlignedBox: {
      const Box& b = *p.as<Box>();
      for (int j = 0; j < 3; ++j) {
        int k = 0;
        aligned(b.axes.col(j), 1.0, k);
        const std::string l = kAxisLetter[k];
        pos(leaf.lo[std::size_t(k)], k, l + "0", b.center[k] - b.halfSize[j], false);
        pos(leaf.hi[std::size_t(k)], k, l + "1", b.center[k] + b.halfSize[j], false);
      }
      break;
    }
    case LeafForm::TurnedBox: {
      const Box& b = *p.as<Box>();
      int j = 0;
      b.axes.row(2).cwiseAbs().maxCoeff(&j);
      const int u = (j + 1) % 3, w = (j + 2) % 3;  // its own x and y, right-handed about z
      Vec3 ax = b.axes.col(u);
      double width = 2 * b.halfSize[u], depth = 2 * b.halfSize[w];
      if (b.axes(2, j) < 0) std::swap(width, depth), ax = b.axes.col(w);
      double turn = std::atan2(ax.y(), ax.x()) * kDeg;
      // The turn in (-45, 45]: a quarter turn swaps the sizes.
      while (turn > 45.0) turn -= 90.0, std::swap(width, depth);
      while (turn <= -45.0) turn += 90.0, std::swap(width, depth);
      pos(leaf.at[0], 0, "x", b.center.x(), false);
      pos(leaf.at[1], 1, "y", b.center.y(), false);
      pos(leaf.lo[2], 2, "z0", b.center.z() - b.halfSize[j], false);
      pos(leaf.hi[2], 2, "z1", b.center.z() + b.halfSize[j], false);
      f.push_back({&leaf.radius, ValueCategory::Step, "width", width});
      f.push_back({&leaf.radius2, ValueCategory::Step, "depth", depth});
      f.push_back({&leaf.angle, ValueCategory::Angle, "turn", turn});
      break;
    }
    case LeafForm::Axial: {
      Vec3 c;
      double h = 0.0;
      if (const auto* s = p.as<Cylinder>()) c = s->center, h = s->height;
      if (const auto* s = p.as<Cone>()) c = s->center, h = s->height;
      if (const auto* s = p.as<Torus>()) c = s->center;
      for (int k = 0; k < 3; ++k) {
        if (k != a) pos(leaf.at[std::size_t(k)], k, kAxisLetter[k], c[k], true);
      }
      const std::string l = kAxisLetter[a];
      if (const auto* t = p.as<Torus>()) {
        pos(leaf.at[std::size_t(a)], a, l, c[a], false);
        f.push_back({&leaf.radius, ValueCategory::Radius, "major_r", t->majorRadius});
        f.push_back({&leaf.radius2, ValueCategory::Radius, "minor_r", t->minorRadius});
        break;
      }
      pos(leaf.lo[std::size_t(a)], a, l + "0", c[a] - 0.5 * h, false);
      pos(leaf.hi[std::size_t(a)], a, l + "1", c[a] + 0.5 * h, false);
      if (const auto* s = p.as<Cylinder>()) {
        f.push_back({&leaf.radius, ValueCategory::Radius, "r", s->radius});
      } else if (const auto* s = p.as<Cone>()) {
        const bool up = s->axis[a] > 0.0;
        f.push_back(
            {&leaf.radius, ValueCategory::Radius, "r0", up ? s->radiusBottom : s->radiusTop});
        f.push_back(
            {&leaf.radius2, ValueCategory::Radius, "r1", up ? s->radiusTop : s->radiusBottom});
      }
      break;
    }
    case LeafForm::Sphere: {
      const auto& s = *p.as<Sphere>();
      for (int k = 0; k < 3; ++k)
        pos(leaf.at[std::size_t(k)], k, kAxisLetter[k], s.center[k], k < 2);
      f.push_back({&leaf.radius, ValueCategory::Radius, "r", s.radius});
      break;
    }
    case LeafForm::AlignedHalfSpace: {
      const auto& h = *p.as<HalfSpace>();
      const std::string l = kAxisLetter[a];
      if (leaf.flipped) {
        pos(leaf.lo[std::size_t(a)], a, l + "0", -h.offset, false);
      } else {
        pos(leaf.hi[std::size_t(a)], a, l + "1", h.offset, false);
      }
      break;
    }
    case LeafForm::TiltedHalfSpace: {
      const auto& h = *p.as<HalfSpace>();
      const double tilt = std::acos(std::clamp(h.normal.z(), -1.0, 1.0)) * kDeg;
      const double turn = std::atan2(h.normal.y(), h.normal.x()) * kDeg;
      f.push_back({&leaf.radius, ValueCategory::Step, "offset", h.offset});
      f.push_back({&leaf.angle, ValueCategory::Angle, "tilt", tilt});
      f.push_back({&leaf.angle2, ValueCategory::Angle, "turn", turn});
      break;
    }
    case LeafForm::Free:
      break;
  }
  return f;
}

}  // namespace

void classifyLeaf(DesignedLeaf& leaf, const Primitive& primitive, double tolerance) {
  classifyLeafImpl(leaf, primitive, tolerance);
}

std::vector<LeafField> leafFields(DesignedLeaf& leaf) { return leafFieldsImpl(leaf); }

// Points supporting each field of a leaf (indices as fieldsOf()), from the
// local gradients of the points on it.
std::vector<double> fieldSupport(const DesignedLeaf& leaf, const std::vector<LeafField>& fields,
                                 const std::vector<Vec3>& gradients) {
  std::vector<double> n(fields.size(), 0.0);
  const auto add = [&](const Expression* e) {
    for (std::size_t i = 0; i < fields.size(); ++i) {
      if (fields[i].expression == e) n[i] += 1.0;
    }
  };
  const auto addAll = [&]() {
    for (double& x : n) x += 1.0;
  };
  for (const Vec3& g : gradients) {
    const int a = leaf.axis;
    switch (leaf.form) {
      case LeafForm::AlignedBox: {
        int k = 0;
        g.cwiseAbs().maxCoeff(&k);
        add(g[k] > 0.0 ? &leaf.lo[std::size_t(k)] : &leaf.hi[std::size_t(k)]);
        break;
      }
      case LeafForm::TurnedBox:
        if (std::abs(g.z()) > kCapCosine) {
          add(g.z() > 0.0 ? &leaf.lo[2] : &leaf.hi[2]);
        } else {
          add(&leaf.at[0]), add(&leaf.at[1]), add(&leaf.radius), add(&leaf.radius2),
              add(&leaf.angle);
        }
        break;
      case LeafForm::Axial:
        if (leaf.type != PrimitiveType::Torus && std::abs(g[a]) > kCapCosine) {
          add(g[a] > 0.0 ? &leaf.lo[std::size_t(a)] : &leaf.hi[std::size_t(a)]);
        } else if (leaf.type == PrimitiveType::Torus) {
          addAll();
        } else {
          for (int k = 0; k < 3; ++k) {
            if (k != a) add(&leaf.at[std::size_t(k)]);
          }
          add(&leaf.radius);
          add(&leaf.radius2);
        }
        break;
      default:
        addAll();
    }
  }
  return n;
}

std::vector<std::vector<double>> fieldOffsets(const DesignedLeaf& leaf,
                                              const std::vector<LeafField>& fields,
                                              const std::vector<Vec3>& points,
                                              const std::vector<Vec3>& gradients) {
  std::vector<std::vector<double>> out(fields.size());
  const auto add = [&](const Expression* e, double offsetFromPoint) {
    for (std::size_t i = 0; i < fields.size(); ++i) {
      if (fields[i].expression == e) out[i].push_back(offsetFromPoint - fields[i].value);
    }
  };
  const int a = leaf.axis;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Vec3& g = gradients[i];
    const Vec3& p = points[i];
    if (leaf.form == LeafForm::AlignedBox) {
      int k = 0;
      g.cwiseAbs().maxCoeff(&k);
      add(g[k] > 0.0 ? &leaf.lo[std::size_t(k)] : &leaf.hi[std::size_t(k)], p[k]);
    } else if (leaf.form == LeafForm::Axial && leaf.type != PrimitiveType::Torus) {
      if (std::abs(g[a]) > kCapCosine) {
        add(g[a] > 0.0 ? &leaf.lo[std::size_t(a)] : &leaf.hi[std::size_t(a)], p[a]);
      } else if (const auto* c = leaf.local.as<Cylinder>()) {
        const Vec3 q = p - c->center;
        add(&leaf.radius, (q - q.dot(c->axis) * c->axis).norm());
      }
    }
  }
  return out;
}

// A cone's cap that no point holds can slide along the cone: moved to the
// nearest whole unit along the axis (its radius following the slope), its
// numbers become the ones the cone was drawn with when it was drawn there.
void slideFreeConeCaps(const DesignedLeaf& leaf, std::vector<LeafField>& fields,
                       const std::vector<double>& support, const ApexReach& reach) {
  if (leaf.form != LeafForm::Axial || leaf.type != PrimitiveType::Cone) return;
  const auto find = [&](const Expression* e) {
    for (std::size_t k = 0; k < fields.size(); ++k) {
      if (fields[k].expression == e) return k;
    }
    return fields.size();
  };
  const std::size_t lo = find(&leaf.lo[std::size_t(leaf.axis)]),
                    hi = find(&leaf.hi[std::size_t(leaf.axis)]), r0 = find(&leaf.radius),
                    r1 = find(&leaf.radius2);
  if (hi >= fields.size() || r1 >= fields.size()) return;
  const double z0 = fields[lo].value, z1 = fields[hi].value;
  const double slope = (fields[r1].value - fields[r0].value) / (z1 - z0);
  const auto slide = [&](std::size_t z, std::size_t r) {
    if (support[z] > 0.0) return;
    const double to = std::round(fields[z].value);
    const double radius = fields[r].value + slope * (to - fields[z].value);
    if (!(radius >= 0.0)) return;
    fields[z].value = to;
    fields[r].value = radius;
  };
  slide(lo, r0);
  slide(hi, r1);
  if (!(fields[hi].value > fields[lo].value)) {  // undo: the cone would vanish
    fields[lo].value = z0;
    fields[hi].value = z1;
    fields[r0].value = fields[r1].value - slope * (z1 - z0);
    return;
  }
  // A narrow cap short of the apex (a fit stops a point's tip where its
  // points thin out) runs on to it when within `reach`: the cone was drawn
  // to a point.
  const auto toApex = [&](std::size_t z, std::size_t r, double away) {
    const double radius = fields[r].value;
    if (!(radius > 0.0) || radius > reach.radius || away * slope >= 0.0) return;
    const double run = radius / std::abs(slope);
    if (run > reach.length) return;
    fields[z].value += away * run;
    fields[r].value = 0.0;
  };
  if (fields[r0].value <= fields[r1].value) {
    toApex(lo, r0, -1.0);
  } else {
    toApex(hi, r1, +1.0);
  }
}

}  // namespace csgvox
