#pragma once
/// JSON reports (report.json, surfaces.json, candidates.json) and scan
/// descriptions.

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "io/scan_reader.h"
#include "primitives/hypotheses.h"
#include "primitives/surface_detection.h"

namespace csgvox {

/// Writes a JSON document, indented, atomically.
/// @throw IoError when the file cannot be written.
void writeJsonFile(const std::filesystem::path& path, const nlohmann::ordered_json& json);

/// One line describing a scan: points, format, bounds, normals.
std::string describeScan(const Scan& scan);
/// The scan's description as JSON.
nlohmann::ordered_json scanJson(const std::filesystem::path& path, const Scan& scan);
/// [x, y, z] as a JSON array.
nlohmann::ordered_json toJson(const Vec3& v);

/// surfaces.json: the scan's name, D, the noise, epsilon and every surface
/// (format in README.md, "File formats").
nlohmann::ordered_json surfacesJson(const std::string& scanName, const DetectionResult& detection);
/// candidates.json: counts per origin, whether the cap removed some, and
/// every candidate with its tree (format in README.md, "File formats").
nlohmann::ordered_json candidatesJson(const std::string& scanName, const HypothesisSet& hypotheses);

}  // namespace csgvox
