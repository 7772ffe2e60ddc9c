#include "io/tree_names.h"

#include <cctype>
#include <charconv>
#include <cmath>
#include <map>
#include <set>

namespace csgvox {
namespace {

bool isIdentifier(const std::string& s) {
  if (s.empty() || !(std::isalpha(static_cast<unsigned char>(s[0])) || s[0] == '_')) return false;
  for (char c : s) {
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_')) return false;
  }
  return true;
}

}  // namespace

std::unordered_map<const Node*, std::string> leafNames(const CsgTree& tree) {
  std::unordered_map<const Node*, std::string> names;
  std::set<std::string> used;
  std::map<std::string, int> counters;
  const auto fresh = [&](const std::string& base, bool numberFirst) {
    std::string candidate = numberFirst ? base + std::to_string(++counters[base]) : base;
    while (used.count(candidate)) candidate = base + "_" + std::to_string(++counters[base + "_"]);
    used.insert(candidate);
    return candidate;
  };
  // Reserve valid user names first so generated names never shadow them.
  for (const Node* leaf : tree.leaves()) {
    if (isIdentifier(leaf->name) && !names.count(leaf) && !used.count(leaf->name)) {
      names[leaf] = leaf->name;
      used.insert(leaf->name);
    }
  }
  for (const Node* leaf : tree.leaves()) {
    if (names.count(leaf)) continue;
    if (isIdentifier(leaf->name)) {
      names[leaf] = fresh(leaf->name, false);
    } else {
      names[leaf] = fresh(std::string(primitiveTypeName(leaf->primitive.type())), true);
    }
  }
  return names;
}

std::string formatNumber(double value) {
  if (value == 0.0) return "0";  // also turns -0 into 0
  char buf[64];
  const auto res = std::to_chars(buf, buf + sizeof(buf), value);
  return std::string(buf, res.ptr);
}

std::string formatVector(const Vec3& v) {
  std::string s = "[";
  s += formatNumber(v.x());
  s += ", ";
  s += formatNumber(v.y());
  s += ", ";
  s += formatNumber(v.z());
  return s += "]";
}

}  // namespace csgvox
