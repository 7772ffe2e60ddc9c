#pragma once
/// report.json and scan descriptions for the command-line tool.

#include "io/scan_reader.h"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>

namespace csgvox::app {

/// A JSON report, written atomically.
struct Report {
  nlohmann::ordered_json json;
  void write(const std::filesystem::path& path) const;
};

/// One line describing a scan: points, format, bounds, normals.
std::string describeScan(const Scan& scan);
/// The scan's description as JSON.
nlohmann::ordered_json scanJson(const std::filesystem::path& path, const Scan& scan);
/// [x, y, z] as a JSON array.
nlohmann::ordered_json toJson(const Vec3& v);

}  // namespace csgvox::app
