#include "io/tree_json.h"

#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "io/errors.h"
#include "io/file_util.h"

namespace csgvox {
namespace {

using Json = nlohmann::ordered_json;
constexpr const char* kFormat = "csgvox-tree";
constexpr int kVersion = 1;
// Deepest accepted nesting of operations. Trees are read, evaluated and freed
// recursively; this keeps that well inside the stack, also in sanitizer builds.
constexpr std::size_t kMaxDepth = 1000;

Json vec(const Vec3& v) { return Json::array({v.x(), v.y(), v.z()}); }

// The vector in `a`; `what` names it in the error message.
Vec3 toVec(const Json& a, const std::string& what) {
  if (!a.is_array() || a.size() != 3 || !a[0].is_number() || !a[1].is_number() ||
      !a[2].is_number()) {
    throw std::invalid_argument(what + " must be an array of 3 numbers");
  }
  return Vec3(a[0].get<double>(), a[1].get<double>(), a[2].get<double>());
}

Vec3 readVec(const Json& j, const char* key) {
  if (!j.contains(key)) throw std::invalid_argument(std::string("missing \"") + key + "\"");
  return toVec(j.at(key), std::string("\"") + key + "\"");
}

double readNumber(const Json& j, const char* key) {
  if (!j.contains(key) || !j.at(key).is_number()) {
    throw std::invalid_argument(std::string("\"") + key + "\" must be a number");
  }
  return j.at(key).get<double>();
}

Json primitiveToJson(const Primitive& p, const std::string& name) {
  Json j;
  j["type"] = std::string(primitiveTypeName(p.type()));
  if (!name.empty()) j["name"] = name;
  if (const auto* s = p.as<HalfSpace>()) {
    j["normal"] = vec(s->normal);
    j["offset"] = s->offset;
  } else if (const auto* s = p.as<Box>()) {
    j["center"] = vec(s->center);
    j["axes"] = Json::array({vec(s->axes.col(0)), vec(s->axes.col(1)), vec(s->axes.col(2))});
    j["half_size"] = vec(s->halfSize);
  } else if (const auto* s = p.as<Cylinder>()) {
    j["center"] = vec(s->center);
    j["axis"] = vec(s->axis);
    j["radius"] = s->radius;
    j["height"] = s->height;
  } else if (const auto* s = p.as<Cone>()) {
    j["center"] = vec(s->center);
    j["axis"] = vec(s->axis);
    j["radius_bottom"] = s->radiusBottom;
    j["radius_top"] = s->radiusTop;
    j["height"] = s->height;
  } else if (const auto* s = p.as<Sphere>()) {
    j["center"] = vec(s->center);
    j["radius"] = s->radius;
  } else if (const auto* s = p.as<Torus>()) {
    j["center"] = vec(s->center);
    j["axis"] = vec(s->axis);
    j["major_radius"] = s->majorRadius;
    j["minor_radius"] = s->minorRadius;
  }
  return j;
}

Primitive primitiveFromJson(const Json& j) {
  if (!j.at("type").is_string()) throw std::invalid_argument("\"type\" must be a string");
  switch (primitiveTypeFromName(j.at("type").get<std::string>())) {
    case PrimitiveType::HalfSpace:
      return HalfSpace{readVec(j, "normal"), readNumber(j, "offset")};
    case PrimitiveType::Box: {
      Box b;
      b.center = readVec(j, "center");
      b.halfSize = readVec(j, "half_size");
      if (j.contains("axes")) {
        const Json& a = j.at("axes");
        if (!a.is_array() || a.size() != 3) {
          throw std::invalid_argument("\"axes\" must be an array of 3 vectors");
        }
        for (int i = 0; i < 3; ++i) {
          b.axes.col(i) = toVec(a[i], "\"axes\"[" + std::to_string(i) + "]");
        }
      }
      return b;
    }
    case PrimitiveType::Cylinder:
      return Cylinder{readVec(j, "center"), readVec(j, "axis"), readNumber(j, "radius"),
                      readNumber(j, "height")};
    case PrimitiveType::Cone:
      return Cone{readVec(j, "center"), readVec(j, "axis"), readNumber(j, "radius_bottom"),
                  readNumber(j, "radius_top"), readNumber(j, "height")};
    case PrimitiveType::Sphere:
      return Sphere{readVec(j, "center"), readNumber(j, "radius")};
    case PrimitiveType::Torus:
      return Torus{readVec(j, "center"), readVec(j, "axis"), readNumber(j, "major_radius"),
                   readNumber(j, "minor_radius")};
  }
  throw std::invalid_argument("unknown primitive type");
}

Json nodeToJson(const Node& node) {
  if (node.kind == NodeKind::Primitive) return primitiveToJson(node.primitive, node.name);
  Json j;
  j["op"] = std::string(nodeKindName(node.kind));
  Json children = Json::array();
  for (const NodePtr& c : node.children) children.push_back(nodeToJson(*c));
  j["children"] = std::move(children);
  return j;
}

// Location of a node for error messages, e.g. "root.children[2].children[0]";
// the middle of a very deep path is elided.
std::string nodePath(const std::vector<std::size_t>& path) {
  constexpr std::size_t kEnds = 4;  // levels shown at each end of a long path
  std::string out = "root";
  for (std::size_t k = 0; k < path.size(); ++k) {
    if (path.size() > 3 * kEnds && k == kEnds) {
      out += "...(" + std::to_string(path.size() - 2 * kEnds) + " more levels)";
      k = path.size() - kEnds;
    }
    out += ".children[" + std::to_string(path[k]) + "]";
  }
  return out;
}

// Reads the node `j` at `path` (child indices from the root); problems are
// reported with that location.
CsgTree nodeFromJson(const Json& j, std::vector<std::size_t>& path) {
  auto fail = [&](const std::string& problem) {
    return std::invalid_argument(nodePath(path) + ": " + problem);
  };
  if (path.size() > kMaxDepth) {
    throw fail("tree is nested too deeply (more than " + std::to_string(kMaxDepth) + " levels)");
  }
  if (!j.is_object()) throw fail("a node must be a JSON object");
  if (j.contains("type")) {
    std::string name;
    if (j.contains("name")) {
      if (!j.at("name").is_string()) throw fail("\"name\" must be a string");
      name = j.at("name").get<std::string>();
    }
    try {
      Primitive primitive = primitiveFromJson(j);
      primitive.validate();
      return CsgTree::leaf(std::move(primitive), name);
    } catch (const std::invalid_argument& e) {
      const std::string label =
          name.empty() ? nodePath(path) : nodePath(path) + " \"" + name + "\"";
      throw std::invalid_argument(label + ": " + e.what());
    }
  }
  if (!j.contains("op") || !j.at("op").is_string()) {
    throw fail("a node needs \"type\" (primitive) or \"op\" (operation)");
  }
  const std::string op = j.at("op").get<std::string>();
  if (op != "union" && op != "intersection" && op != "difference" && op != "complement") {
    throw fail("unknown operation \"" + op + "\"");
  }
  if (!j.contains("children") || !j.at("children").is_array() || j.at("children").empty()) {
    throw fail("operation \"" + op + "\" needs a non-empty \"children\" array");
  }
  const Json& list = j.at("children");
  if (op == "complement" && list.size() != 1) {
    throw fail("complement needs exactly one child, not " + std::to_string(list.size()));
  }
  std::vector<CsgTree> children;
  for (std::size_t i = 0; i < list.size(); ++i) {
    path.push_back(i);
    children.push_back(nodeFromJson(list[i], path));
    path.pop_back();
  }
  if (op == "union") return CsgTree::unite(children);
  if (op == "intersection") return CsgTree::intersect(children);
  if (op == "difference") return CsgTree::subtract(children);
  return CsgTree::complement(children.front());
}

}  // namespace

CsgTree readTreeJson(std::istream& in, const std::string& source) {
  Json j;
  try {
    j = Json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    throw ParseError(source + ": not valid JSON (" + e.what() + ")");
  }
  try {
    if (!j.is_object()) throw std::invalid_argument("top level must be a JSON object");
    if (j.contains("format") && j.at("format") != kFormat) {
      throw std::invalid_argument("\"format\" is not \"csgvox-tree\"");
    }
    // Compared as a JSON value: a narrowing get<int>() would accept 2^32 + 1.
    if (j.contains("version") &&
        (!j.at("version").is_number_integer() || j.at("version") != Json(kVersion))) {
      throw std::invalid_argument("unsupported \"version\" " + j.at("version").dump() +
                                  " (this csgvox reads version 1)");
    }
    if (!j.contains("root")) throw std::invalid_argument("missing \"root\"");
    std::vector<std::size_t> path;
    CsgTree tree = nodeFromJson(j.at("root"), path);
    tree.validate();
    return tree;
  } catch (const nlohmann::json::exception& e) {
    throw ParseError(source + ": invalid tree (" + e.what() + ")");
  } catch (const std::invalid_argument& e) {
    throw ParseError(source + ": invalid tree: " + e.what());
  }
}

CsgTree readTreeJson(const std::filesystem::path& path) {
  requireReadableFile(path);
  std::ifstream in(path);
  return readTreeJson(in, path.string());
}

void writeTreeJson(std::ostream& out, const CsgTree& tree) {
  if (tree.empty()) throw std::invalid_argument("cannot write an empty tree");
  Json j;
  j["format"] = kFormat;
  j["version"] = kVersion;
  j["root"] = nodeToJson(*tree.root());
  out << j.dump(2) << "\n";
}

Json treeNodeToJson(const CsgTree& tree) {
  if (tree.empty()) throw std::invalid_argument("cannot write an empty tree");
  return nodeToJson(*tree.root());
}

std::string treeNodeJson(const CsgTree& tree) { return treeNodeToJson(tree).dump(); }

void writeTreeJson(const std::filesystem::path& path, const CsgTree& tree) {
  writeFileAtomically(path, [&](std::ostream& out) { writeTreeJson(out, tree); });
}

}  // namespace csgvox
