#include "io/gp_files.h"

#include <array>
#include <cctype>
#include <cmath>
#include <fstream>
#include <istream>
#include <numbers>
#include <stdexcept>
#include <string_view>
#include <utility>

#include "core/clipped_solid.h"
#include "io/errors.h"
#include "io/file_util.h"
#include "io/reader_support.h"

namespace csgvox {

namespace {

using detail::parseError;

// A word of the input for a message: at most 40 characters, bytes that are
// not printable shown as '?'.
std::string quoted(std::string_view word) {
  constexpr std::size_t kMax = 40;
  std::string out = "'";
  for (std::size_t i = 0; i < word.size() && i < kMax; ++i) {
    const auto c = static_cast<unsigned char>(word[i]);
    out += std::isprint(c) ? static_cast<char>(c) : '?';
  }
  if (word.size() > kMax) out += "...";
  return out + "'";
}

// ---------------------------------------------------------------------------
// .fit primitives

struct FitType {
  std::string_view name;
  SurfaceType type;
  std::size_t numbers;
  std::string_view layout;  // for messages
};

constexpr std::array<FitType, 5> kFitTypes = {{
    {"plane", SurfaceType::Plane, 4, "nx ny nz d"},
    {"sphere", SurfaceType::Sphere, 4, "cx cy cz r"},
    {"cylinder", SurfaceType::Cylinder, 7, "ax ay az px py pz r"},
    {"cone", SurfaceType::Cone, 7, "ax ay az cx cy cz angle"},
    {"torus", SurfaceType::Torus, 8, "nx ny nz cx cy cz r_minor r_major"},
}};

const FitType* findFitType(std::string_view name) {
  for (const FitType& t : kFitTypes) {
    if (t.name == name) return &t;
  }
  return nullptr;
}

// Parses one non-empty .fit line; `fail(problem)` returns the ParseError to
// throw, with the line's location.
template <class Fail>
SurfaceShape parseFitLine(const std::vector<std::string_view>& words, const Fail& fail) {
  const FitType* type = findFitType(words.front());
  if (type == nullptr) {
    throw fail("unknown primitive type " + quoted(words.front()) +
               " (expected plane, sphere, cylinder, cone or torus)");
  }
  if (words.size() - 1 != type->numbers) {
    throw fail(std::string(type->name) + " needs " + std::to_string(type->numbers) + " numbers (" +
               std::string(type->layout) + "), got " + std::to_string(words.size() - 1));
  }
  std::vector<double> v(type->numbers);
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (!detail::parseFinite(words[i + 1], v[i])) {
      throw fail(quoted(words[i + 1]) + " is not a finite number");
    }
  }
  // The length of the vector at v[first]; stableNorm does not overflow.
  const auto length = [&](std::size_t first, const char* what) {
    const double len = Vec3(v[first], v[first + 1], v[first + 2]).stableNorm();
    if (!(len > 0.0) || !std::isfinite(len)) throw fail(std::string(what) + " has zero length");
    return len;
  };
  const auto unit = [&](std::size_t first, const char* what) {
    return Vec3(Vec3(v[first], v[first + 1], v[first + 2]) / length(first, what));
  };
  const auto positive = [&](double x, const char* what) {
    if (!(x > 0.0)) throw fail(std::string(what) + " must be > 0");
    return x;
  };
  switch (type->type) {
    case SurfaceType::Plane: {
      // f = d - n·x >= 0 inside: the solid {n·x <= d}.
      const double len = length(0, "plane normal");
      return PlaneSurface{Vec3(Vec3(v[0], v[1], v[2]) / len), v[3] / len};
    }
    case SurfaceType::Sphere:
      return SphereSurface{Vec3(v[0], v[1], v[2]), positive(v[3], "sphere radius")};
    case SurfaceType::Cylinder: {
      const Vec3 axis = unit(0, "cylinder axis");
      return CylinderSurface{Vec3(v[3], v[4], v[5]), axis, positive(v[6], "cylinder radius")};
    }
    case SurfaceType::Cone: {
      const Vec3 axis = unit(0, "cone axis");
      if (!(v[6] > 0.0) || !(v[6] < 0.5 * std::numbers::pi)) {
        throw fail("cone half-angle must be in (0, pi/2) radians");
      }
      return ConeSurface{Vec3(v[3], v[4], v[5]), axis, v[6]};
    }
    case SurfaceType::Torus: {
      const Vec3 axis = unit(0, "torus axis");
      const double minor = positive(v[6], "torus minor radius");
      const double major = positive(v[7], "torus major radius");
      if (minor > major)
        throw fail("torus minor radius exceeds its major radius (a spindle torus)");
      TorusSurface t;
      t.center = Vec3(v[3], v[4], v[5]);
      t.axisDir = axis;
      t.majorRadius = major;
      t.minorRadius = minor;
      return t;
    }
  }
  throw fail("unknown primitive type");
}

// ---------------------------------------------------------------------------
// Expressions

enum class GpOperation { Union, Intersection, Subtraction, Negation };

struct GpOperationName {
  std::string_view name;
  GpOperation op;
  std::size_t arity;
};

constexpr std::array<GpOperationName, 4> kOperations = {{
    {"union", GpOperation::Union, 2},
    {"intersection", GpOperation::Intersection, 2},
    {"subtraction", GpOperation::Subtraction, 2},
    {"negation", GpOperation::Negation, 1},
}};

const GpOperationName* findOperation(std::string_view name) {
  for (const GpOperationName& o : kOperations) {
    if (o.name == name) return &o;
  }
  return nullptr;
}

// An operation whose ']' has not been read yet.
struct Frame {
  const GpOperationName* op;
  std::vector<CsgTree> operands;
};

// Reads an expression text without recursion (deep input cannot overflow
// the stack).
class ExpressionParser {
 public:
  ExpressionParser(std::string_view text, std::span<const GpPrimitive> primitives, const Aabb& box,
                   const std::string& source)
      : text_(text),
        primitives_(primitives),
        box_(box),
        source_(source),
        leaves_(primitives.size()) {}

  CsgTree parse() {
    skipBlanks();
    if (pos_ == text_.size()) parseError(source_, "empty expression");
    std::vector<Frame> stack;
    while (true) {
      // An operand: an operation (pushed) or a leaf.
      skipBlanks();
      const std::size_t at = pos_;
      const std::string_view word = readWord();
      if (word.empty()) {
        if (pos_ == text_.size()) failEnd(stack.size());
        fail(at, "expected an operation or a leaf, found " + quoted(text_.substr(at, 1)));
      }
      skipBlanks();
      const GpOperationName* op = findOperation(word);
      if (op != nullptr) {
        if (!consume('[')) fail(pos_, "expected '[' after " + quoted(word));
        if (stack.size() >= kMaxGpNesting) {
          fail(at, "the expression is nested more than " + std::to_string(kMaxGpNesting) +
                       " levels deep");
        }
        stack.push_back({op, {}});
        continue;
      }
      CsgTree value = leaf(word, at);
      // Close every operation this operand completes.
      while (true) {
        if (stack.empty()) {
          skipBlanks();
          if (pos_ != text_.size()) {
            fail(pos_, "unexpected text after the expression: " + quoted(text_.substr(pos_, 20)));
          }
          return value;
        }
        Frame& top = stack.back();
        top.operands.push_back(std::move(value));
        skipBlanks();
        const std::size_t here = pos_;
        if (consume(',')) {
          if (top.operands.size() >= top.op->arity) fail(here, arityProblem(top, true));
          break;  // read the next operand
        }
        if (consume(']')) {
          if (top.operands.size() != top.op->arity) fail(here, arityProblem(top, false));
          value = build(top);
          stack.pop_back();
          continue;
        }
        if (pos_ == text_.size()) failEnd(stack.size());
        fail(here, "expected ',' or ']', found " + quoted(text_.substr(here, 1)));
      }
    }
  }

 private:
  void skipBlanks() {
    while (pos_ < text_.size() && std::isspace(static_cast<unsigned char>(text_[pos_]))) ++pos_;
  }

  bool consume(char c) {
    if (pos_ < text_.size() && text_[pos_] == c) {
      ++pos_;
      return true;
    }
    return false;
  }

  // Letters, digits and '_' (a name or a leaf).
  std::string_view readWord() {
    const std::size_t start = pos_;
    while (pos_ < text_.size()) {
      const auto c = static_cast<unsigned char>(text_[pos_]);
      if (!std::isalnum(c) && c != '_') break;
      ++pos_;
    }
    return text_.substr(start, pos_ - start);
  }

  // The leaf named `word` (TYPE + index), read at offset `at`.
  CsgTree leaf(std::string_view word, std::size_t at) {
    std::size_t split = word.size();
    while (split > 0 && std::isdigit(static_cast<unsigned char>(word[split - 1]))) --split;
    const std::string_view type = word.substr(0, split);
    const std::string_view digits = word.substr(split);
    if (findFitType(type) == nullptr || digits.empty()) {
      fail(at, quoted(word) +
                   " is neither an operation (union, intersection, subtraction, negation) nor a "
                   "leaf (plane, sphere, cylinder, cone or torus followed by an index)");
    }
    std::uint64_t index = 0;
    if (!detail::parseCount(digits, index) || index >= primitives_.size()) {
      fail(at, quoted(word) + " indexes line " + std::string(digits) + ", but the .fit file has " +
                   std::to_string(primitives_.size()) + " primitives (lines 0 to " +
                   std::to_string(primitives_.size() - 1) + ")");
    }
    const GpPrimitive& prim = primitives_[index];
    const std::string_view actual = surfaceTypeName(static_cast<SurfaceType>(prim.shape.index()));
    if (actual != type) {
      fail(at, quoted(word) + ": primitive " + std::to_string(index) + " of the .fit file is a " +
                   std::string(actual) + " (" + prim.name + ")");
    }
    std::optional<CsgTree>& cached = leaves_[index];
    if (!cached) {
      try {
        cached = CsgTree::leaf(clippedSolid(prim.shape, box_), prim.name);
      } catch (const std::invalid_argument& e) {
        fail(at, quoted(word) + ": " + e.what());
      }
    }
    return *cached;
  }

  static std::string arityProblem(const Frame& frame, bool tooMany) {
    const std::size_t arity = frame.op->arity;
    return std::string(frame.op->name) + " takes " + std::to_string(arity) + " operand" +
           (arity == 1 ? "" : "s") + ", " +
           (tooMany ? "got more" : "got " + std::to_string(frame.operands.size()));
  }

  static CsgTree build(const Frame& frame) {
    switch (frame.op->op) {
      case GpOperation::Union:
        return CsgTree::unite(frame.operands);
      case GpOperation::Intersection:
        return CsgTree::intersect(frame.operands);
      case GpOperation::Subtraction:
        return CsgTree::subtract(frame.operands);
      case GpOperation::Negation:
        return CsgTree::complement(frame.operands.front());
    }
    return {};
  }

  // "line L, column C" of a byte offset (1-based).
  std::string location(std::size_t offset) const {
    std::size_t line = 1, column = 1;
    for (std::size_t i = 0; i < offset && i < text_.size(); ++i) {
      if (text_[i] == '\n') {
        ++line;
        column = 1;
      } else {
        ++column;
      }
    }
    return "line " + std::to_string(line) + ", column " + std::to_string(column);
  }

  [[noreturn]] void fail(std::size_t offset, const std::string& problem) const {
    parseError(source_, location(offset) + ": " + problem);
  }

  [[noreturn]] void failEnd(std::size_t open) const {
    fail(text_.size(),
         "unexpected end of the expression (" + std::to_string(open) + " unclosed '[')");
  }

  std::string_view text_;
  std::span<const GpPrimitive> primitives_;
  Aabb box_;
  const std::string& source_;
  std::vector<std::optional<CsgTree>> leaves_;  // one shared leaf per used primitive
  std::size_t pos_ = 0;
};

void requireUsableBox(const Aabb& box) {
  if (box.isEmpty() || !box.isBounded()) {
    throw std::invalid_argument("the clip box is empty or unbounded");
  }
}

}  // namespace

std::vector<GpPrimitive> readGpPrimitives(std::istream& in, const std::string& source) {
  std::vector<GpPrimitive> primitives;
  std::string line;
  std::size_t lineIndex = 0;
  std::size_t firstBlank = 0;
  bool pendingBlank = false;  // blank lines seen since the last primitive
  for (; std::getline(in, line); ++lineIndex) {
    const std::vector<std::string_view> words = detail::splitWords(line);
    if (words.empty()) {
      if (!pendingBlank) firstBlank = lineIndex;
      pendingBlank = true;
      continue;
    }
    if (pendingBlank) {
      parseError(source, "line " + std::to_string(firstBlank + 1) + " (index " +
                             std::to_string(firstBlank) +
                             ") is empty; a primitive's index is its line number, so only the "
                             "end of the file may be blank");
    }
    const auto fail = [&](const std::string& problem) {
      return ParseError(source + ": line " + std::to_string(lineIndex + 1) + " (index " +
                        std::to_string(lineIndex) + "): " + problem);
    };
    SurfaceShape shape = parseFitLine(words, fail);
    primitives.push_back(
        {std::string(words.front()) + std::to_string(lineIndex), std::move(shape)});
  }
  if (in.bad()) throw IoError(source + ": read failed");
  if (primitives.empty()) parseError(source, "no primitives");
  return primitives;
}

std::vector<GpPrimitive> readGpPrimitives(const std::filesystem::path& path) {
  requireReadableFile(path);
  std::ifstream in(path, std::ios::binary);
  return readGpPrimitives(in, path.string());
}

CsgTree readGpExpression(std::istream& in, std::span<const GpPrimitive> primitives, const Aabb& box,
                         const std::string& source) {
  requireUsableBox(box);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw IoError(source + ": read failed");
  return ExpressionParser(text, primitives, box, source).parse();
}

CsgTree readGpExpression(const std::filesystem::path& path, std::span<const GpPrimitive> primitives,
                         const Aabb& box) {
  requireReadableFile(path);
  std::ifstream in(path, std::ios::binary);
  return readGpExpression(in, primitives, box, path.string());
}

Aabb gpClipBox(std::span<const GpPrimitive> primitives, double margin) {
  if (primitives.empty()) throw std::invalid_argument("gpClipBox: no primitives");
  if (!(margin > 0.0) || !std::isfinite(margin)) {
    throw std::invalid_argument("gpClipBox: margin must be finite and > 0");
  }
  Aabb box;
  for (const GpPrimitive& p : primitives) {
    std::visit(
        [&box](const auto& s) {
          using S = std::decay_t<decltype(s)>;
          if constexpr (std::is_same_v<S, PlaneSurface>) {
            box.extend(Vec3(s.offset * s.normal));
          } else if constexpr (std::is_same_v<S, CylinderSurface>) {
            box.extend(Vec3(s.axisPoint.array() - s.radius));
            box.extend(Vec3(s.axisPoint.array() + s.radius));
          } else if constexpr (std::is_same_v<S, ConeSurface>) {
            box.extend(s.apex);
          } else if constexpr (std::is_same_v<S, SphereSurface>) {
            box.extend(Vec3(s.center.array() - s.radius));
            box.extend(Vec3(s.center.array() + s.radius));
          } else {
            box.extend(
                Primitive(Torus{s.center, s.axisDir, s.majorRadius, s.minorRadius}).bounds());
          }
        },
        p.shape);
  }
  const double diagonal = box.diagonal();
  return box.grown(diagonal > 0.0 ? margin * diagonal : 1.0);
}

Aabb gpScanClipBox(const Aabb& scanBounds, double margin) {
  requireUsableBox(scanBounds);
  if (!(scanBounds.diagonal() > 0.0)) {
    throw std::invalid_argument("the scan's points all coincide: no clip box");
  }
  if (!(margin > 0.0) || !std::isfinite(margin)) {
    throw std::invalid_argument("gpScanClipBox: margin must be finite and > 0");
  }
  return scanBounds.grown(margin * scanBounds.diagonal());
}

GpImport importGp(const std::filesystem::path& fit, const std::filesystem::path& expression,
                  const GpImportOptions& options) {
  GpImport result;
  result.primitives = readGpPrimitives(fit);
  if (options.box) {
    result.box = *options.box;
    requireUsableBox(result.box);
  } else {
    result.box = gpClipBox(result.primitives);
    if (!result.box.isBounded()) {
      throw ParseError(fit.string() +
                       ": the primitives' coordinates are too large for a clip box (give a scan)");
    }
  }
  if (options.clipToBox && (result.box.size().array() <= 0.0).any()) {
    throw std::invalid_argument("the clip box has a side of zero length");
  }
  result.tree = readGpExpression(expression, result.primitives, result.box);
  if (options.clipToBox) {
    Box clip;
    clip.center = result.box.center();
    clip.halfSize = 0.5 * result.box.size();
    result.tree = CsgTree::intersect({result.tree, CsgTree::leaf(clip, "clip_box")});
  }
  return result;
}

}  // namespace csgvox
