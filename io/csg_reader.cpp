#include "io/csg_reader.h"

#include <cctype>
#include <cmath>
#include <fstream>
#include <istream>
#include <iterator>
#include <optional>
#include <sstream>
#include <vector>

#include "io/errors.h"
#include "io/file_util.h"

namespace csgvox {
namespace {

// A value of an argument: a number, a word (true, false, undef) or a list.
struct Value {
  std::optional<double> number;
  std::string word;
  std::vector<Value> list;
  bool isList = false;
};

struct Statement {
  std::string keyword;
  int line = 0;
  std::vector<std::pair<std::string, Value>> args;  // name empty when positional
  std::vector<Statement> children;

  const Value* arg(const std::string& name, std::size_t position = 99) const {
    for (const auto& [n, v] : args) {
      if (n == name) return &v;
    }
    std::size_t k = 0;
    for (const auto& [n, v] : args) {
      if (n.empty() && k++ == position) return &v;
    }
    return nullptr;
  }
};

class Parser {
 public:
  Parser(std::string text, std::string name) : text_(std::move(text)), name_(std::move(name)) {}

  std::vector<Statement> statements(bool nested) {
    std::vector<Statement> out;
    for (;;) {
      skip();
      if (pos_ >= text_.size()) {
        if (nested) fail("missing '}'");
        return out;
      }
      if (text_[pos_] == '}') {
        if (!nested) fail("unexpected '}'");
        ++pos_;
        return out;
      }
      if (text_[pos_] == ';') {  // an empty statement
        ++pos_;
        continue;
      }
      out.push_back(statement());
    }
  }

  [[noreturn]] void fail(const std::string& what) const {
    throw ParseError(name_ + ": line " + std::to_string(line_) + ": " + what);
  }
  [[noreturn]] void fail(const std::string& what, int line) const {
    throw ParseError(name_ + ": line " + std::to_string(line) + ": " + what);
  }

 private:
  void skip() {
    while (pos_ < text_.size()) {
      const char c = text_[pos_];
      if (c == '\n') {
        ++line_;
        ++pos_;
      } else if (std::isspace(static_cast<unsigned char>(c))) {
        ++pos_;
      } else if (text_.compare(pos_, 2, "//") == 0) {
        while (pos_ < text_.size() && text_[pos_] != '\n') ++pos_;
      } else if (text_.compare(pos_, 2, "/*") == 0) {
        const std::size_t end = text_.find("*/", pos_ + 2);
        if (end == std::string::npos) fail("unterminated comment");
        for (std::size_t i = pos_; i < end; ++i) line_ += text_[i] == '\n';
        pos_ = end + 2;
      } else {
        return;
      }
    }
  }

  void expect(char c) {
    skip();
    if (pos_ >= text_.size() || text_[pos_] != c) fail(std::string("expected '") + c + "'");
    ++pos_;
  }

  bool accept(char c) {
    skip();
    if (pos_ < text_.size() && text_[pos_] == c) {
      ++pos_;
      return true;
    }
    return false;
  }

  std::string word() {
    skip();
    const std::size_t start = pos_;
    while (pos_ < text_.size() && (std::isalnum(static_cast<unsigned char>(text_[pos_])) ||
                                   text_[pos_] == '_' || text_[pos_] == '$')) {
      ++pos_;
    }
    if (start == pos_) fail("expected a name");
    return text_.substr(start, pos_ - start);
  }

  Value value() {
    skip();
    Value v;
    if (accept('[')) {
      v.isList = true;
      if (accept(']')) return v;
      do {
        v.list.push_back(value());
      } while (accept(','));
      expect(']');
      return v;
    }
    if (pos_ < text_.size() && text_[pos_] == '"') {
      const std::size_t end = text_.find('"', pos_ + 1);
      if (end == std::string::npos) fail("unterminated string");
      v.word = text_.substr(pos_ + 1, end - pos_ - 1);
      pos_ = end + 1;
      return v;
    }
    const char* begin = text_.c_str() + pos_;
    char* end = nullptr;
    const double d = std::strtod(begin, &end);
    if (end != begin) {
      pos_ += std::size_t(end - begin);
      if (!std::isfinite(d)) fail("a number is not finite");
      v.number = d;
      return v;
    }
    v.word = word();
    return v;
  }

  Statement statement() {
    skip();
    Statement s;
    s.line = line_;
    while (pos_ < text_.size() && std::string("!#%*").find(text_[pos_]) != std::string::npos) {
      ++pos_;  // modifiers change the display only
    }
    s.keyword = word();
    expect('(');
    if (!accept(')')) {
      do {
        skip();
        const std::size_t save = pos_;
        const int saveLine = line_;
        std::string name;
        if (pos_ < text_.size() && (std::isalpha(static_cast<unsigned char>(text_[pos_])) ||
                                    text_[pos_] == '$' || text_[pos_] == '_')) {
          name = word();
          if (!accept('=')) {  // a positional word value
            pos_ = save;
            line_ = saveLine;
            name.clear();
          }
        }
        s.args.emplace_back(name, value());
      } while (accept(','));
      expect(')');
    }
    if (accept('{')) {
      s.children = statements(true);
    } else {
      expect(';');
    }
    return s;
  }

  std::string text_;
  std::string name_;
  std::size_t pos_ = 0;
  int line_ = 1;
};

// A rigid placement: x -> rotation * x + translation.
struct Placement {
  Mat3 rotation = Mat3::Identity();
  Vec3 translation = Vec3::Zero();
  Vec3 apply(const Vec3& p) const { return rotation * p + translation; }
};

class Builder {
 public:
  explicit Builder(const Parser& parser) : parser_(parser) {}

  // The statements as one tree (their union when several); empty when none.
  std::optional<CsgTree> group(const std::vector<Statement>& list, const Placement& at) const {
    std::vector<CsgTree> parts;
    for (const Statement& s : list) {
      if (auto t = build(s, at)) parts.push_back(*t);
    }
    if (parts.empty()) return std::nullopt;
    if (parts.size() == 1) return parts.front();
    return CsgTree::unite(parts);
  }

 private:
  double number(const Statement& s, const std::string& name, std::size_t position = 99) const {
    const Value* v = s.arg(name, position);
    if (!v || !v->number) parser_.fail(s.keyword + ": needs a number " + name, s.line);
    return *v->number;
  }

  bool centred(const Statement& s) const {
    const Value* v = s.arg("center");
    return v && v->word == "true";
  }

  std::optional<CsgTree> build(const Statement& s, const Placement& at) const {
    const std::string& k = s.keyword;
    if (k == "group" || k == "union" || k == "render" || k == "color") return group(s.children, at);
    if (k == "difference" || k == "intersection") {
      std::vector<CsgTree> parts;
      for (const Statement& c : s.children) {
        if (auto t = build(c, at)) parts.push_back(*t);
      }
      if (parts.empty()) return std::nullopt;
      return k == "difference" ? CsgTree::subtract(parts) : CsgTree::intersect(parts);
    }
    if (k == "multmatrix") return group(s.children, compose(at, matrix(s)));
    if (k == "cube") return cube(s, at);
    if (k == "cylinder") return cylinder(s, at);
    if (k == "sphere") {
      const double r = number(s, "r", 0);
      if (r <= 0) parser_.fail("sphere: radius must be positive", s.line);
      return CsgTree::leaf(Sphere{at.apply(Vec3::Zero()), r});
    }
    if (k == "rotate_extrude") return torus(s, at);
    parser_.fail("unsupported statement '" + k + "'", s.line);
  }

  Placement matrix(const Statement& s) const {
    const Value* m = s.arg("m", 0);
    if (!m || !m->isList || m->list.size() < 3)
      parser_.fail("multmatrix: needs a 4x4 matrix", s.line);
    Placement p;
    for (int i = 0; i < 3; ++i) {
      const Value& row = m->list[std::size_t(i)];
      if (!row.isList || row.list.size() != 4)
        parser_.fail("multmatrix: rows need 4 numbers", s.line);
      for (int j = 0; j < 4; ++j) {
        const Value& e = row.list[std::size_t(j)];
        if (!e.number) parser_.fail("multmatrix: rows need 4 numbers", s.line);
        if (j < 3)
          p.rotation(i, j) = *e.number;
        else
          p.translation[i] = *e.number;
      }
    }
    if ((p.rotation.transpose() * p.rotation - Mat3::Identity()).cwiseAbs().maxCoeff() > 1e-6 ||
        p.rotation.determinant() < 0.0) {
      parser_.fail("multmatrix: only rotations and translations are supported", s.line);
    }
    return p;
  }

  static Placement compose(const Placement& outer, const Placement& inner) {
    return {outer.rotation * inner.rotation,
            outer.rotation * inner.translation + outer.translation};
  }

  CsgTree cube(const Statement& s, const Placement& at) const {
    const Value* size = s.arg("size", 0);
    Vec3 dims;
    if (size && size->number) {
      dims = Vec3::Constant(*size->number);
    } else if (size && size->isList && size->list.size() == 3 && size->list[0].number &&
               size->list[1].number && size->list[2].number) {
      dims = Vec3(*size->list[0].number, *size->list[1].number, *size->list[2].number);
    } else {
      parser_.fail("cube: needs a size", s.line);
    }
    if ((dims.array() <= 0.0).any()) parser_.fail("cube: sizes must be positive", s.line);
    const Vec3 local = centred(s) ? Vec3::Zero() : Vec3(0.5 * dims);
    return CsgTree::leaf(Box{at.apply(local), at.rotation, 0.5 * dims});
  }

  CsgTree cylinder(const Statement& s, const Placement& at) const {
    const double h = number(s, "h", 0);
    double r1 = 0, r2 = 0;
    if (const Value* r = s.arg("r"); r && r->number) {
      r1 = r2 = *r->number;
    } else {
      r1 = number(s, "r1", 1);
      r2 = number(s, "r2", 2);
    }
    if (h <= 0 || r1 < 0 || r2 < 0 || (r1 == 0 && r2 == 0)) {
      parser_.fail("cylinder: needs h > 0 and a positive radius", s.line);
    }
    const Vec3 center = at.apply(centred(s) ? Vec3::Zero() : Vec3(0, 0, 0.5 * h));
    const Vec3 axis = at.rotation.col(2);
    if (r1 == r2) return CsgTree::leaf(Cylinder{center, axis, r1, h});
    return CsgTree::leaf(Cone{center, axis, r1, r2, h});
  }

  // rotate_extrude of a circle moved off the axis by a multmatrix: a torus.
  CsgTree torus(const Statement& s, const Placement& at) const {
    if (const Value* a = s.arg("angle"); a && (!a->number || std::abs(*a->number) < 360.0)) {
      parser_.fail("rotate_extrude: only full turns are supported", s.line);
    }
    const Statement* m = s.children.size() == 1 ? &s.children.front() : nullptr;
    const Statement* c = nullptr;
    Placement offset;
    if (m && m->keyword == "multmatrix" && m->children.size() == 1) {
      offset = matrix(*m);
      c = &m->children.front();
    } else if (m) {
      c = m;
    }
    if (!c || c->keyword != "circle" || !offset.rotation.isIdentity(1e-9) ||
        std::abs(offset.translation.y()) > 1e-9 || std::abs(offset.translation.z()) > 1e-9) {
      parser_.fail("rotate_extrude: only a circle moved along x (a torus) is supported", s.line);
    }
    const double minor = number(*c, "r", 0);
    const double major = offset.translation.x();
    if (minor <= 0 || major < minor) {
      parser_.fail("rotate_extrude: the circle must not cross the axis", s.line);
    }
    return CsgTree::leaf(Torus{at.apply(Vec3::Zero()), at.rotation.col(2), major, minor});
  }

  const Parser& parser_;
};

}  // namespace

CsgTree readCsg(std::istream& in, const std::string& name) {
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  Parser parser(text, name);
  const std::vector<Statement> list = parser.statements(false);
  const std::optional<CsgTree> tree = Builder(parser).group(list, Placement{});
  if (!tree) throw ParseError(name + ": holds no solid");
  try {
    tree->validate();
  } catch (const std::invalid_argument& e) {
    throw ParseError(name + ": " + e.what());
  }
  return *tree;
}

CsgTree readCsg(const std::filesystem::path& path) {
  requireReadableFile(path);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path.string() + ": cannot be opened for reading");
  return readCsg(in, path.string());
}

}  // namespace csgvox
