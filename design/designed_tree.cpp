#include "design/designed_tree.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <numbers>
#include <optional>
#include <set>
#include <stdexcept>

#include "core/decimal.h"
#include "core/export_cutters.h"
#include "core/export_extent.h"
#include "core/seed.h"
#include "design/leaf_fields.h"
#include "design/pattern_detection.h"
#include "design/point_support.h"
#include "design/role_names.h"

namespace csgvox {
namespace {

constexpr double kDeg = 180.0 / std::numbers::pi;
constexpr double kInf = std::numeric_limits<double>::infinity();
const char* const kAxisLetter[3] = {"x", "y", "z"};
// Points this near a leaf (fraction of the part's diagonal) say where its
// faces lie, and how many of them at least.
constexpr double kNearBand = 0.01;
constexpr std::size_t kLeastOffsets = 3;
// Caps of adding primitives that face each other this near (fraction of
// the part's diagonal) meet (as tree.step's builder snaps them).
constexpr double kMeetTolerance = 0.00125;
// One value of the fitted tree before grouping.
struct Slot {
  ValueCategory category = ValueCategory::Step;
  double value = 0.0;
  double support = 0.0;         // points holding it (kInf: exact, e.g. a count)
  double lever = 1.0;           // Angle: radius the angle is read at (its uncertainty is u / lever)
  std::string name;             // owner_field
  std::set<int> leaves;         // designed leaves using it
  std::string owner;            // a pattern's name, when a pattern owns it
  std::vector<double> offsets;  // how far each point near its face would move it
};

std::string plural(const std::string& role, int n) {
  if (n == 1) return "1 " + role;
  if (!role.empty() && (role.back() == 's' || role.back() == 'h'))
    return std::to_string(n) + " " + role + "es";
  return std::to_string(n) + " " + role + "s";
}

// The grid the IoU against the fitted tree is measured on, and the fitted
// tree's inside flags on it. One point per cell, at a fixed random place in
// it (stratified sampling): at cell centres a face parallel to the grid, as
// the frame makes most faces, flips whole layers or nothing as it moves, so
// a snap that moves it by a third of a cell would count as no change.
struct IouGrid {
  std::vector<Vec3> points;
  std::vector<char> fittedInside;
  int fittedCount = 0;
};

IouGrid iouGrid(const CsgTree& local, int resolution) {
  IouGrid g;
  const Aabb e = exportExtent(local);
  const Aabb box = e.grown(0.01 * e.diagonal());
  const double cell = box.size().maxCoeff() / std::max(resolution, 4);
  const Vec3 size = box.size();
  const int nx = std::max(1, int(std::ceil(size.x() / cell)));
  const int ny = std::max(1, int(std::ceil(size.y() / cell)));
  const int nz = std::max(1, int(std::ceil(size.z() / cell)));
  g.points.reserve(std::size_t(nx) * ny * nz);
  const auto unit = [](std::uint64_t bits) { return double(bits >> 11) * 0x1.0p-53; };
  std::uint64_t index = 0;
  for (int i = 0; i < nx; ++i)
    for (int j = 0; j < ny; ++j)
      for (int k = 0; k < nz; ++k, ++index) {
        const std::uint64_t a = mixSeed(index, 0), b = mixSeed(index, 1), c = mixSeed(index, 2);
        g.points.push_back(box.min + cell * Vec3(i + unit(a), j + unit(b), k + unit(c)));
      }
  std::vector<double> f(g.points.size());
  local.values(g.points, f);
  g.fittedInside.resize(f.size());
  for (std::size_t i = 0; i < f.size(); ++i) {
    g.fittedInside[i] = f[i] >= 0.0;
    g.fittedCount += g.fittedInside[i];
  }
  return g;
}

bool validPrimitive(const Primitive& p) {
  try {
    p.validate();
  } catch (const std::invalid_argument&) {
    return false;
  }
  return true;
}

}  // namespace

namespace {

// Builds the designed tree; the parts of designTree() in order.
class Designer {
 public:
  Designer(const CsgTree& fitted, const PartFrame& frame, std::span<const Vec3> points,
           const DesignOptions& options)
      : options_(options), points_(points) {
    d_.fitted = fitted;
    d_.frame = frame;
    local_ = treeInFrame(fitted, frame);
    localPoints_.reserve(points.size());
    for (const Vec3& p : points) localPoints_.push_back(frame.toLocal(p));
    diagonal_ = exportExtent(local_).diagonal();
  }

  // `reshape`: find patterns and slide free cone caps (kept only when the
  // tree keeps its shape with them).
  DesignedTree run(bool reshape = true) {
    slide_ = reshape;
    makeLeaves();
    if (reshape) findLeafPatterns();
    makeSlots();
    if (reshape) joinMeetingCaps();
    groupSlots();
    prepare();
    if (reshape && !keepsShape()) {
      return Designer(d_.fitted, d_.frame, points_, options_).run(false);
    }
    chooseUnits();
    if (options_.snap) snap();
    measureDatumOffset();
    mergeEqualSnapped();
    nameParameters();
    measure();
    return std::move(d_);
  }

 private:
  void makeLeaves() {
    const std::vector<const Node*> world = d_.fitted.distinctLeaves();
    const std::vector<const Node*> local = local_.distinctLeaves();
    const LeafRoles roles = leafRoles(d_.fitted);
    d_.leaves.resize(world.size());
    std::map<std::string, int> roleCount, roleSeen;
    for (std::size_t i = 0; i < world.size(); ++i) {
      DesignedLeaf& l = d_.leaves[i];
      l.node = world[i];
      localIndex_[local[i]] = int(i);
      l.cuts = roles.removing.count(world[i]) > 0;
      l.adds = roles.adding.count(world[i]) > 0 || !l.cuts;
      l.role = roleName(local[i]->primitive, l.cuts && !l.adds, diagonal_);
      classifyLeaf(l, local[i]->primitive, options_.alignTolerance);
      ++roleCount[l.role];
    }
    for (DesignedLeaf& l : d_.leaves) {
      l.name = roleCount[l.role] == 1 ? l.role : l.role + "_" + std::to_string(++roleSeen[l.role]);
    }
    // Points on each leaf, with their local gradients.
    gradients_.resize(d_.leaves.size());
    near_.resize(d_.leaves.size());
    nearGradients_.resize(d_.leaves.size());
    if (!localPoints_.empty()) {
      const PointSupport support = pointSupport(local_, localPoints_);
      d_.noise = support.noise;
      for (std::size_t i = 0; i < localPoints_.size(); ++i) {
        if (support.leaf[i])
          gradients_[std::size_t(localIndex_.at(support.leaf[i]))].push_back(support.gradient[i]);
      }
      // The points near each leaf, also those a fit left a little off it:
      // where they all lie off one face, the face is off (see refitted()).
      SupportOptions wide;
      wide.leastBand = kNearBand * diagonal_;
      const PointSupport nearSupport = pointSupport(local_, localPoints_, wide);
      for (std::size_t i = 0; i < localPoints_.size(); ++i) {
        if (!nearSupport.leaf[i]) continue;
        const std::size_t leaf = std::size_t(localIndex_.at(nearSupport.leaf[i]));
        near_[leaf].push_back(localPoints_[i]);
        nearGradients_[leaf].push_back(nearSupport.gradient[i]);
      }
    }
  }

  // Sibling leaves on the same side of one operation, used once each.
  void findLeafPatterns() {
    std::map<const Node*, int> uses;
    for (const Node* leaf : local_.leaves()) ++uses[leaf];
    std::vector<std::vector<int>> groups;
    std::vector<const Node*> stack = {local_.root().get()};
    while (!stack.empty()) {
      const Node* n = stack.back();
      stack.pop_back();
      if (n->kind == NodeKind::Primitive) continue;
      std::vector<int> first, rest;
      for (std::size_t i = 0; i < n->children.size(); ++i) {
        const Node* c = n->children[i].get();
        if (c->kind != NodeKind::Primitive) {
          stack.push_back(c);
          continue;
        }
        if (uses[c] != 1) continue;
        const int index = localIndex_.at(c);
        if (d_.leaves[std::size_t(index)].form == LeafForm::Free) continue;
        (n->kind == NodeKind::Difference && i == 0 ? first : rest).push_back(index);
      }
      groups.push_back(first);
      groups.push_back(rest);
    }
    PatternOptions po;
    po.tolerance = options_.patternTolerance * diagonal_;
    for (const auto& group : groups) {
      if (group.size() < 2) continue;
      std::vector<PatternCandidate> prims;
      for (int i : group) prims.push_back({d_.leaves[std::size_t(i)].local, looseCaps(i)});
      for (const FoundPattern& f : findPatterns(prims, po)) {
        found_.push_back(f);
        for (int& m : found_.back().members) m = group[std::size_t(m)];
      }
    }
    // Tree order of their first members.
    std::sort(found_.begin(), found_.end(), [](const FoundPattern& a, const FoundPattern& b) {
      return *std::min_element(a.members.begin(), a.members.end()) <
             *std::min_element(b.members.begin(), b.members.end());
    });
  }

  // When a cone's narrow cap runs on to its apex: its radius within twice
  // the noise or 0.5 % of the part's diagonal (a tip that thin has too few
  // points for the fit to reach it), the tip it adds at most 2 % of it.
  ApexReach apexReach() const {
    return {std::max(0.005 * diagonal_, 2.0 * d_.noise), 0.02 * diagonal_};
  }

  // The radius an angle of the leaf is read at: half a turned box's width.
  double leverOf(const DesignedLeaf& l) const {
    if (l.form == LeafForm::TiltedHalfSpace) return 0.5 * diagonal_;
    if (l.form != LeafForm::TurnedBox) return 1.0;
    const Box& b = *l.local.as<Box>();
    return std::max(b.halfSize.maxCoeff(), 1e-12);
  }

  // A cylinder that only cuts: its length is compared with no other (a
  // hole's ends past the part are free; a pattern whose members' caps differ
  // where it matters fails the shape test and is dropped).
  bool looseCaps(int i) const {
    const DesignedLeaf& l = d_.leaves[std::size_t(i)];
    return l.type == PrimitiveType::Cylinder && l.form == LeafForm::Axial && !l.adds && l.cuts;
  }

  int addSlot(ValueCategory c, double value, double support, const std::string& name, int leaf,
              double lever = 1.0) {
    Slot s;
    s.category = c;
    s.value = value;
    s.support = support;
    s.lever = lever;
    s.name = name;
    if (leaf >= 0) s.leaves.insert(leaf);
    slots_.push_back(s);
    return int(slots_.size()) - 1;
  }

  void makeSlots() {
    std::vector<int> patternOf(d_.leaves.size(), -1);
    for (std::size_t p = 0; p < found_.size(); ++p) {
      for (int m : found_[p].members) patternOf[std::size_t(m)] = int(p);
    }
    std::vector<char> done(d_.leaves.size(), 0);
    for (std::size_t i = 0; i < d_.leaves.size(); ++i) {
      if (done[i]) continue;
      if (patternOf[i] >= 0) {
        makePatternSlots(found_[std::size_t(patternOf[i])]);
        for (int m : found_[std::size_t(patternOf[i])].members) done[std::size_t(m)] = 1;
        continue;
      }
      DesignedLeaf& l = d_.leaves[i];
      std::vector<LeafField> fields = leafFields(l);
      const std::vector<double> n = fieldSupport(l, fields, gradients_[i]);
      if (!localPoints_.empty() && slide_) slideFreeConeCaps(l, fields, n, apexReach());
      const auto offsets = fieldOffsets(l, fields, near_[i], nearGradients_[i]);
      for (std::size_t k = 0; k < fields.size(); ++k) {
        const int slot = addSlot(fields[k].category, fields[k].value, n[k],
                                 l.name + "_" + fields[k].name, int(i), leverOf(l));
        slots_[std::size_t(slot)].offsets = offsets[k];
        *fields[k].expression = Expression::of(slot);
      }
    }
  }

  void makePatternSlots(const FoundPattern& f) {
    // Members named in the pattern's order (the names they had, sorted).
    {
      std::vector<std::string> names;
      for (int m : f.members) names.push_back(d_.leaves[std::size_t(m)].name);
      std::sort(names.begin(), names.end(), [](const std::string& a, const std::string& b) {
        return a.size() != b.size() ? a.size() < b.size() : a < b;
      });
      for (std::size_t i = 0; i < names.size(); ++i) {
        d_.leaves[std::size_t(f.members[i])].name = names[i];
      }
    }
    DesignedPattern p;
    const DesignedLeaf& first = d_.leaves[std::size_t(f.members.front())];
    p.kind = f.kind == FoundPatternKind::Circular  ? PatternKind::Circular
             : f.kind == FoundPatternKind::Lattice ? PatternKind::Lattice
                                                   : PatternKind::Row;
    const std::string base = first.role == "hole" ? "bolt" : first.role;
    p.name = base + (p.kind == PatternKind::Circular  ? "_circle"
                     : p.kind == PatternKind::Lattice ? "_grid"
                                                      : "_row");
    for (const DesignedPattern& other : d_.patterns) {
      if (other.name == p.name) p.name += "_" + std::to_string(d_.patterns.size() + 1);
    }
    p.members = f.members;
    const int index = int(d_.patterns.size());
    const int n = int(f.members.size());
    // Member fields: one slot each, the members' mean (positions less their
    // offsets in the pattern), supported by every member's points.
    std::vector<std::vector<LeafField>> fields;
    std::vector<std::vector<double>> support;
    std::vector<std::vector<std::vector<double>>> offsets;
    for (int m : f.members) {
      const DesignedLeaf& l = d_.leaves[std::size_t(m)];
      fields.push_back(leafFields(d_.leaves[std::size_t(m)]));
      support.push_back(fieldSupport(l, fields.back(), gradients_[std::size_t(m)]));
      if (!localPoints_.empty() && slide_) {
        slideFreeConeCaps(l, fields.back(), support.back(), apexReach());
      }
      offsets.push_back(
          fieldOffsets(l, fields.back(), near_[std::size_t(m)], nearGradients_[std::size_t(m)]));
    }
    double crossSupport = 0.0;
    std::array<double, 3> stepSupport = {0.0, 0.0, 0.0};  // points placing the members per axis
    for (std::size_t k = 0; k < fields.front().size(); ++k) {
      const LeafField& f0 = fields.front()[k];
      double sum = 0.0, n_k = 0.0;
      for (int i = 0; i < n; ++i) {
        double value = fields[std::size_t(i)][k].value;
        if (f.kind != FoundPatternKind::Circular && f0.positionAxis >= 0) {
          const int a = f0.positionAxis;
          const int ii = i % f.count, jj = i / f.count;
          value -= ii * f.step[a] + jj * f.step2[a];
        }
        sum += value;
        n_k += support[std::size_t(i)][k];
      }
      if (f0.positionAxis >= 0) {
        stepSupport[std::size_t(f0.positionAxis)] =
            std::max(stepSupport[std::size_t(f0.positionAxis)], n_k);
      }
      if (f.kind == FoundPatternKind::Circular && f0.crossPosition) {
        crossSupport += n_k / 2;
        continue;  // placed by the pattern
      }
      const int s =
          addSlot(f0.category, sum / n, n_k, first.name + "_" + f0.name, f.members.front());
      for (int m : f.members) slots_[std::size_t(s)].leaves.insert(m);
      for (int i = 0; i < n; ++i) {
        const std::vector<double>& o = offsets[std::size_t(i)][k];
        slots_[std::size_t(s)].offsets.insert(slots_[std::size_t(s)].offsets.end(), o.begin(),
                                              o.end());
      }
      for (int i = 0; i < n; ++i) *fields[std::size_t(i)][k].expression = Expression::of(s);
    }
    const auto own = [&](int slot) {
      slots_[std::size_t(slot)].owner = p.name;
      return Expression::of(slot);
    };
    p.count = addSlot(ValueCategory::Count, f.count, kInf, p.name + "_count", -1);
    slots_[std::size_t(p.count)].owner = p.name;
    if (p.kind == PatternKind::Circular) {
      p.centerX =
          own(addSlot(ValueCategory::PositionX, f.center.x(), crossSupport, p.name + "_x", -1));
      p.centerY =
          own(addSlot(ValueCategory::PositionY, f.center.y(), crossSupport, p.name + "_y", -1));
      p.radius = own(addSlot(ValueCategory::Step, f.radius, crossSupport, p.name + "_r", -1));
      p.phase = own(
          addSlot(ValueCategory::Angle, f.phase, crossSupport, p.name + "_phase", -1, f.radius));
    } else {
      for (int a = 0; a < 3; ++a) {
        const double tol = options_.patternTolerance * diagonal_;
        if (std::abs(f.step[a]) > tol) {
          p.step[std::size_t(a)] =
              own(addSlot(ValueCategory::Step, f.step[a], stepSupport[std::size_t(a)],
                          p.name + "_d" + kAxisLetter[a], -1));
        }
        if (std::abs(f.step2[a]) > tol) {
          p.step2[std::size_t(a)] =
              own(addSlot(ValueCategory::Step, f.step2[a], stepSupport[std::size_t(a)],
                          p.name + "_d" + kAxisLetter[a], -1));
        }
      }
      if (p.kind == PatternKind::Lattice) {
        p.count2 = addSlot(ValueCategory::Count, f.count2, kInf, p.name + "_count2", -1);
        slots_[std::size_t(p.count2)].owner = p.name;
      }
    }
    for (int i = 0; i < n; ++i) {
      DesignedLeaf& l = d_.leaves[std::size_t(f.members[std::size_t(i)])];
      l.pattern = index;
      l.member = i;
    }
    d_.patterns.push_back(p);
  }

  // The slot an expression is, or -1 (a pattern's member is placed by
  // several).
  static int slotOf(const Expression& e) {
    return e.terms.size() == 1 && e.terms.front().first == 1.0 ? e.terms.front().second : -1;
  }

  // Caps of two primitives that add material, facing each other across a
  // gap narrower than kMeetTolerance of D with overlapping cross-sections
  // (a shaft's chamfer cone and its body, fitted 0.07 apart), meet: both
  // take their supports' weighted mean, so they become one parameter and
  // the solid one piece (exact booleans, as FreeCAD's, leave the sliver
  // between two solids).
  void joinMeetingCaps() {
    const double tol = kMeetTolerance * diagonal_;
    for (std::size_t i = 0; i < d_.leaves.size(); ++i) {
      const DesignedLeaf& a = d_.leaves[i];
      if (a.cuts || a.pattern >= 0 || !meetsByCaps(a)) continue;
      for (std::size_t j = 0; j < d_.leaves.size(); ++j) {
        const DesignedLeaf& b = d_.leaves[j];
        if (j == i || b.cuts || b.pattern >= 0 || !meetsByCaps(b)) continue;
        for (int axis = 0; axis < 3; ++axis) {
          const int top = slotOf(a.hi[std::size_t(axis)]), bottom = slotOf(b.lo[std::size_t(axis)]);
          if (top < 0 || bottom < 0) continue;
          Slot &below = slots_[std::size_t(top)], &above = slots_[std::size_t(bottom)];
          const double gap = above.value - below.value;
          if (!(gap > 0.0 && gap <= tol) || !crossSectionsOverlap(a, b, axis)) continue;
          const double w0 = below.support + 1.0, w1 = above.support + 1.0;
          below.value = above.value = (w0 * below.value + w1 * above.value) / (w0 + w1);
        }
      }
    }
  }

  static bool meetsByCaps(const DesignedLeaf& l) {
    return l.form == LeafForm::AlignedBox ||
           (l.form == LeafForm::Axial && l.type != PrimitiveType::Torus);
  }

  static bool crossSectionsOverlap(const DesignedLeaf& a, const DesignedLeaf& b, int axis) {
    const Aabb x = a.local.bounds(), y = b.local.bounds();
    for (int k = 0; k < 3; ++k) {
      if (k != axis && (x.max[k] <= y.min[k] || y.max[k] <= x.min[k])) return false;
    }
    return true;
  }

  // Slots of one category within groupTolerance become one parameter.
  void groupSlots() {
    const double tol = options_.groupTolerance * diagonal_;
    std::vector<int> order(slots_.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = int(i);
    std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
      const Slot &x = slots_[std::size_t(a)], &y = slots_[std::size_t(b)];
      if (x.category != y.category) return x.category < y.category;
      return x.value < y.value;
    });
    std::vector<int> paramOf(slots_.size(), -1);
    std::vector<std::vector<int>> members;
    for (std::size_t k = 0; k < order.size(); ++k) {
      const Slot& s = slots_[std::size_t(order[k])];
      const bool joins = k > 0 && s.category != ValueCategory::Count &&
                         s.category != ValueCategory::Step &&
                         slots_[std::size_t(order[k - 1])].category == s.category &&
                         s.value - slots_[std::size_t(order[k - 1])].value <= tol;
      if (!joins) members.emplace_back();
      members.back().push_back(order[k]);
    }
    // Parameters in order of their first slot (tree order).
    std::sort(members.begin(), members.end(), [](const auto& a, const auto& b) {
      return *std::min_element(a.begin(), a.end()) < *std::min_element(b.begin(), b.end());
    });
    for (auto& group : members) {
      std::sort(group.begin(), group.end());
      const int index = int(d_.parameters.size());
      DesignParameter p;
      const Slot& first = slots_[std::size_t(group.front())];
      p.name = first.name;
      p.kind = first.category == ValueCategory::Angle   ? ParameterKind::Angle
               : first.category == ValueCategory::Count ? ParameterKind::Count
                                                        : ParameterKind::Length;
      double sum = 0.0, support = 0.0;
      Slot merged = first;
      for (int s : group) {
        sum += slots_[std::size_t(s)].value;
        support += slots_[std::size_t(s)].support;
        paramOf[std::size_t(s)] = index;
        merged.leaves.insert(slots_[std::size_t(s)].leaves.begin(),
                             slots_[std::size_t(s)].leaves.end());
        if (s != group.front()) {
          merged.offsets.insert(merged.offsets.end(), slots_[std::size_t(s)].offsets.begin(),
                                slots_[std::size_t(s)].offsets.end());
        }
      }
      p.fitted = sum / double(group.size());
      p.value = p.fitted;
      p.uncertainty = uncertainty(support, first.lever, p.kind);
      if (p.kind == ParameterKind::Length && !std::isfinite(p.uncertainty) &&
          merged.offsets.size() >= kLeastOffsets && !localPoints_.empty()) {
        // No point within the noise band, some near (a face a fit left off
        // its points): they hold it, as tightly as they agree.
        p.uncertainty = options_.confidence * std::max(spread(merged.offsets), d_.noise) /
                        std::sqrt(double(merged.offsets.size()));
      }
      merged.support = support;
      d_.parameters.push_back(p);
      paramSlots_.push_back(merged);
    }
    remap(paramOf);
  }

  double uncertainty(double support, double lever, ParameterKind kind) const {
    if (kind == ParameterKind::Count) return 0.0;
    double u = 0.0;
    if (localPoints_.empty()) {
      u = options_.treeUncertainty * diagonal_;
    } else {
      u = support > 0.0 ? options_.confidence * d_.noise / std::sqrt(support) : kInf;
      u = std::max(u, 1e-9 * diagonal_);
    }
    return kind == ParameterKind::Angle ? u / std::max(lever, 1e-12) * kDeg : u;
  }

  // Rewrites every expression through `map` (old index -> new index).
  void remap(const std::vector<int>& map) {
    const auto fix = [&](Expression& e) {
      for (auto& t : e.terms) t.second = map[std::size_t(t.second)];
      // Terms on one parameter add up.
      std::map<int, double> sum;
      for (const auto& t : e.terms) sum[t.second] += t.first;
      if (sum.size() != e.terms.size()) {
        e.terms.clear();
        for (const auto& [p, c] : sum) {
          if (c != 0.0) e.terms.emplace_back(c, p);
        }
      }
    };
    for (DesignedLeaf& l : d_.leaves) {
      for (auto* arr : {&l.lo, &l.hi, &l.at}) {
        for (Expression& e : *arr) fix(e);
      }
      fix(l.radius);
      fix(l.radius2);
      fix(l.angle);
      fix(l.angle2);
    }
    for (DesignedPattern& p : d_.patterns) {
      for (Expression* e : {&p.centerX, &p.centerY, &p.radius, &p.phase}) fix(*e);
      for (auto* arr : {&p.step, &p.step2}) {
        for (Expression& e : *arr) fix(e);
      }
      if (p.count >= 0) p.count = map[std::size_t(p.count)];
      if (p.count2 >= 0) p.count2 = map[std::size_t(p.count2)];
    }
  }

  void chooseUnits() {
    int mm = 0, inch = 0;
    for (const DesignParameter& p : d_.parameters) {
      if (p.kind != ParameterKind::Length || !std::isfinite(p.uncertainty)) continue;
      if (const auto v = simplestLength(p.fitted, p.uncertainty, UnitSystem::Millimetre)) {
        mm += ladderRung(*v, UnitSystem::Millimetre) <= 1;
      }
      if (const auto v = simplestLength(p.fitted, p.uncertainty, UnitSystem::Inch)) {
        inch += ladderRung(*v, UnitSystem::Inch) <= 4;
      }
    }
    d_.units = inch > mm ? UnitSystem::Inch : UnitSystem::Millimetre;
  }

  // The leaves whose primitives depend on parameter p.
  std::set<int> leavesOf(int p) const {
    std::set<int> out;
    const auto uses = [&](const Expression& e) {
      return std::any_of(e.terms.begin(), e.terms.end(),
                         [&](const auto& t) { return t.second == p; });
    };
    for (std::size_t i = 0; i < d_.leaves.size(); ++i) {
      const DesignedLeaf& l = d_.leaves[i];
      bool u = uses(l.radius) || uses(l.radius2) || uses(l.angle) || uses(l.angle2);
      for (int k = 0; k < 3; ++k) u = u || uses(l.lo[k]) || uses(l.hi[k]) || uses(l.at[k]);
      if (l.pattern >= 0) {
        const DesignedPattern& pat = d_.patterns[std::size_t(l.pattern)];
        u = u || uses(pat.centerX) || uses(pat.centerY) || uses(pat.radius) || uses(pat.phase) ||
            pat.count == p || pat.count2 == p;
        for (int k = 0; k < 3; ++k) u = u || uses(pat.step[k]) || uses(pat.step2[k]);
      }
      if (u) out.insert(int(i));
    }
    return out;
  }

  // The fitted tree's inside flags on the grid and its points' distances,
  // then the unsnapped designed tree's (patterns and slid caps in it) as
  // the baseline that each snap is measured from.
  void prepare() {
    grid_ = iouGrid(local_, options_.iouResolution);
    if (!localPoints_.empty()) baseDistance_ = meanDistance(local_, &baseAbs_);
    basePrims_.clear();
    baseLeafInside_.assign(d_.leaves.size(), {});
    for (std::size_t i = 0; i < d_.leaves.size(); ++i)
      basePrims_.push_back(d_.localPrimitive(int(i)));
    const CsgTree base = d_.localTree();
    std::vector<double> f(grid_.points.size());
    base.values(grid_.points, f);
    baseInside_.resize(f.size());
    baseInter_ = baseUnion_ = 0;
    for (std::size_t i = 0; i < f.size(); ++i) {
      baseInside_[i] = f[i] >= 0.0;
      baseInter_ += grid_.fittedInside[i] && baseInside_[i];
      baseUnion_ += grid_.fittedInside[i] || baseInside_[i];
    }
    if (!localPoints_.empty()) baseDesignedDistance_ = meanDistance(base, &baseDesignedAbs_);
  }

  // A pattern shares its members' values (their means), a cone's free cap
  // slides: the tree must keep its shape with them.
  bool keepsShape() const {
    const double iou = baseUnion_ > 0 ? double(baseInter_) / double(baseUnion_) : 1.0;
    for (const Primitive& p : basePrims_) {
      if (!validPrimitive(p)) return false;
    }
    return iou >= options_.minIou && fitsPoints(baseDesignedDistance_);
  }

  bool fitsPoints(double meanDistance) const {
    if (localPoints_.empty()) return true;
    const double noise = std::max(d_.noise, options_.minNoise * diagonal_);
    return meanDistance <= baseDistance_ + options_.fitnessSlack * noise;
  }

  // The test a set of changed values must pass: valid primitives, IoU against
  // the fitted tree, the points' mean distance. Returns the IoU (-1: fails).
  // Measured from the baseline: only the leaves the values change are
  // evaluated, on the grid points where one of them changes side (inside or
  // outside the tree is a function of the leaves' sides), and on the points
  // near them (2 % of D: the others keep their distance).
  double check(const std::vector<int>& changed) const {
    std::set<int> affected;
    for (int p : changed) {
      const std::set<int> l = leavesOf(p);
      affected.insert(l.begin(), l.end());
    }
    Aabb region;
    std::vector<std::pair<int, Primitive>> moved;
    for (int i : affected) {
      Primitive now = d_.localPrimitive(i);
      if (!validPrimitive(now)) return -1.0;
      region.extend(now.bounds());
      region.extend(basePrims_[std::size_t(i)].bounds());
      moved.emplace_back(i, std::move(now));
    }
    if (affected.empty()) {
      return baseUnion_ > 0 ? double(baseInter_) / double(baseUnion_) : 1.0;
    }
    region = region.grown(1e-9 * diagonal_);
    std::vector<Vec3> pts;
    std::vector<std::size_t> idx;
    for (std::size_t i = 0; i < grid_.points.size(); ++i) {
      if (region.contains(grid_.points[i])) {
        pts.push_back(grid_.points[i]);
        idx.push_back(i);
      }
    }
    std::vector<char> flips(pts.size(), 0);
    std::vector<double> after(pts.size());
    for (const auto& [leaf, now] : moved) {
      const std::vector<char>& before = baseInsideOf(leaf);
      now.values(pts, after);
      for (std::size_t k = 0; k < pts.size(); ++k) {
        flips[k] = flips[k] || (before[idx[k]] != (after[k] >= 0.0));
      }
    }
    std::vector<Vec3> flipped;
    std::vector<std::size_t> flippedIdx;
    for (std::size_t k = 0; k < pts.size(); ++k) {
      if (flips[k]) {
        flipped.push_back(pts[k]);
        flippedIdx.push_back(idx[k]);
      }
    }
    const CsgTree tree = d_.localTree();
    std::vector<double> f(flipped.size());
    tree.values(flipped, f);
    long inter = baseInter_, uni = baseUnion_;
    for (std::size_t k = 0; k < flipped.size(); ++k) {
      const bool a = grid_.fittedInside[flippedIdx[k]], b0 = baseInside_[flippedIdx[k]],
                 b = f[k] >= 0.0;
      inter += (a && b) - (a && b0);
      uni += (a || b) - (a || b0);
    }
    const double iou = uni > 0 ? double(inter) / double(uni) : 1.0;
    if (!localPoints_.empty()) {
      const Aabb near = region.grown(0.02 * diagonal_);
      std::vector<Vec3> close;
      double was = 0.0;
      for (std::size_t i = 0; i < localPoints_.size(); ++i) {
        if (!near.contains(localPoints_[i])) continue;
        close.push_back(localPoints_[i]);
        was += baseDesignedAbs_[i];
      }
      // min and max move by at most what an operand moves: when the moved
      // leaves' largest change already fits, the tree's does.
      std::vector<double> bound(close.size(), 0.0), v0(close.size()), v1(close.size());
      for (const auto& [leaf, now] : moved) {
        basePrims_[std::size_t(leaf)].values(close, v0);
        now.values(close, v1);
        for (std::size_t k = 0; k < close.size(); ++k) {
          bound[k] = std::max(bound[k], std::abs(v1[k] - v0[k]));
        }
      }
      double growth = 0.0;
      for (double b : bound) growth += b;
      const double n = double(localPoints_.size()), m = double(close.size());
      // Near the change, the points' mean distance may grow by one standard
      // error of it at most (σ/√m: a noisy shaft's hub radius fitted 15.536
      // ± 0.038 is not 15.5, its points say, though over all points the
      // change is lost); over all points, by fitnessSlack noise deviations.
      const double noise = std::max(d_.noise, options_.minNoise * diagonal_);
      if (growth > 0.0 &&
          (growth / m > noise / std::sqrt(m) || !fitsPoints(baseDesignedDistance_ + growth / n))) {
        std::vector<double> g(close.size());
        tree.values(close, g);
        double is = 0.0;
        for (double x : g) is += std::abs(x);
        if ((is - was) / m > noise / std::sqrt(m)) return -1.0;
        if (!fitsPoints(baseDesignedDistance_ + (is - was) / n)) return -1.0;
      }
    }
    return iou;
  }

  // Which grid points lie inside baseline leaf `leaf`, computed on first use
  // (each check moves a few leaves; most leaves are never moved).
  const std::vector<char>& baseInsideOf(int leaf) const {
    std::vector<char>& inside = baseLeafInside_[std::size_t(leaf)];
    if (inside.empty()) {
      std::vector<double> f(grid_.points.size());
      basePrims_[std::size_t(leaf)].values(grid_.points, f);
      inside.resize(f.size());
      for (std::size_t i = 0; i < f.size(); ++i) inside[i] = f[i] >= 0.0;
    }
    return inside;
  }

  void snap() {
    std::vector<std::optional<double>> candidate(d_.parameters.size());
    std::vector<int> all;
    for (std::size_t i = 0; i < d_.parameters.size(); ++i) {
      const DesignParameter& p = d_.parameters[i];
      if (p.kind == ParameterKind::Count) continue;
      candidate[i] = p.kind == ParameterKind::Angle
                         ? simplestAngle(p.fitted, p.uncertainty)
                         : simplestLength(refitted(int(i)), p.uncertainty, d_.units);
      if (candidate[i] && *candidate[i] != p.fitted) all.push_back(int(i));
      if (candidate[i] && *candidate[i] == p.fitted) d_.parameters[i].snapped = true;
    }
    const auto apply = [&](const std::vector<int>& set, bool on) {
      for (int i : set) {
        d_.parameters[std::size_t(i)].value =
            on ? *candidate[std::size_t(i)] : d_.parameters[std::size_t(i)].fitted;
      }
    };
    // A value no point holds may not change the solid at all: nothing says
    // the snapped one is right (a hidden face, a cutter's turn); each is
    // tried alone. The values the points hold: all together first, kept
    // when the set costs no more than one parameter may; else each on its
    // own (the solid it changes: IoU against the fitted tree, from the
    // baseline's). Then the ones that pass, together, for the points' fit,
    // dropping the costliest until it passes.
    const double baseIou = baseUnion_ > 0 ? double(baseInter_) / double(baseUnion_) : 1.0;
    const auto passes = [&](double iou, double allowed) {
      return iou >= 0.0 && baseIou - iou <= allowed;
    };
    const double allowed = 1.0 - options_.minIou;
    std::vector<int> held, unheld;
    std::vector<std::pair<double, int>> passing;
    for (int i : all) {
      if (std::isfinite(d_.parameters[std::size_t(i)].uncertainty)) {
        held.push_back(i);
        continue;
      }
      apply({i}, true);
      const double iou = check({i});
      apply({i}, false);
      if (passes(iou, 0.0)) unheld.push_back(i);
    }
    // Together too (a face one cutter hides may be the one another moved).
    apply(unheld, true);
    while (!unheld.empty() && !passes(check(unheld), 0.0)) {
      apply({unheld.back()}, false);
      unheld.pop_back();
    }
    apply(unheld, false);
    for (int i : unheld) passing.emplace_back(baseIou, i);
    apply(held, true);
    const bool together = passes(check(held), allowed);
    apply(held, false);
    for (int i : held) {
      if (together) {
        passing.emplace_back(1.0, i);
        continue;
      }
      apply({i}, true);
      const double iou = check({i});
      apply({i}, false);
      if (passes(iou, allowed) || (trusted(i, *candidate[std::size_t(i)]) &&
                                   passes(iou, uncertaintyCost(i, *candidate[std::size_t(i)])))) {
        passing.emplace_back(iou, i);
      }
    }
    std::stable_sort(passing.begin(), passing.end(),
                     [](const auto& a, const auto& b) { return a.first > b.first; });
    all.clear();
    for (const auto& [iou, i] : passing) all.push_back(i);
    apply(all, true);
    while (!all.empty() && check(all) < 0.0) {
      apply({all.back()}, false);
      all.pop_back();
    }
    for (int i : all) d_.parameters[std::size_t(i)].snapped = true;
  }

  // The median of a sample (the upper middle value).
  static double median(std::vector<double> v) {
    const auto mid = v.begin() + std::ptrdiff_t(v.size() / 2);
    std::nth_element(v.begin(), mid, v.end());
    return *mid;
  }

  // Robust deviation of a sample: 1.4826 × its median absolute deviation.
  static double spread(std::vector<double> v) {
    const double m = median(v);
    for (double& x : v) x = std::abs(x - m);
    return 1.4826 * median(std::move(v));
  }

  // The value parameter i's points imply: the fitted one, unless the points
  // near its faces lie off them beyond the noise band and its uncertainty
  // (their median offset; a clean scan's face a fit left 0.008 off, which
  // the points within the band, a few on its edges, cannot tell): then
  // where they lie.
  double refitted(int i) const {
    const DesignParameter& p = d_.parameters[std::size_t(i)];
    const std::vector<double>& o = paramSlots_[std::size_t(i)].offsets;
    if (o.size() < kLeastOffsets || !std::isfinite(p.uncertainty)) return p.fitted;
    const double offset = median(o), band = SupportOptions{}.band * d_.noise;
    return std::abs(offset) > std::max(p.uncertainty, band) ? p.fitted + offset : p.fitted;
  }

  // A length's snap that chance would rarely give: its uncertainty at most
  // a quarter of its rung's step (a value lands within u of some multiple
  // of that step with probability 2u / step, here at most a half); a
  // loosely held value's whole unit is rounding, not a designed value found.
  bool trusted(int i, double target) const {
    const DesignParameter& p = d_.parameters[std::size_t(i)];
    if (p.kind != ParameterKind::Length) return false;
    const int rung = ladderRung(target, d_.units);
    return rung >= 0 && p.uncertainty <= 0.25 * ladderStep(rung, d_.units);
  }

  // What moving parameter i by its own uncertainty towards `target` costs
  // the IoU against the fitted tree: a snap within the uncertainty may cost
  // as much, since the fitted value is no surer than that (a noisy scan's
  // large face or thin wall moves many grid points for a u of 0.07).
  // Without points the uncertainty is a nominal tolerance, not a
  // measurement: no cost is allowed for it.
  double uncertaintyCost(int i, double target) {
    DesignParameter& p = d_.parameters[std::size_t(i)];
    if (localPoints_.empty() || !std::isfinite(p.uncertainty) || target == p.fitted) return 0.0;
    p.value = p.fitted + std::copysign(p.uncertainty, target - p.fitted);
    const double iou = check({i});
    p.value = p.fitted;
    const double baseIou = baseUnion_ > 0 ? double(baseInter_) / double(baseUnion_) : 1.0;
    return iou < 0.0 ? 0.0 : std::max(0.0, baseIou - iou);
  }

  void measureDatumOffset() {
    // An offset below a tenth of the finest uncertainty along its axis is
    // left alone (a clean scan's, at float noise): the design would not move.
    Vec3 sum = Vec3::Zero(), weight = Vec3::Zero(), finest = Vec3::Constant(kInf);
    for (std::size_t i = 0; i < d_.parameters.size(); ++i) {
      const DesignParameter& p = d_.parameters[i];
      const int axis = int(paramSlots_[i].category);
      if (axis > 2 || !p.snapped || !std::isfinite(p.uncertainty) || p.uncertainty <= 0.0) continue;
      const double w = 1.0 / (p.uncertainty * p.uncertainty);
      sum[axis] += w * (refitted(int(i)) - p.value);
      weight[axis] += w;
      finest[axis] = std::min(finest[axis], p.uncertainty);
    }
    for (int a = 0; a < 3; ++a) {
      const double offset = weight[a] > 0.0 ? sum[a] / weight[a] : 0.0;
      d_.datumOffset[a] = std::abs(offset) >= 0.1 * finest[a] ? offset : 0.0;
    }
  }

  // The points' mean |f| to `tree`; each point's |f| into `each` when given.
  double meanDistance(const CsgTree& tree, std::vector<double>* each = nullptr) const {
    std::vector<double> g(localPoints_.size());
    tree.values(localPoints_, g);
    double mean = 0.0;
    for (double& x : g) {
      x = std::abs(x);
      mean += x;
    }
    if (each) *each = g;
    return g.empty() ? 0.0 : mean / double(g.size());
  }

  // Snapped parameters of one kind of position or radius with one value
  // become one (coplanar faces, coaxial axes, equal radii the fit left apart).
  void mergeEqualSnapped() {
    std::vector<int> map(d_.parameters.size());
    std::vector<DesignParameter> kept;
    std::vector<Slot> keptSlots;
    std::map<std::pair<int, double>, int> seen;
    for (std::size_t i = 0; i < d_.parameters.size(); ++i) {
      const DesignParameter& p = d_.parameters[i];
      const Slot& s = paramSlots_[i];
      const bool mergeable = p.snapped && s.category <= ValueCategory::Radius && s.owner.empty();
      const auto key = std::make_pair(int(s.category), p.value);
      if (mergeable) {
        if (const auto it = seen.find(key); it != seen.end()) {
          map[i] = it->second;
          Slot& into = keptSlots[std::size_t(it->second)];
          into.leaves.insert(s.leaves.begin(), s.leaves.end());
          continue;
        }
        seen[key] = int(kept.size());
      }
      map[i] = int(kept.size());
      kept.push_back(p);
      keptSlots.push_back(s);
    }
    d_.parameters = std::move(kept);
    paramSlots_ = std::move(keptSlots);
    remap(map);
  }

  void nameParameters() {
    std::set<std::string> used;
    for (std::size_t i = 0; i < d_.parameters.size(); ++i) {
      DesignParameter& p = d_.parameters[i];
      std::string name = p.name;
      for (int k = 2; used.count(name); ++k) name = p.name + "_" + std::to_string(k);
      used.insert(name);
      p.name = name;
      const Slot& s = paramSlots_[i];
      if (!s.owner.empty() && s.leaves.empty()) {
        p.usedBy = s.owner;
        continue;
      }
      std::map<std::string, int> roles;
      std::vector<std::string> order;
      for (int l : s.leaves) {
        const std::string& r = d_.leaves[std::size_t(l)].role;
        if (!roles.count(r)) order.push_back(r);
        ++roles[r];
      }
      for (const std::string& r : order) {
        if (!p.usedBy.empty()) p.usedBy += ", ";
        p.usedBy += plural(r, roles[r]);
      }
    }
  }

  void measure() {
    const CsgTree tree = d_.localTree();
    if (!grid_.points.empty()) {
      std::vector<double> f(grid_.points.size());
      tree.values(grid_.points, f);
      long inter = 0, uni = 0;
      for (std::size_t i = 0; i < f.size(); ++i) {
        inter += grid_.fittedInside[i] && f[i] >= 0.0;
        uni += grid_.fittedInside[i] || f[i] >= 0.0;
      }
      d_.iouToFitted = uni > 0 ? double(inter) / double(uni) : 1.0;
    }
    if (!localPoints_.empty()) {
      d_.meanDistanceFitted = baseDistance_;
      d_.meanDistanceDesigned = meanDistance(tree);
    }
  }

  DesignOptions options_;
  bool slide_ = true;
  std::span<const Vec3> points_;
  DesignedTree d_;
  CsgTree local_;
  std::vector<Vec3> localPoints_;
  double diagonal_ = 1.0;
  std::unordered_map<const Node*, int> localIndex_;
  std::vector<std::vector<Vec3>> gradients_;
  std::vector<std::vector<Vec3>> near_, nearGradients_;  // points near each leaf (kNearBand)
  std::vector<FoundPattern> found_;
  std::vector<Slot> slots_;
  std::vector<Slot> paramSlots_;
  IouGrid grid_;
  double baseDistance_ = 0.0;
  std::vector<double> baseAbs_;  // each point's |f| to the fitted tree
  // The baseline: the designed tree before any snap.
  std::vector<Primitive> basePrims_;                       // its leaves
  mutable std::vector<std::vector<char>> baseLeafInside_;  // see baseInsideOf()
  std::vector<char> baseInside_;                           // its inside flags on the grid
  long baseInter_ = 0, baseUnion_ = 0;   // its grid cells in and in either with the fitted tree
  std::vector<double> baseDesignedAbs_;  // each point's |f| to it
  double baseDesignedDistance_ = 0.0;    // their mean
};

}  // namespace

namespace {

// At most `most` of the points, every k-th (deterministic).
std::vector<Vec3> thinned(std::span<const Vec3> points, int most) {
  const std::size_t n = points.size();
  const std::size_t cap = std::size_t(std::max(most, 1));
  if (n <= cap) return {points.begin(), points.end()};
  std::vector<Vec3> out;
  out.reserve(cap);
  for (std::size_t i = 0; i < cap; ++i) out.push_back(points[i * n / cap]);
  return out;
}

}  // namespace

DesignedTree designTree(const CsgTree& fitted, const PartFrame& frame, std::span<const Vec3> points,
                        const DesignOptions& options) {
  if (fitted.empty()) throw std::invalid_argument("designTree: empty tree");
  const std::vector<Vec3> used = thinned(points, options.maxPoints);
  return Designer(fitted, frame, used, options).run();
}

DesignedTree designTree(const CsgTree& fitted, std::span<const Vec3> allPoints,
                        const DesignOptions& options) {
  if (fitted.empty()) throw std::invalid_argument("designTree: empty tree");
  const std::vector<Vec3> used = thinned(allPoints, options.maxPoints);
  const std::span<const Vec3> points = used;
  PartFrame frame = partFrame(fitted, points, options.frame);
  DesignedTree d = designTree(fitted, frame, points, options);
  // The origin is a fitted face or axis, as off as its points leave it: moved
  // to where the snapped positions put it, and the tree designed again.
  const auto refined = [&](DesignedTree first, PartFrame f) {
    const double d0 = exportExtent(fitted).diagonal();
    if (points.empty() || first.datumOffset.norm() <= 1e-9 * d0) return first;
    f.origin = roundedOrigin(f.origin + f.rotation * first.datumOffset,
                             options.frame.originTolerance * d0);
    return designTree(fitted, f, points, options);
  };
  if (!frame.spinFree) return refined(std::move(d), frame);
  // The frame turned about its z by `phase` (radians), and the tree
  // designed in it.
  const auto turnedBy = [&](double phase) {
    Mat3 spin = Mat3::Identity();
    spin << std::cos(phase), -std::sin(phase), 0, std::sin(phase), std::cos(phase), 0, 0, 0, 1;
    frame.rotation = nearestWorldAxes(frame.rotation * spin, options.frame.worldTolerance);
    frame.spinFree = false;
    return refined(designTree(fitted, frame, points, options), frame);
  };
  // A turned part: x through the first member of a bolt circle about the
  // main axis, so that a turned copy of the part gives the same values.
  const double tol = options.patternTolerance * exportExtent(fitted).diagonal();
  for (const DesignedPattern& p : d.patterns) {
    const auto fittedOf = [&](const Expression& e) {
      double v = 0.0;
      for (const auto& [c, i] : e.terms) v += c * d.parameters[std::size_t(i)].fitted;
      return v;
    };
    if (p.kind != PatternKind::Circular || std::abs(fittedOf(p.centerX)) > tol ||
        std::abs(fittedOf(p.centerY)) > tol) {
      continue;
    }
    const double phase = fittedOf(p.phase) / kDeg;
    if (std::abs(phase) < 1e-12) return d;
    return turnedBy(phase);
  }
  // Without one, x along the first cylinder or cone across the main axis (a
  // radial hole or pin), pointing away from the axis: else the world's axes
  // would leave it oblique, written with its fitted numbers.
  for (const DesignedLeaf& l : d.leaves) {
    Vec3 axis = Vec3::Zero(), center = Vec3::Zero();
    if (const auto* c = l.local.as<Cylinder>()) axis = c->axis, center = c->center;
    if (const auto* c = l.local.as<Cone>()) axis = c->axis, center = c->center;
    if (axis.isZero() || std::abs(axis.z()) > std::sin(options.alignTolerance)) continue;
    if (axis.x() * center.x() + axis.y() * center.y() < 0.0) axis = -axis;
    const double phase = std::atan2(axis.y(), axis.x());
    if (std::abs(phase) < 1e-12) return refined(std::move(d), frame);
    return turnedBy(phase);
  }
  return refined(std::move(d), frame);
}

}  // namespace csgvox
