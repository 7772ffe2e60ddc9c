#include "io/tree_names.h"

#include <cctype>
#include <charconv>
#include <cmath>
#include <map>
#include <set>

#include "core/decimal.h"

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

bool isOpenScadReserved(const std::string& name) {
  // OpenSCAD's keywords, constants and built-in modules and functions (its
  // language manual and cheat sheet, up to release 2021.01, plus the
  // deprecated and the internal ones it still accepts). A module of one of
  // these names would not parse or would replace the built-in that the other
  // modules call.
  static const std::set<std::string, std::less<>> reserved = {
      // keywords and constants
      "module", "function", "include", "use", "if", "else", "for", "intersection_for", "let",
      "each", "assert", "echo", "assign", "true", "false", "undef", "PI", "inf", "nan",
      // 3D and 2D primitives
      "cube", "sphere", "cylinder", "polyhedron", "circle", "square", "polygon", "text", "import",
      "import_stl", "import_off", "import_dxf", "surface", "roof",
      // transformations and operations
      "translate", "rotate", "scale", "resize", "mirror", "multmatrix", "color", "offset", "hull",
      "minkowski", "union", "difference", "intersection", "render", "projection", "linear_extrude",
      "rotate_extrude", "dxf_linear_extrude", "dxf_rotate_extrude", "children", "child", "group",
      "parent_module", "fill",
      // functions
      "abs", "sign", "sin", "cos", "tan", "acos", "asin", "atan", "atan2", "floor", "round", "ceil",
      "ln", "len", "log", "pow", "sqrt", "exp", "rands", "min", "max", "concat", "lookup", "str",
      "chr", "ord", "search", "version", "version_num", "norm", "cross", "is_undef", "is_bool",
      "is_num", "is_string", "is_list", "is_function", "is_object", "dxf_dim", "dxf_cross",
      "object", "textmetrics", "fontmetrics"};
  return reserved.count(name) > 0;
}

std::unordered_map<const Node*, std::string> leafNames(const CsgTree& tree) {
  std::unordered_map<const Node*, std::string> names;
  std::set<std::string> used;
  std::map<std::string, int> counters;
  // OpenSCAD's own names are never given out (a leaf named so gets a suffix).
  for (const Node* leaf : tree.leaves()) {
    if (isOpenScadReserved(leaf->name)) used.insert(leaf->name);
  }
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
  return value == 0.0 ? "0" : toDecimal(value);  // also turns -0 into 0
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
