#include "io/design_json.h"

#include <cmath>
#include <fstream>
#include <ostream>

#include "io/errors.h"
#include "io/file_util.h"
#include "io/tree_json.h"

namespace csgvox {
namespace {

using Json = nlohmann::ordered_json;

Json vec(const Vec3& v) { return Json::array({v.x(), v.y(), v.z()}); }

// A number, or null when it is not finite (JSON has no infinity).
Json number(double v) { return std::isfinite(v) ? Json(v) : Json(nullptr); }

std::string kindName(ParameterKind k) {
  return k == ParameterKind::Angle ? "angle" : k == ParameterKind::Count ? "count" : "length";
}

Json patternJson(const DesignedTree& d, const DesignedPattern& p) {
  Json j;
  j["name"] = p.name;
  j["kind"] = p.kindName();
  Json members = Json::array();
  for (int m : p.members) members.push_back(d.leaves[std::size_t(m)].name);
  j["members"] = members;
  const auto v = [&](const Expression& e) { return e.value(d.parameters); };
  const auto world = [&](const std::array<Expression, 3>& s) {
    return vec(d.frame.rotation * Vec3(v(s[0]), v(s[1]), v(s[2])));
  };
  j["count"] = std::lround(d.parameters[std::size_t(p.count)].value);
  j["count_parameter"] = d.parameters[std::size_t(p.count)].name;
  if (p.kind == PatternKind::Circular) {
    j["axis"] = vec(d.frame.rotation.col(2));
    j["center"] = vec(d.frame.toWorld(Vec3(v(p.centerX), v(p.centerY), 0.0)));
    j["radius"] = v(p.radius);
    j["phase"] = v(p.phase);
    j["radius_parameter"] = p.radius.text(d.parameters);
    j["phase_parameter"] = p.phase.text(d.parameters);
  } else {
    j["step"] = world(p.step);
    if (p.kind == PatternKind::Lattice) {
      j["count2"] = std::lround(d.parameters[std::size_t(p.count2)].value);
      j["step2"] = world(p.step2);
    }
  }
  return j;
}

}  // namespace

void writeDesignedTreeJson(std::ostream& out, const DesignedTree& d) {
  Json j;
  j["format"] = "csgvox-tree";
  j["version"] = 1;
  j["root"] = treeNodeToJson(d.tree());
  Json frame;
  frame["origin"] = vec(d.frame.origin);
  frame["axes"] = Json::array(
      {vec(d.frame.rotation.col(0)), vec(d.frame.rotation.col(1)), vec(d.frame.rotation.col(2))});
  j["frame"] = frame;
  j["units"] = unitSystemName(d.units);
  Json params = Json::array();
  for (const DesignParameter& p : d.parameters) {
    Json q;
    q["name"] = p.name;
    q["kind"] = kindName(p.kind);
    q["value"] = p.value;
    q["fitted"] = p.fitted;
    q["uncertainty"] = number(p.uncertainty);
    q["snapped"] = p.snapped;
    q["used_by"] = p.usedBy;
    params.push_back(q);
  }
  j["parameters"] = params;
  Json patterns = Json::array();
  for (const DesignedPattern& p : d.patterns) patterns.push_back(patternJson(d, p));
  j["patterns"] = patterns;
  out << j.dump(2) << "\n";
}

void writeDesignedTreeJson(const std::filesystem::path& path, const DesignedTree& design) {
  writeFileAtomically(path, [&](std::ostream& out) { writeDesignedTreeJson(out, design); });
}

std::optional<PartFrame> readTreeFrame(const std::filesystem::path& path) {
  requireReadableFile(path);
  std::ifstream in(path);
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    throw ParseError(path.string() + ": not valid JSON (" + e.what() + ")");
  }
  if (!j.is_object() || !j.contains("frame")) return std::nullopt;
  try {
    const auto& f = j.at("frame");
    PartFrame frame;
    for (int i = 0; i < 3; ++i) frame.origin[i] = f.at("origin").at(i).get<double>();
    for (int c = 0; c < 3; ++c)
      for (int i = 0; i < 3; ++i) frame.rotation(i, c) = f.at("axes").at(c).at(i).get<double>();
    const double error = (frame.rotation.transpose() * frame.rotation - Mat3::Identity()).norm();
    if (!(error < 1e-9) || !(frame.rotation.determinant() > 0.0) || !frame.origin.allFinite()) {
      throw ParseError(path.string() +
                       ": \"frame\": axes are not a right-handed orthonormal frame");
    }
    return frame;
  } catch (const nlohmann::json::exception& e) {
    throw ParseError(path.string() + ": \"frame\" (" + e.what() + ")");
  }
}

Json designReportJson(const DesignedTree& d, double seconds) {
  Json j;
  j["units"] = unitSystemName(d.units);
  j["parameters"] = d.parameters.size();
  j["snapped"] = d.snappedCount();
  j["patterns"] = d.patterns.size();
  j["frame_is_world"] = d.frame.isIdentity();
  j["iou_to_fitted"] = d.iouToFitted;
  if (d.noise > 0.0) {
    j["noise"] = d.noise;
    j["mean_distance_fitted"] = d.meanDistanceFitted;
    j["mean_distance_designed"] = d.meanDistanceDesigned;
  }
  Json values = Json::array();
  double largest = 0.0;
  for (const DesignParameter& p : d.parameters) {
    if (p.kind == ParameterKind::Count) continue;
    Json q;
    q["name"] = p.name;
    q["fitted"] = p.fitted;
    q["value"] = p.value;
    q["change"] = p.value - p.fitted;
    q["uncertainty"] = number(p.uncertainty);
    q["snapped"] = p.snapped;
    if (p.snapped) largest = std::max(largest, std::abs(p.value - p.fitted));
    values.push_back(q);
  }
  j["largest_change"] = largest;
  j["values"] = values;
  j["seconds"] = seconds;
  return j;
}

}  // namespace csgvox
