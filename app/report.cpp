#include "app/report.h"

#include "io/file_util.h"

#include <cstdio>
#include <ostream>

namespace csgvox::app {

void Report::write(const std::filesystem::path& path) const {
  writeFileAtomically(path, [&](std::ostream& out) { out << json.dump(2) << "\n"; });
}

nlohmann::ordered_json toJson(const Vec3& v) { return {v.x(), v.y(), v.z()}; }

std::string describeScan(const Scan& scan) {
  const Aabb b = scan.cloud.bounds();
  const Vec3 s = b.size();
  char buf[512];
  std::snprintf(buf, sizeof(buf), "%zu points (%s%s), size %.4g x %.4g x %.4g, diagonal %.4g, %s",
                scan.cloud.size(), scan.info.format.c_str(),
                scan.info.fromMesh ? ", sampled from a mesh" : "", s.x(), s.y(), s.z(),
                b.diagonal(), scan.info.normalsEstimated ? "normals estimated" : "normals given");
  return buf;
}

nlohmann::ordered_json scanJson(const std::filesystem::path& path, const Scan& scan) {
  const Aabb b = scan.cloud.bounds();
  nlohmann::ordered_json j;
  j["file"] = path.string();
  j["format"] = scan.info.format;
  j["points"] = scan.cloud.size();
  j["from_mesh"] = scan.info.fromMesh;
  if (scan.info.fromMesh) j["mesh_faces"] = scan.info.meshFaces;
  j["normals"] = scan.info.normalsEstimated ? "estimated" : "given";
  j["bounds_min"] = toJson(b.min);
  j["bounds_max"] = toJson(b.max);
  j["diagonal"] = b.diagonal();
  return j;
}

}  // namespace csgvox::app
