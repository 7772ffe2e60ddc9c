// The designed tree: frame, snapped parameters, shared groups and patterns,
// on the bundled parts' true trees moved and perturbed as a fit leaves them.

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "design/designed_tree.h"
#include "design/part_frame.h"
#include "io/tree_json.h"
#include "part_list.h"
#include "test_helpers.h"

namespace csgvox {
namespace {

using test::dataDir;

CsgTree part(const std::string& name) { return readTreeJson(dataDir() / name / "tree.json"); }

// Every length of every primitive moved by up to `noise` (a fit's error).
CsgTree perturbed(const CsgTree& tree, double noise, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-noise, noise);
  std::unordered_map<const Node*, NodePtr> done;
  std::function<NodePtr(const NodePtr&)> walk = [&](const NodePtr& n) -> NodePtr {
    if (auto it = done.find(n.get()); it != done.end()) return it->second;
    NodePtr out;
    if (n->kind == NodeKind::Primitive) {
      Primitive p = std::visit(
          [&](auto s) -> Primitive {
            using T = decltype(s);
            if constexpr (std::is_same_v<T, HalfSpace>) {
              s.offset += u(rng);
            } else {
              s.center += Vec3(u(rng), u(rng), u(rng));
              if constexpr (std::is_same_v<T, Box>) s.halfSize += Vec3(u(rng), u(rng), u(rng));
              if constexpr (std::is_same_v<T, Cylinder>) s.radius += u(rng), s.height += u(rng);
              if constexpr (std::is_same_v<T, Sphere>) s.radius += u(rng);
              if constexpr (std::is_same_v<T, Torus>) s.majorRadius += u(rng), s.minorRadius += u(rng);
              if constexpr (std::is_same_v<T, Cone>) {
                s.radiusBottom += s.radiusBottom > 0 ? u(rng) : 0.0;
                s.radiusTop += s.radiusTop > 0 ? u(rng) : 0.0;
                s.height += u(rng);
              }
            }
            return s;
          },
          n->primitive.shape());
      out = std::make_shared<const Node>(p, n->name);
    } else {
      std::vector<NodePtr> c;
      for (const auto& k : n->children) c.push_back(walk(k));
      out = std::make_shared<const Node>(n->kind, c);
    }
    return done[n.get()] = out;
  };
  return CsgTree(walk(tree.root()));
}

void dump(const DesignedTree& d) {
  for (const auto& p : d.parameters) {
    std::printf("%-24s fitted %.9g value %.9g u %.3g %s  (%s)\n", p.name.c_str(), p.fitted, p.value,
                p.uncertainty, p.snapped ? "snapped" : "", p.usedBy.c_str());
  }
  for (const auto& p : d.patterns) std::printf("pattern %s %s members %zu\n", p.name.c_str(), p.kindName().c_str(), p.members.size());
  for (const auto& l : d.leaves) std::printf("leaf %s form %d\n", l.name.c_str(), int(l.form));
  std::printf("iou %.6f\n", d.iouToFitted);
}

TEST(DesignedTree, Dump) {
  const DesignedTree d = designTree(perturbed(part("flange"), 1e-4, 1));
  dump(d);
}

}  // namespace
}  // namespace csgvox
