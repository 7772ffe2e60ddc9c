#include "cad/brep_builder.h"

#include <BRepAdaptor_Surface.hxx>
#include <BRepAlgoAPI_Common.hxx>
#include <BRepAlgoAPI_Cut.hxx>
#include <BRepAlgoAPI_Fuse.hxx>
#include <BRepBndLib.hxx>
#include <BRepCheck_Analyzer.hxx>
#include <BRepGProp.hxx>
#include <BRepMesh_IncrementalMesh.hxx>
#include <BRepPrimAPI_MakeBox.hxx>
#include <BRepBuilderAPI_Copy.hxx>
#include <BRepPrimAPI_MakeCone.hxx>
#include <BRepPrimAPI_MakeCylinder.hxx>
#include <BRepPrimAPI_MakeSphere.hxx>
#include <BRepPrimAPI_MakeTorus.hxx>
#include <BRep_Builder.hxx>
#include <BRep_Tool.hxx>
#include <Bnd_Box.hxx>
#include <GProp_GProps.hxx>
#include <Message_ProgressIndicator.hxx>
#include <Poly_Triangulation.hxx>
#include <ShapeUpgrade_UnifySameDomain.hxx>
#include <Standard_Failure.hxx>
#include <TopExp_Explorer.hxx>
#include <TopLoc_Location.hxx>
#include <TopTools_ListOfShape.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Compound.hxx>
#include <algorithm>
#include <chrono>
#include <future>
#include <memory>
#include <thread>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <optional>
#include <random>
#include <sstream>

#include "cad/face_snapping.h"
#include "core/export_extent.h"
#include "core/solid_sampling.h"
#include "io/tree_names.h"

namespace csgvox::cad {
namespace {

gp_Pnt pnt(const Vec3& v) { return gp_Pnt(v.x(), v.y(), v.z()); }
gp_Dir dir(const Vec3& v) { return gp_Dir(v.x(), v.y(), v.z()); }

// An exact rotation (orthonormal, right-handed) closest to the frame's axes:
// the tree keeps them orthonormal only to about 1e-6.
Mat3 exactRotation(Mat3 axes) {
  if (axes.determinant() < 0.0) axes.col(2) = -axes.col(2);  // a centred box is symmetric
  return Eigen::Quaterniond(axes).normalized().toRotationMatrix();
}

TopoDS_Shape cube(const Mat3& frame, const Vec3& center, const Vec3& size) {
  const Mat3 r = exactRotation(frame);
  const Vec3 corner = center - r * (0.5 * size);
  const gp_Ax2 ax(pnt(corner), dir(r.col(2)), dir(r.col(0)));
  return BRepPrimAPI_MakeBox(ax, size.x(), size.y(), size.z()).Shape();
}

TopoDS_Shape cube(const StandInCube& c) { return cube(c.frame, c.center, Vec3::Constant(c.edge)); }

void throwIfCancelled(const RunControl& control) {
  if (control.cancelled()) throw CancelledError("the STEP export was cancelled");
}

struct Builder {
  const StepOptions& options;
  const std::unordered_map<const Node*, std::string>& names;
  Aabb extent;  // the part's extent (exportExtent): the scale of tolerances
  Aabb reach;   // what the stand-ins of unbounded sets cover (standInExtent)
  double bigEdge = 0.0;

  TopoDS_Shape primitive(const Primitive& p) const {
    if (const auto* h = p.as<HalfSpace>()) return cube(halfSpaceCube(*h, reach, bigEdge));
    if (const auto* b = p.as<Box>()) return cube(b->axes, b->center, 2.0 * b->halfSize);
    if (const auto* c = p.as<Cylinder>()) {
      const gp_Ax2 ax(pnt(c->center - 0.5 * c->height * c->axis), dir(c->axis));
      return BRepPrimAPI_MakeCylinder(ax, c->radius, c->height).Shape();
    }
    if (const auto* c = p.as<Cone>()) {
      const gp_Ax2 ax(pnt(c->center - 0.5 * c->height * c->axis), dir(c->axis));
      if (std::abs(c->radiusBottom - c->radiusTop) <= 1e-12 * (c->radiusBottom + c->radiusTop)) {
        return BRepPrimAPI_MakeCylinder(ax, c->radiusBottom, c->height).Shape();
      }
      return BRepPrimAPI_MakeCone(ax, c->radiusBottom, c->radiusTop, c->height).Shape();
    }
    if (const auto* s = p.as<Sphere>())
      return BRepPrimAPI_MakeSphere(pnt(s->center), s->radius).Shape();
    const Torus& t = std::get<Torus>(p.shape());
    return BRepPrimAPI_MakeTorus(gp_Ax2(pnt(t.center), dir(t.axis)), t.majorRadius, t.minorRadius)
        .Shape();
  }

  static std::string pathText(const NodePath& path) {
    std::string s = "root";
    for (std::size_t i : path) s += "/" + std::to_string(i);
    return s;
  }

  std::string describe(const Node& n) const {
    if (n.kind == NodeKind::Primitive) return names.at(&n);
    return std::string(nodeKindName(n.kind)) + " of " + std::to_string(n.children.size());
  }

  std::string nodeText(const Node& n, const NodePath& path) const {
    std::string s =
        "the " + std::string(nodeKindName(n.kind)) + " at node " + pathText(path) + " (";
    for (std::size_t i = 0; i < n.children.size(); ++i) {
      s += (i ? ", " : "") + describe(*n.children[i]);
    }
    return s + ")";
  }

  static bool hasSolid(const TopoDS_Shape& s) {
    return !s.IsNull() && TopExp_Explorer(s, TopAbs_SOLID).More();
  }

  // Runs one boolean; the result, std::nullopt when it is empty.
  std::optional<TopoDS_Shape> boolean(BRepAlgoAPI_BooleanOperation& op, const TopoDS_Shape& a,
                                      const TopTools_ListOfShape& tools, const Node& n,
                                      const NodePath& path) const {
    TopTools_ListOfShape args;
    args.Append(a);
    op.SetArguments(args);
    op.SetTools(tools);
    op.SetNonDestructive(true);
    if (options.fuzzy > 0.0) op.SetFuzzyValue(options.fuzzy * extent.diagonal());
    op.SetRunParallel(false);
    op.SetToFillHistory(false);
    op.Build(cancelIndicator(options.control)->Start());
    throwIfCancelled(options.control);  // before the errors: a user break is one
    if (op.HasErrors() || !op.IsDone()) {
      std::ostringstream why;
      op.DumpErrors(why);
      std::string text = why.str();
      for (char& c : text) {
        if (c == '\n' || c == '\r') c = ' ';
      }
      throw CadError("OpenCASCADE cannot compute " + nodeText(n, path) +
                     (text.empty() ? std::string() : ": " + text));
    }
    const TopoDS_Shape r = op.Shape();
    if (!hasSolid(r)) return std::nullopt;
    return r;
  }

  // The node's solid; std::nullopt when it is empty.
  std::optional<TopoDS_Shape> node(const Node& n, NodePath& path) const {
    try {
      return nodeUnchecked(n, path);
    } catch (const CadError&) {
      throw;
    } catch (const Standard_Failure& e) {
      throw CadError("OpenCASCADE cannot compute " + nodeText(n, path) + ": " +
                     e.GetMessageString());
    }
  }

  std::optional<TopoDS_Shape> child(const Node& n, std::size_t i, NodePath& path) const {
    path.push_back(i);
    auto r = node(*n.children[i], path);
    path.pop_back();
    return r;
  }

  std::optional<TopoDS_Shape> nodeUnchecked(const Node& n, NodePath& path) const {
    switch (n.kind) {
      case NodeKind::Primitive:
        return primitive(n.primitive);
      case NodeKind::Union: {
        std::vector<TopoDS_Shape> parts;
        for (std::size_t i = 0; i < n.children.size(); ++i) {
          if (auto s = child(n, i, path)) parts.push_back(*s);
        }
        if (parts.empty()) return std::nullopt;
        if (parts.size() == 1) return parts.front();
        TopTools_ListOfShape tools;
        for (std::size_t i = 1; i < parts.size(); ++i) tools.Append(parts[i]);
        BRepAlgoAPI_Fuse op;
        return boolean(op, parts.front(), tools, n, path);
      }
      case NodeKind::Intersection: {
        // One tool at a time: a boolean with several tools treats them as
        // their union.
        std::optional<TopoDS_Shape> acc = child(n, 0, path);
        for (std::size_t i = 1; acc && i < n.children.size(); ++i) {
          const auto s = child(n, i, path);
          if (!s) return std::nullopt;
          TopTools_ListOfShape tools;
          tools.Append(*s);
          BRepAlgoAPI_Common op;
          acc = boolean(op, *acc, tools, n, path);
        }
        return acc;
      }
      case NodeKind::Difference: {
        const auto base = child(n, 0, path);
        if (!base) return std::nullopt;
        TopTools_ListOfShape tools;
        for (std::size_t i = 1; i < n.children.size(); ++i) {
          if (auto s = child(n, i, path)) tools.Append(*s);
        }
        if (tools.IsEmpty()) return base;
        BRepAlgoAPI_Cut op;
        return boolean(op, *base, tools, n, path);
      }
      case NodeKind::Complement: {
        const TopoDS_Shape all = cube(surroundingCube(reach, bigEdge));
        const auto s = child(n, 0, path);
        if (!s) return all;
        TopTools_ListOfShape tools;
        tools.Append(*s);
        BRepAlgoAPI_Cut op;
        return boolean(op, all, tools, n, path);
      }
    }
    return std::nullopt;
  }
};

// The leaf whose surface holds the face: points inside the face (the centres
// of its triangles in the surface's parameters, so off its edges, which
// other surfaces share) on the leaf's surface within `tolerance`; the
// closest fit when several leaves' surfaces hold them.
const Node* faceLeaf(const TopoDS_Face& face, const std::vector<const Node*>& leaves,
                     double tolerance) {
  TopLoc_Location loc;
  const Handle(Poly_Triangulation) tri = BRep_Tool::Triangulation(face, loc);
  if (tri.IsNull() || tri->NbTriangles() == 0 || !tri->HasUVNodes()) return nullptr;
  const BRepAdaptor_Surface surface(face);  // located: points in world coordinates
  std::vector<Vec3> points;
  const int count = tri->NbTriangles();
  const int step = std::max(1, count / 32);
  for (int i = 1; i <= count; i += step) {
    int a, b, c;
    tri->Triangle(i).Get(a, b, c);
    const gp_XY uv = (tri->UVNode(a).XY() + tri->UVNode(b).XY() + tri->UVNode(c).XY()) / 3.0;
    const gp_Pnt p = surface.Value(uv.X(), uv.Y());
    points.emplace_back(p.X(), p.Y(), p.Z());
  }
  const Node* best = nullptr;
  double bestError = tolerance;
  for (const Node* leaf : leaves) {
    double worst = 0.0;
    for (std::size_t i = 0; i < points.size() && worst <= bestError; ++i) {
      worst = std::max(worst, std::abs(leaf->primitive.value(points[i])));
    }
    if (worst <= bestError && (!best || worst < bestError)) {
      best = leaf;
      bestError = worst;
    }
  }
  return best;
}

double shapeVolume(const TopoDS_Shape& shape) {
  GProp_GProps props;
  BRepGProp::VolumeProperties(shape, props);
  return props.Mass();
}

// OpenCASCADE's solid agrees with the tree's when their volumes agree
// within `tolerance` (relative) or a sliver of the box.
bool volumesAgree(double brep, double sampled, const Aabb& box, double tolerance) {
  return std::abs(brep - sampled) <= tolerance * std::max(sampled, 1e-4 * box.size().prod());
}

}  // namespace

namespace {

class CancelIndicator final : public Message_ProgressIndicator {
 public:
  explicit CancelIndicator(const RunControl& control) : control_(control) {}
  Standard_Boolean UserBreak() override { return control_.cancelled(); }
  void Show(const Message_ProgressScope&, const Standard_Boolean) override {}

 private:
  RunControl control_;  // a copy: it shares the cancel request
};

}  // namespace

Handle(Message_ProgressIndicator) cancelIndicator(const RunControl& control) {
  return new CancelIndicator(control);
}

BrepSummary summarize(const TopoDS_Shape& shape) {
  BrepSummary s;
  if (shape.IsNull()) return s;
  for (TopExp_Explorer e(shape, TopAbs_SOLID); e.More(); e.Next()) ++s.solids;
  for (TopExp_Explorer e(shape, TopAbs_FACE); e.More(); e.Next()) ++s.faces;
  s.valid = BRepCheck_Analyzer(shape).IsValid();
  s.closed = s.solids > 0;
  for (TopExp_Explorer e(shape, TopAbs_SHELL); e.More(); e.Next()) {
    if (!BRep_Tool::IsClosed(e.Current())) s.closed = false;
  }
  GProp_GProps props;
  BRepGProp::VolumeProperties(shape, props);
  s.volume = props.Mass();
  Bnd_Box box;
  BRepBndLib::AddOptimal(shape, box, false, false);
  if (!box.IsVoid()) {
    double x0, y0, z0, x1, y1, z1;
    box.Get(x0, y0, z0, x1, y1, z1);
    s.bounds.min = Vec3(x0, y0, z0);
    s.bounds.max = Vec3(x1, y1, z1);
  }
  return s;
}

namespace {

// The longest wait for OpenCASCADE to merge a built solid's faces (it takes
// under 0.05 s on every bundled part).
constexpr double kUnifySeconds = 5.0;

// A built solid: one solid, or a compound of several.
struct Candidate {
  TopoDS_Shape shape;
  std::size_t solids = 0;
  double volume = 0.0;
  bool valid = false;
};

Candidate candidate(const TopoDS_Shape& shape) {
  // Keep the solids alone (a boolean's result is a compound).
  std::vector<TopoDS_Shape> solids;
  for (TopExp_Explorer e(shape, TopAbs_SOLID); e.More(); e.Next()) solids.push_back(e.Current());
  Candidate c;
  c.solids = solids.size();
  if (solids.size() == 1) {
    c.shape = solids.front();
  } else {
    TopoDS_Compound compound;
    BRep_Builder builder;
    builder.MakeCompound(compound);
    for (const TopoDS_Shape& s : solids) builder.Add(compound, s);
    c.shape = compound;
  }
  c.volume = shapeVolume(c.shape);
  c.valid = c.solids > 0 && BRepCheck_Analyzer(c.shape).IsValid();
  return c;
}

// The candidate with the faces of one surface merged, when OpenCASCADE
// can do it within kUnifySeconds and the result is as valid (merging is
// cosmetic). Only ever given the chosen solid: on the wrong solids a boolean
// can leave, merging ran for more than ten minutes on one (part 143 of the
// InverseCSG parts), and on a right solid of 99 faces (a tree of part 155)
// it never ended. It runs on a copy of the shape in a thread of its own; past
// the limit the faces stay as built and the thread is left to end with the
// process (OpenCASCADE's merging cannot be interrupted).
Candidate unified(const Candidate& c) {
  using Result = std::optional<TopoDS_Shape>;
  auto task = std::make_shared<std::packaged_task<Result(TopoDS_Shape)>>([](TopoDS_Shape shape) {
    try {
      ShapeUpgrade_UnifySameDomain unify(shape, true, true, false);
      unify.Build();
      return Result(unify.Shape());
    } catch (const Standard_Failure&) {
      return Result();
    }
  });
  std::future<Result> merging = task->get_future();
  BRepBuilderAPI_Copy copy(c.shape);
  std::thread([task, shape = copy.Shape()]() { (*task)(shape); }).detach();
  if (merging.wait_for(std::chrono::duration<double>(kUnifySeconds)) != std::future_status::ready) {
    return c;
  }
  const Result shape = merging.get();
  if (!shape) return c;
  Candidate merged = candidate(*shape);
  if (merged.valid && merged.solids == c.solids) return merged;
  return c;
}

// The volume test of a built solid: OpenCASCADE's booleans can return a
// valid but wrong solid on nearly coincident or tangent faces, so its volume
// must be the tree's (sampled in `box`; no test when the tolerance is 0).
struct VolumeCheck {
  const StepOptions& options;
  const CsgTree& tree;
  Aabb box;
  mutable double sampled = 0.0;
  mutable bool fine = false;

  // 48 cells across the box can miss the volume by a few per cent where a
  // small part lies beside a large piece (a far cylinder's segment beside a
  // block): a solid that disagrees is judged again against a finer sample,
  // taken once.
  bool agrees(const Candidate& c) const {
    if (options.volumeTolerance <= 0.0 ||
        volumesAgree(c.volume, sampled, box, options.volumeTolerance)) {
      return true;
    }
    if (!fine) {
      sampled = sampledVolume(tree, box, 160);
      fine = true;
    }
    return volumesAgree(c.volume, sampled, box, options.volumeTolerance);
  }
  // One valid solid of the tree's volume.
  bool good(const Candidate& c) const { return c.valid && c.solids == 1 && agrees(c); }
};

// A tree tried and the solid built from it.
struct Built {
  CsgTree tree;
  Candidate solid;
};

// The tries at building the tree's solid, and the first error of those that
// built none.
struct BrepAttempts {
  const CsgTree& tree;
  const StepOptions& options;
  Aabb extent;
  Aabb reach;         // what the cubes standing in for half-spaces must cover
  double edge = 0.0;  // of those cubes
  std::vector<Built> tries{};
  std::optional<CadError> firstError{};

  // Builds `t` with booleans of the given fuzziness.
  void attempt(const CsgTree& t, double fuzzy) {
    const auto names = leafNames(t);
    StepOptions o = options;
    o.fuzzy = fuzzy;
    const Builder b{o, names, extent, reach, edge};
    try {
      NodePath path;
      const std::optional<TopoDS_Shape> shape = b.node(*t.root(), path);
      if (!shape) throw CadError("the solid is empty: no point lies inside the tree");
      tries.push_back({t, candidate(*shape)});
    } catch (const CadError& e) {
      if (!firstError) firstError = e;
    } catch (const Standard_Failure& e) {
      if (!firstError) {
        firstError =
            CadError(std::string("OpenCASCADE cannot finish the solid: ") + e.GetMessageString());
      }
    }
  }

  // Builds the tree with its near-coincident caps snapped (and onto the
  // planes tangent to its tori with `torusTangents`), when snapping moves any.
  void attemptSnapped(bool torusTangents) {
    FaceSnapOptions snap;
    snap.tolerance = options.snapTolerance * extent.diagonal();
    snap.angle = options.snapAngle;
    snap.torusTangents = torusTangents;
    const FaceSnapResult snapped = snapFaces(tree, snap);
    if (snapped.movedCaps > 0 || snapped.turnedAxes > 0) attempt(snapped.tree, options.fuzzy);
  }
};

// The first one solid of the right volume, else the first of several
// solids of the right volume (written as they are: a sliver wider than
// the snapping tolerance separates them in the tree itself); null: none.
const Built* chooseSolid(const std::vector<Built>& tries, const VolumeCheck& check) {
  for (const Built& t : tries) {
    if (check.good(t.solid)) return &t;
  }
  for (const Built& t : tries) {
    if (t.solid.valid && check.agrees(t.solid)) return &t;
  }
  return nullptr;
}

// The first operation (children before parents) whose solid disagrees with
// the tree's, as the builder `b` describes it; the root when none does.
std::string firstWrongOperation(const CsgTree& tree, const Builder& b, const Aabb& extent) {
  std::string where = b.nodeText(*tree.root(), NodePath{});
  std::function<bool(const Node&, NodePath&)> locate = [&](const Node& n, NodePath& p) {
    if (n.kind == NodeKind::Primitive) return false;
    for (std::size_t i = 0; i < n.children.size(); ++i) {
      p.push_back(i);
      const bool found = locate(*n.children[i], p);
      p.pop_back();
      if (found) return true;
    }
    const CsgTree sub(tree.nodeAt(p));
    NodePath local;
    const auto s = b.node(n, local);
    const Aabb subBox = exportExtent(sub).grown(0.01 * extent.diagonal());
    const double v = sampledVolume(sub, subBox, 48);
    if (volumesAgree(s ? shapeVolume(*s) : 0.0, v, subBox, b.options.volumeTolerance)) return false;
    where = b.nodeText(n, p);
    return true;
  };
  NodePath p;
  locate(*tree.root(), p);
  return where;
}

// Throws the error of tries that gave no solid to choose: the first
// error, or the solid that is invalid or of the wrong volume.
[[noreturn]] void failBuild(const BrepAttempts& a, const VolumeCheck& check) {
  if (a.tries.empty()) throw *a.firstError;
  const auto names = leafNames(a.tree);
  const Builder b{a.options, names, a.extent, a.reach, a.edge};
  if (check.agrees(a.tries.front().solid)) {
    throw CadError("OpenCASCADE built an invalid solid for " +
                   b.nodeText(*a.tree.root(), NodePath{}));
  }
  const std::string where = firstWrongOperation(a.tree, b, a.extent);
  char buf[160];
  std::snprintf(buf, sizeof(buf), " (the part comes out with volume %.6g instead of %.6g)",
                a.tries.front().solid.volume, check.sampled);
  throw CadError("OpenCASCADE computed a wrong solid for " + where + buf);
}

// Names each face of the shape after the leaf of `tree` whose surface holds it.
void nameFaces(BrepResult& result, const CsgTree& tree, double diagonal) {
  const auto names = leafNames(tree);
  BRepMesh_IncrementalMesh mesh(result.shape, 0.01 * diagonal, false, 0.5, false);
  const std::vector<const Node*> leaves = tree.leaves();
  for (TopExp_Explorer e(result.shape, TopAbs_FACE); e.More(); e.Next()) {
    const Node* leaf = faceLeaf(TopoDS::Face(e.Current()), leaves, 1e-6 * diagonal);
    if (leaf) result.faceNames.emplace_back(e.Current(), names.at(leaf));
  }
}

}  // namespace

BrepResult buildBrep(const CsgTree& tree, const StepOptions& options) {
  tree.validate();
  const Aabb extent = exportExtent(tree);
  const Aabb reach = standInExtent(tree);
  const double edge = options.halfSpaceScale * std::max(reach.diagonal(), 1e-9);
  const Aabb box = extent.grown(0.01 * extent.diagonal());
  const VolumeCheck check{options, tree, box,
                          options.volumeTolerance > 0.0 ? sampledVolume(tree, box, 48) : 0.0};

  BrepAttempts a{tree, options, extent, reach, edge};
  auto done = [&] { return !a.tries.empty() && check.good(a.tries.back().solid); };
  // The tree as it is; then, until one is a valid solid of the tree's
  // volume: its near-coincident caps snapped (pieces that a sliver of the
  // fit separates come together); the tree as it is with fuzzy booleans
  // (OpenCASCADE then classifies faces that nearly touch a torus right);
  // the caps snapped onto the planes tangent to the tori as well (where
  // they lie decides OpenCASCADE's result there).
  a.attempt(tree, options.fuzzy);
  if (!done() && options.snapTolerance > 0.0) a.attemptSnapped(false);
  if (!done() && options.retryFuzzy > options.fuzzy) a.attempt(tree, options.retryFuzzy);
  if (!done() && options.snapTolerance > 0.0) a.attemptSnapped(true);
  const Built* chosen = chooseSolid(a.tries, check);
  if (!chosen) failBuild(a, check);
  throwIfCancelled(options.control);

  BrepResult result;
  if (options.unifyFaces) {
    const Candidate merged = unified(chosen->solid);
    result.shape = check.agrees(merged) ? merged.shape : chosen->solid.shape;
  } else {
    result.shape = chosen->solid.shape;
  }
  throwIfCancelled(options.control);
  try {
    if (options.nameFaces) nameFaces(result, chosen->tree, extent.diagonal());
  } catch (const Standard_Failure& e) {
    throw CadError(std::string("OpenCASCADE cannot finish the solid: ") + e.GetMessageString());
  }
  return result;
}

}  // namespace csgvox::cad
