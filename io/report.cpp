#include "io/report.h"

#include <cstdio>
#include <ostream>

#include "io/file_util.h"
#include "io/tree_json.h"

namespace csgvox {

void writeJsonFile(const std::filesystem::path& path, const nlohmann::ordered_json& json) {
  writeFileAtomically(path, [&](std::ostream& out) { out << json.dump(2) << "\n"; });
}

nlohmann::ordered_json toJson(const Vec3& v) { return {v.x(), v.y(), v.z()}; }

std::string describeScan(const Scan& scan) {
  const Aabb b = scan.cloud.bounds();
  const Vec3 s = b.size();
  char normals[128] = "normals given";
  if (scan.info.normalsReplaced) {
    std::snprintf(normals, sizeof(normals),
                  "normals re-estimated (%.0f %% of the given ones agreed with the surface)",
                  100.0 * scan.info.normalAgreement);
  } else if (scan.info.normalsEstimated) {
    std::snprintf(normals, sizeof(normals), "normals estimated");
  }
  char files[64] = "";
  if (!scan.info.files.empty()) {
    std::snprintf(files, sizeof(files), " from %zu files", scan.info.files.size());
  }
  char removed[128] = "";
  if (scan.info.outliersRemoved > 0) {
    std::snprintf(removed, sizeof(removed), ", removed %zu outliers (%zu off the surface)",
                  scan.info.outliersRemoved, scan.info.offSurfaceRemoved);
  }
  char buf[640];
  std::snprintf(buf, sizeof(buf),
                "%zu points%s (%s%s), size %.4g x %.4g x %.4g, diagonal %.4g, %s%s",
                scan.cloud.size(), files, scan.info.format.c_str(),
                scan.info.fromMesh ? ", sampled from a mesh" : "", s.x(), s.y(), s.z(),
                b.diagonal(), normals, removed);
  return buf;
}

nlohmann::ordered_json scanJson(const std::filesystem::path& path, const Scan& scan) {
  const Aabb b = scan.cloud.bounds();
  nlohmann::ordered_json j;
  j["file"] = path.string();
  if (!scan.info.files.empty()) j["files"] = scan.info.files;
  j["format"] = scan.info.format;
  j["points"] = scan.cloud.size();
  j["from_mesh"] = scan.info.fromMesh;
  if (scan.info.fromMesh) j["mesh_faces"] = scan.info.meshFaces;
  if (!scan.info.fromMesh) {
    j["outliers_removed"] = scan.info.outliersRemoved;
    j["off_surface_removed"] = scan.info.offSurfaceRemoved;
  }
  j["normals"] = scan.info.normalsReplaced    ? "re-estimated"
                 : scan.info.normalsEstimated ? "estimated"
                                              : "given";
  if (scan.info.normalAgreement >= 0.0) j["normal_agreement"] = scan.info.normalAgreement;
  j["bounds_min"] = toJson(b.min);
  j["bounds_max"] = toJson(b.max);
  j["diagonal"] = b.diagonal();
  return j;
}

namespace {

nlohmann::ordered_json surfaceJson(const Surface& s) {
  nlohmann::ordered_json j;
  j["type"] = std::string(surfaceTypeName(s.type()));
  j["inliers"] = s.inliers.size();
  j["rms"] = s.rms;
  if (s.type() != SurfaceType::Plane) j["convex"] = s.convex;
  if (const auto* p = s.as<PlaneSurface>()) {
    j["normal"] = toJson(p->normal);
    j["offset"] = p->offset;
  } else if (const auto* c = s.as<CylinderSurface>()) {
    j["axis_point"] = toJson(c->axisPoint);
    j["axis_dir"] = toJson(c->axisDir);
    j["radius"] = c->radius;
  } else if (const auto* c = s.as<ConeSurface>()) {
    j["apex"] = toJson(c->apex);
    j["axis_dir"] = toJson(c->axisDir);
    j["half_angle"] = c->halfAngle;
  } else if (const auto* sp = s.as<SphereSurface>()) {
    j["center"] = toJson(sp->center);
    j["radius"] = sp->radius;
  } else if (const auto* t = s.as<TorusSurface>()) {
    j["center"] = toJson(t->center);
    j["axis_dir"] = toJson(t->axisDir);
    j["major_radius"] = t->majorRadius;
    j["minor_radius"] = t->minorRadius;
  }
  return j;
}

}  // namespace

nlohmann::ordered_json surfacesJson(const std::string& scanName, const DetectionResult& detection) {
  nlohmann::ordered_json surfaces = nlohmann::ordered_json::array();
  for (const Surface& s : detection.surfaces) surfaces.push_back(surfaceJson(s));
  nlohmann::ordered_json j;
  j["scan"] = scanName;
  j["diagonal"] = detection.diagonal;
  j["noise"] = detection.noise;
  j["normal_noise"] = detection.normalNoise;
  j["epsilon"] = detection.epsilon;
  j["surfaces"] = std::move(surfaces);
  return j;
}

nlohmann::ordered_json candidatesJson(const std::string& scanName,
                                      const HypothesisSet& hypotheses) {
  nlohmann::ordered_json candidates = nlohmann::ordered_json::array();
  for (const Candidate& c : hypotheses.candidates) {
    nlohmann::ordered_json j;
    j["origin"] = std::string(candidateOriginName(c.origin));
    j["surfaces"] = c.surfaces;
    j["support"] = c.support;
    if (c.tool) j["tool"] = true;
    j["tree"] = treeNodeToJson(c.tree);
    candidates.push_back(std::move(j));
  }
  nlohmann::ordered_json counts;
  for (std::size_t o = 0; o < kCandidateOriginCount; ++o) {
    counts[std::string(candidateOriginName(CandidateOrigin(o)))] =
        hypotheses.stats.returned.count[o];
  }
  nlohmann::ordered_json j;
  j["scan"] = scanName;
  j["counts"] = counts;
  j["capped"] = hypotheses.stats.capped;
  j["candidates"] = std::move(candidates);
  return j;
}

}  // namespace csgvox
