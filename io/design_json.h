#pragma once
/// The designed tree in JSON: tree.json's `frame`, `units`, `parameters`
/// and `patterns` (beside the explicit primitives of `root`), and the
/// `design` section of report.json (what was snapped and by how much).
/// Documented in docs/formats.md.

#include <filesystem>
#include <iosfwd>
#include <nlohmann/json.hpp>
#include <optional>

#include "design/designed_tree.h"

namespace csgvox {

/// tree.json of a designed tree: the designed tree's primitives (world
/// coordinates, leaves named by role) under "root", then "frame", "units",
/// "parameters" and "patterns". @throw std::invalid_argument for an empty tree.
void writeDesignedTreeJson(std::ostream& out, const DesignedTree& design);
/// Writes it to `path` atomically. @throw IoError, std::invalid_argument.
void writeDesignedTreeJson(const std::filesystem::path& path, const DesignedTree& design);

/// The "frame" a tree.json records, or nothing when it has none.
/// @throw IoError when the file cannot be read; ParseError when its frame is malformed.
std::optional<PartFrame> readTreeFrame(const std::filesystem::path& path);

/// report.json's "design": units, parameters and how many were snapped,
/// each snapped value with its fitted value and change, patterns, the IoU
/// against the fitted tree and the points' mean distance to both trees.
nlohmann::ordered_json designReportJson(const DesignedTree& design, double seconds);

}  // namespace csgvox
