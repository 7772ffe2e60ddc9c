#include "io/tree_json.h"

#include "io/errors.h"
#include "io/file_util.h"

#include <nlohmann/json.hpp>

#include <fstream>

namespace csgvox {
namespace {

using Json = nlohmann::ordered_json;
constexpr const char* kFormat = "csgvox-tree";
constexpr int kVersion = 1;

Json vec(const Vec3& v) { return Json::array({v.x(), v.y(), v.z()}); }

Vec3 readVec(const Json& j, const char* key) {
  if (!j.contains(key)) throw std::invalid_argument(std::string("missing \"") + key + "\"");
  const Json& a = j.at(key);
  if (!a.is_array() || a.size() != 3 || !a[0].is_number() || !a[1].is_number() ||
      !a[2].is_number()) {
    throw std::invalid_argument(std::string("\"") + key + "\" must be an array of 3 numbers");
  }
  return Vec3(a[0].get<double>(), a[1].get<double>(), a[2].get<double>());
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
    case PrimitiveType::HalfSpace: return HalfSpace{readVec(j, "normal"), readNumber(j, "offset")};
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
          Json wrap;
          wrap["v"] = a[i];
          b.axes.col(i) = readVec(wrap, "v");
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
    case PrimitiveType::Sphere: return Sphere{readVec(j, "center"), readNumber(j, "radius")};
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

CsgTree nodeFromJson(const Json& j, int depth) {
  if (depth > 10000) throw std::invalid_argument("tree is nested too deeply");
  if (!j.is_object()) throw std::invalid_argument("a node must be a JSON object");
  if (j.contains("type")) {
    std::string name;
    if (j.contains("name")) {
      if (!j.at("name").is_string()) throw std::invalid_argument("\"name\" must be a string");
      name = j.at("name").get<std::string>();
    }
    return CsgTree::leaf(primitiveFromJson(j), name);
  }
  if (!j.contains("op") || !j.at("op").is_string()) {
    throw std::invalid_argument("a node needs \"type\" (primitive) or \"op\" (operation)");
  }
  const std::string op = j.at("op").get<std::string>();
  if (!j.contains("children") || !j.at("children").is_array() || j.at("children").empty()) {
    throw std::invalid_argument("operation \"" + op + "\" needs a non-empty \"children\" array");
  }
  std::vector<CsgTree> children;
  for (const Json& c : j.at("children")) children.push_back(nodeFromJson(c, depth + 1));
  if (op == "union") return CsgTree::unite(children);
  if (op == "intersection") return CsgTree::intersect(children);
  if (op == "difference") return CsgTree::subtract(children);
  if (op == "complement") {
    if (children.size() != 1) throw std::invalid_argument("complement needs exactly one child");
    return CsgTree::complement(children.front());
  }
  throw std::invalid_argument("unknown operation \"" + op + "\"");
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
    if (j.contains("version") && (!j.at("version").is_number_integer() ||
                                  j.at("version").get<int>() > kVersion)) {
      throw std::invalid_argument("unsupported \"version\" (this csgvox reads version 1)");
    }
    if (!j.contains("root")) throw std::invalid_argument("missing \"root\"");
    CsgTree tree = nodeFromJson(j.at("root"), 0);
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

void writeTreeJson(const std::filesystem::path& path, const CsgTree& tree) {
  writeFileAtomically(path, [&](std::ostream& out) { writeTreeJson(out, tree); });
}

}  // namespace csgvox
