#pragma once
/// Reading scans: point clouds (PLY, XYZ, XYZN) and meshes (PLY with faces,
/// OFF, OBJ, STL) become points with unit outward normals. Normals missing
/// from a point cloud are estimated; meshes are sampled by area.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <iosfwd>
#include <string>
#include <vector>

#include "core/point_cloud.h"

namespace csgvox {

/// Options of readScan.
struct ReadOptions {
  std::size_t meshSamples = 100000;  ///< points sampled from a mesh input, area-weighted (count)
  std::uint64_t seed = 1;            ///< seed of the mesh sampling; same seed, same points
  int normalNeighbors = 18;  ///< k nearest neighbours for estimating missing normals (count, >= 6)
  /// Given normals are replaced by estimated ones when fewer than this
  /// fraction of the points agree with their local surface (normalAgreement
  /// over normalNeighbors neighbours); the bundled scans read 0.72 to 1,
  /// random normals 0.1 to 0.18. 0 keeps given normals always (fraction, 0..1).
  double minNormalAgreement = 0.5;
  std::size_t minPoints = 100;  ///< a scan with fewer points is rejected (count)
  /// Point clouds lose their outliers (scattered points, points off the
  /// surface such as mixed pixels) before anything else (findOutliers).
  bool removeOutliers = true;
};

/// What readScan found in the file.
struct ScanInfo {
  /// Format that was read: "ply-ascii", "ply-binary-le", "ply-binary-be",
  /// "xyz", "xyzn", "off-mesh", "obj-mesh", "stl-ascii-mesh",
  /// "stl-binary-mesh", or a PLY format with "-mesh" appended.
  std::string format;
  bool fromMesh = false;          ///< the points were sampled from the faces of a mesh
  std::size_t meshFaces = 0;      ///< faces in the mesh file as written (0 for a point cloud)
  bool normalsEstimated = false;  ///< the normals were estimated (the file had none, or
                                  ///< normalsReplaced)
  bool normalsReplaced = false;   ///< the file's normals disagreed with the surface and were
                                  ///< replaced by estimated ones
  /// Fraction of the file's normals that agree with the local surface
  /// (normalAgreement); -1 when the file had no normals or is a mesh.
  double normalAgreement = -1.0;
  std::size_t pointsRead = 0;  ///< points (for a mesh: vertices) read from the file
  /// The files read into the scan, as given, when there are several
  /// (readScans); empty for one file.
  std::vector<std::string> files;
  /// Points of a point cloud removed as outliers (count; 0 for a mesh):
  /// scattered ones plus offSurfaceRemoved.
  std::size_t outliersRemoved = 0;
  /// Of outliersRemoved, those off the surface of their neighbours (mixed
  /// pixels at depth edges) rather than scattered (count).
  std::size_t offSurfaceRemoved = 0;
};

/// A scan read from a file.
struct Scan {
  PointCloud cloud;  ///< the points, each with a unit outward normal
  ScanInfo info;     ///< how they were obtained
};

/// Kind of scan file; readScan(path) picks it from the file's extension.
enum class ScanFileType {
  Ply,  ///< .ply: a point cloud, or a mesh when it has a non-empty face element
  Xyz,  ///< .xyz, .xyzn, .pts, .txt: "x y z" or "x y z nx ny nz" per line
  Off,  ///< .off: a polygon mesh (ASCII; OFF, COFF, NOFF, STOFF, 4OFF)
  Obj,  ///< .obj: a polygon mesh (only "v" and "f" lines matter)
  Stl,  ///< .stl: a triangle mesh, ASCII or binary
};

/// Reads a scan from a file whose type is given by its extension
/// (case-insensitive): .ply, .xyz, .xyzn, .pts, .txt, .off, .obj, .stl.
///
/// A point cloud keeps its points; given normals are normalised, missing
/// normals are estimated (estimateNormals with options.normalNeighbors), and
/// so are given normals of which fewer than options.minNormalAgreement agree
/// with the local surface (normals in random directions, or of another scan).
/// A mesh yields options.meshSamples points drawn uniformly by area, each with
/// the normal of its face, oriented outwards (consistently oriented soup,
/// positive enclosed volume).
/// @throw IoError "<path>: ..." when the file is missing, a directory or
///        another kind of file that is not a regular file (a FIFO, a device),
///        unreadable, or has an unsupported extension.
/// @throw ParseError "<path>: ..." when the content is not a valid scan:
///        empty, garbled or truncated, more data than a PLY header declares,
///        a line with another number of values than its header or (XYZ) the
///        first line, a word that is not a finite number, zero-length
///        normals, fewer than options.minPoints points, a mesh without faces
///        or with zero area, or a point cloud whose points all lie on one
///        plane within its noise (one view of a flat face).
/// @throw std::invalid_argument when options are invalid (normalNeighbors
///        < 6, minNormalAgreement outside 0..1, meshSamples < minPoints for
///        a mesh).
Scan readScan(const std::filesystem::path& path, const ReadOptions& options = {});

/// Reads several point-cloud files that are already in one frame (a
/// scanner's exports of its views or setups) as one scan: their points are
/// put together, then treated as readScan() treats one file's (missing
/// normals estimated on the whole). Normals are kept only when every file
/// has them. options.minPoints applies to the whole; info.format is the
/// first file's, info.pointsRead the sum, info.files the paths. One path:
/// readScan(path).
/// @throw IoError / ParseError as readScan(path), naming the file; ParseError
///        when a file is a mesh (a mesh is a whole part, not a view of one)
///        or the files together have fewer than options.minPoints points.
/// @throw std::invalid_argument when `paths` is empty or options are invalid.
Scan readScans(const std::vector<std::filesystem::path>& paths, const ReadOptions& options = {});

/// Reads a scan of the given type from a stream opened in binary mode. The
/// stream must be seekable (an std::ifstream or std::stringstream) and is
/// read from position 0 to its end. `source` names the input in error
/// messages. Otherwise as readScan(path).
/// @throw ParseError "<source>: ..." for invalid content (as readScan(path)).
/// @throw IoError when the stream cannot be read or is not seekable.
/// @throw std::invalid_argument for invalid options.
Scan readScan(std::istream& in, ScanFileType type, const std::string& source = "<stream>",
              const ReadOptions& options = {});

/// The scan file type named by the extension of `path` (case-insensitive).
/// @throw IoError "<path>: unsupported scan file extension ..." otherwise.
ScanFileType scanFileTypeFromPath(const std::filesystem::path& path);

}  // namespace csgvox
