// The csgvox Python module: scans as NumPy arrays, the main job's
// reconstruction and report, and CSG trees (JSON, OpenSCAD, vectorised
// evaluation). Errors are Python exceptions with the command-line tool's
// one-line messages.

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <cstring>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "io/errors.h"
#include "io/point_arrays.h"
#include "io/scad_export.h"
#include "io/scan_reader.h"
#include "io/text_export.h"
#include "io/tree_json.h"
#include "job/console.h"
#include "job/job.h"
#include "pipeline/reconstruct.h"
#include "primitives/solver_log.h"

namespace py = pybind11;
using namespace csgvox;

namespace {

using Array = py::array_t<double, py::array::c_style | py::array::forcecast>;

// Rows of an (N, 3) array as points. @throw ParseError for another shape.
std::vector<Vec3> toVectors(const Array& a, const char* name) {
  if (a.ndim() != 2 || a.shape(1) != 3) {
    std::ostringstream shape;
    for (py::ssize_t i = 0; i < a.ndim(); ++i) shape << (i ? ", " : "") << a.shape(i);
    throw ParseError(std::string(name) + ": expected an array of shape (N, 3), got (" +
                     shape.str() + ")");
  }
  std::vector<Vec3> out(std::size_t(a.shape(0)));
  const double* d = a.data();
  for (std::size_t i = 0; i < out.size(); ++i) out[i] = Vec3(d[3 * i], d[3 * i + 1], d[3 * i + 2]);
  return out;
}

Array toArray(const std::vector<Vec3>& v) {
  Array a({py::ssize_t(v.size()), py::ssize_t(3)});
  double* d = a.mutable_data();
  for (std::size_t i = 0; i < v.size(); ++i) {
    d[3 * i] = v[i].x();
    d[3 * i + 1] = v[i].y();
    d[3 * i + 2] = v[i].z();
  }
  return a;
}

py::object toPython(const nlohmann::ordered_json& j) {
  return py::module_::import("json").attr("loads")(j.dump());
}

std::string treeJsonText(const CsgTree& tree) {
  std::ostringstream out;
  writeTreeJson(out, tree);
  return out.str();
}

CsgTree treeFromJson(const std::string& text) {
  std::istringstream in(text);
  return readTreeJson(in, "<json>");
}

/// A reconstruction's tree and its report.json content.
struct Result {
  CsgTree tree;
  py::object report;
};

Result reconstructArrays(const Array& points, const std::optional<Array>& normals, int res,
                         std::uint64_t seed, const std::string& method, const std::string& label,
                         const std::string& labelBoundary, double timeLimit) {
  JobOptions job;
  ReconstructOptions& options = job.reconstruct;
  options.resolution = res;
  options.seed = seed;
  options.method = methodFromName(method);
  options.labels.method = labelMethodFromName(label);
  options.labels.boundary =
      valueNamed<BoundaryRule>(kBoundaryRuleNames, labelBoundary, "label boundary");
  job.timeLimit = timeLimit;
  validate(options);
  checkRange("time_limit", timeLimit, option_ranges::timeLimit);

  std::vector<Vec3> p = toVectors(points, "points");
  std::vector<Vec3> n = normals ? toVectors(*normals, "normals") : std::vector<Vec3>{};
  nlohmann::ordered_json report;
  Result result;
  {
    py::gil_scoped_release release;
    ReadOptions ro;
    ro.seed = seed;
    Stopwatch watch;
    const Scan scan = scanFromArrays(std::move(p), std::move(n), "points", ro);
    options.detect.estimatedNormals = scan.info.normalsEstimated;
    StepTimes timings;
    timings.add("read", watch.seconds(), watch.cpuSeconds());
    const Reconstruction rec = reconstruct(scan.cloud, options, {}, RunControl(timeLimit));
    for (const StageTime& t : rec.timings) timings.add(t.stage, t.seconds, t.cpuSeconds);
    if (!rec.ok()) throw ParseError("points: " + rec.message);
    const Console quiet(true);
    report = reportWithoutFiles("<array>", scan, rec, job, timings, quiet);
    result.tree = rec.tree;
  }
  result.report = toPython(report);
  return result;
}

py::array_t<double> evaluateTree(const CsgTree& tree, const Array& points) {
  const std::vector<Vec3> p = toVectors(points, "points");
  py::array_t<double> out(py::ssize_t(p.size()));
  {
    py::gil_scoped_release release;
    tree.values(p, std::span<double>(out.mutable_data(), p.size()));
  }
  return out;
}

}  // namespace

PYBIND11_MODULE(csgvox, m) {
  m.doc() =
      "csgvox: from a 3D scan of a mechanical part to a compact, editable CSG tree.\n\n"
      "read_scan(path) -> (points, normals); reconstruct(points, normals=None, res=64, seed=1,\n"
      "method=...) -> Result(.tree, .report); Tree.to_json(), to_scad(), to_text(),\n"
      "evaluate(points), Tree.from_json(text).";
  m.attr("__version__") = "0.1.0";
  // As the command line: the solver's per-step warnings of a fit that
  // recovers are not news for the user; its errors still reach stderr.
  csgvox::setSolverLog(csgvox::SolverLog::Errors);

  // The library's exceptions keep their one-line messages.
  static py::exception<IoError> ioError(m, "IoError", PyExc_OSError);
  static py::exception<ParseError> parseError(m, "ParseError", PyExc_ValueError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const IoError& e) {
      PyErr_SetString(ioError.ptr(), e.what());
    } catch (const ParseError& e) {
      PyErr_SetString(parseError.ptr(), e.what());
    }
  });

  py::class_<CsgTree>(m, "Tree", "A CSG tree (an FRep: f >= 0 inside the solid).")
      .def_static("from_json", &treeFromJson, py::arg("text"),
                  "A tree from the text of a tree.json. Raises ParseError for an invalid tree.")
      .def("to_json", &treeJsonText, "The tree.json text (numbers round-trip exactly).")
      .def(
          "to_scad",
          [](const CsgTree& t) {
            std::ostringstream out;
            writeScad(out, t);
            return out.str();
          },
          "The tree.scad text: an OpenSCAD program.")
      .def(
          "to_text",
          [](const CsgTree& t) {
            std::ostringstream out;
            writeTreeText(out, t);
            return out.str();
          },
          "The tree.txt text: the expression and one definition per primitive.")
      .def("evaluate", &evaluateTree, py::arg("points"),
           "Signed distances of an (N, 3) array of points: an (N,) array, >= 0 inside.")
      .def_property_readonly("primitives", &CsgTree::primitiveCount, "Leaves of the tree.")
      .def_property_readonly("operations", &CsgTree::operationCount, "Operations of the tree.")
      .def_property_readonly("depth", &CsgTree::depth, "Levels of the tree (1 for one leaf).")
      .def("__repr__", [](const CsgTree& t) {
        return "<csgvox.Tree: " + std::to_string(t.primitiveCount()) + " primitives, " +
               std::to_string(t.operationCount()) + " operations>";
      });

  py::class_<Result>(m, "Result", "A reconstruction: the tree and its report.")
      .def_readonly("tree", &Result::tree, "The CSG tree.")
      .def_readonly("report", &Result::report, "The report.json content, as a dict.")
      .def("__repr__", [](const Result& r) {
        return "<csgvox.Result: " + std::to_string(r.tree.primitiveCount()) + " primitives>";
      });

  m.def(
      "read_scan",
      [](const std::filesystem::path& path, std::size_t meshSamples, std::uint64_t seed) {
        ReadOptions ro;
        ro.meshSamples = meshSamples;
        ro.seed = seed;
        Scan scan;
        {
          py::gil_scoped_release release;
          scan = readScan(path, ro);
        }
        return py::make_tuple(toArray(scan.cloud.points), toArray(scan.cloud.normals));
      },
      py::arg("path"), py::arg("mesh_samples") = 100000, py::arg("seed") = 1,
      "Reads a scan file (PLY, XYZ, XYZN, OFF, OBJ, STL) as (points, normals), two (N, 3)\n"
      "float64 arrays; missing normals are estimated, meshes sampled. Raises IoError or\n"
      "ParseError with the file's name and the problem.");

  m.def("reconstruct", &reconstructArrays, py::arg("points"), py::arg("normals") = py::none(),
        py::arg("res") = 64, py::arg("seed") = 1,
        py::arg("method") = std::string(methodName(ReconstructOptions().method)),
        py::arg("label") = "winding", py::arg("label_boundary") = "centre",
        py::arg("time_limit") = 0.0,
        "The main job on an (N, 3) array of points with outward normals (estimated when\n"
        "None): a Result whose .tree is the CSG tree and .report the fields of report.json.\n"
        "The same points, normals, options and seed give the tree `csgvox SCAN` writes.\n"
        "Runs without the GIL. Raises ParseError when the points are invalid or no tree\n"
        "explains them, ValueError for a bad option.");
}
