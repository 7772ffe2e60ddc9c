#include "io/ply_header.h"

#include <algorithm>
#include <array>
#include <charconv>
#include <cstdint>
#include <istream>

#include "io/reader_support.h"

namespace csgvox::detail {
namespace {

bool isPlyFloat(std::string_view type) {
  return type == "float" || type == "float32" || type == "double" || type == "float64";
}

/// Reads one header line (without "\n" or "\r"); false at the end of the
/// stream. Bounded, so that a binary file is not read whole as one line.
bool readHeaderLine(std::istream& in, std::string& line, const std::string& source) {
  constexpr std::size_t kMaxLine = 4096;
  line.clear();
  char c = 0;
  bool any = false;
  while (in.get(c)) {
    any = true;
    if (c == '\n') break;
    if (line.size() == kMaxLine)
      parseError(source, "garbled PLY header (a header line is too long)");
    line.push_back(c);
  }
  if (!line.empty() && line.back() == '\r') line.pop_back();
  return any;
}

/// Names of an element's properties ("x y z nx ny nz").
std::string propertyNames(const PlyElement& element) {
  std::string names;
  for (const PlyProperty& p : element.properties) names += (names.empty() ? "" : " ") + p.name;
  return names;
}

/// What the header declares, for messages: "100 vertices and 12 faces".
std::string declaredCounts(const PlyHeader& header) {
  std::string declared = std::to_string(header.vertices->count) + " vertices";
  if (header.faces) declared += " and " + std::to_string(header.faces->count) + " faces";
  return declared;
}

/// True when `word` is a number of the PLY scalar type `type`.
bool isPlyValue(std::string_view word, const std::string& type) {
  if (isPlyFloat(type)) {
    if (word.starts_with('+')) word.remove_prefix(1);
    double value = 0.0;
    const auto result = std::from_chars(word.data(), word.data() + word.size(), value);
    return result.ec == std::errc() && result.ptr == word.data() + word.size();
  }
  std::int64_t value = 0;
  const auto result = std::from_chars(word.data(), word.data() + word.size(), value);
  return result.ec == std::errc() && result.ptr == word.data() + word.size();
}

/// ASCII data: one row per line (blank lines skipped), each with exactly the
/// values its properties declare, and nothing but blanks after the last row.
void checkAsciiData(std::istream& in, const PlyHeader& header, const std::string& source) {
  const std::string text = slurp(in, source);
  std::size_t pos = 0;
  std::size_t lineNumber = header.headerLines;
  std::vector<std::string_view> words;
  auto nextLine = [&] {
    while (pos < text.size()) {
      const std::size_t end = std::min(text.find('\n', pos), text.size());
      words = splitWords(std::string_view(text.data() + pos, end - pos));
      pos = end + 1;
      ++lineNumber;
      if (!words.empty()) return true;
    }
    return false;
  };
  for (const PlyElement& element : header.elements) {
    for (std::uint64_t row = 0; row < element.count; ++row) {
      const std::string what = "PLY " + element.name + " " + std::to_string(row + 1) + " of " +
                               std::to_string(element.count);
      if (!nextLine()) {
        parseError(source, "truncated PLY data: only " + std::to_string(row) + " of " +
                               std::to_string(element.count) + " " + element.name +
                               " rows before the end of the file");
      }
      const std::string where = "line " + std::to_string(lineNumber) + ": ";
      std::size_t at = 0;
      for (const PlyProperty& p : element.properties) {
        std::uint64_t items = 1;
        if (!p.countType.empty()) {
          if (at >= words.size() || !parseCount(words[at], items)) {
            parseError(source,
                       where + what + " has no valid length for its list \"" + p.name + "\"");
          }
          ++at;
          if (items > words.size() - at) {
            parseError(source, where + what + ": a list is longer than its line (\"" + p.name +
                                   "\" states " + std::to_string(items) + " values, " +
                                   std::to_string(words.size() - at) + " follow)");
          }
        }
        for (std::uint64_t i = 0; i < items; ++i, ++at) {
          if (at >= words.size()) {
            parseError(source, where + what + " has " + std::to_string(words.size()) +
                                   " values, fewer than its properties (" + propertyNames(element) +
                                   ") need");
          }
          if (!isPlyValue(words[at], p.type)) {
            parseError(source, where + "\"" + std::string(words[at].substr(0, 40)) +
                                   "\" is not a " + p.type + " value (property \"" + p.name +
                                   "\" of " + what + ")");
          }
        }
      }
      if (at != words.size()) {
        parseError(source, where + what + " has " + std::to_string(words.size()) +
                               " values; its properties (" + propertyNames(element) + ") take " +
                               std::to_string(at));
      }
    }
  }
  if (nextLine()) {
    parseError(source, "line " + std::to_string(lineNumber) +
                           ": more PLY data than the header declares (" + declaredCounts(header) +
                           ")");
  }
}

/// Binary data: every list length fits in the rest of the file, and nothing
/// but blanks follows the last row. CGAL sizes a list from its stated length
/// before reading the items, so one garbled length exhausts memory.
void checkBinaryData(std::istream& in, const PlyHeader& header, const std::string& source) {
  const PlyElement* element = nullptr;
  std::uint64_t row = 0;
  auto fail = [&] {
    parseError(source, "PLY data is truncated or garbled (" + element->name + " " +
                           std::to_string(row + 1) + " of " + std::to_string(element->count) +
                           ": a list is longer than the rest of the file, or the file ends in it)");
  };
  std::uint64_t left = header.dataBytes;
  auto readLength = [&](const std::string& type) {
    const int size = plyTypeSize(type);
    std::array<unsigned char, 4> b{};
    if (left < static_cast<std::uint64_t>(size) ||
        !in.read(reinterpret_cast<char*>(b.data()), size)) {
      fail();
    }
    left -= static_cast<std::uint64_t>(size);
    std::uint64_t length = 0;
    for (int i = 0; i < size; ++i) {
      const int byte = header.data == PlyData::BigEndian ? i : size - 1 - i;
      length = (length << 8) | b[static_cast<std::size_t>(byte)];
    }
    const bool isSigned = type == "char" || type == "int8" || type == "short" || type == "int16" ||
                          type == "int" || type == "int32";
    if (isSigned && (length >> (8 * size - 1)) != 0) fail();  // negative
    return length;
  };
  auto skip = [&](std::uint64_t bytes) {
    if (bytes > left) fail();
    in.ignore(static_cast<std::streamsize>(bytes));
    left -= bytes;
  };
  for (const PlyElement& e : header.elements) {
    element = &e;
    row = 0;
    std::uint64_t rowBytes = 0;
    bool hasList = false;
    for (const PlyProperty& p : e.properties) {
      hasList = hasList || !p.countType.empty();
      rowBytes += static_cast<std::uint64_t>(plyTypeSize(p.type));
    }
    if (!hasList) {  // fixed-size rows: the header's size check covered them
      skip(saturatingMulAdd(0, e.count, rowBytes));
      continue;
    }
    for (; row < e.count; ++row) {
      for (const PlyProperty& p : e.properties) {
        const std::uint64_t items = p.countType.empty() ? 1 : readLength(p.countType);
        skip(saturatingMulAdd(0, items, static_cast<std::uint64_t>(plyTypeSize(p.type))));
      }
    }
  }
  std::string rest(static_cast<std::size_t>(std::min<std::uint64_t>(left, 4096)), '\0');
  in.read(rest.data(), static_cast<std::streamsize>(rest.size()));
  if (left > rest.size() || rest.find_first_not_of(" \t\r\n") != std::string::npos) {
    parseError(source, "more PLY data than the header declares (" + declaredCounts(header) + "; " +
                           std::to_string(left) + " bytes follow the last of them)");
  }
}

/// Reads the first two lines, "ply" and the format line; the data's encoding.
PlyData readPlyFormat(std::istream& in, const std::string& source) {
  std::string line;
  if (!readHeaderLine(in, line, source) || line.find_first_not_of(" \t") == std::string::npos ||
      splitWords(line).size() != 1 || splitWords(line)[0] != "ply") {
    parseError(source, "not a PLY file (the first line must be \"ply\")");
  }
  readHeaderLine(in, line, source);
  const std::vector<std::string_view> format = splitWords(line);
  if (format.size() != 3 || format[0] != "format" ||
      (format[1] != "ascii" && format[1] != "binary_little_endian" &&
       format[1] != "binary_big_endian")) {
    parseError(source,
               "garbled PLY header (the second line must be \"format ascii|binary_little_endian|"
               "binary_big_endian 1.0\")");
  }
  return format[1] == "ascii"                  ? PlyData::Ascii
         : format[1] == "binary_little_endian" ? PlyData::LittleEndian
                                               : PlyData::BigEndian;
}

/// The property a "property" header line (`line`, split into `words`) declares.
PlyProperty parseProperty(const std::vector<std::string_view>& words, const std::string& line,
                          const std::string& source) {
  PlyProperty property;
  if (words.size() == 5 && words[1] == "list") {
    property = {std::string(words[4]), std::string(words[3]), std::string(words[2])};
    const bool integralCount =
        plyTypeSize(words[2]) != 0 && !isPlyFloat(words[2]) && plyTypeSize(words[2]) <= 4;
    if (!integralCount || plyTypeSize(words[3]) == 0) {
      parseError(source, "unsupported PLY list type in \"" + line + "\"");
    }
  } else if (words.size() == 3) {
    property = {std::string(words[2]), std::string(words[1]), ""};
    if (plyTypeSize(words[1]) == 0) {
      parseError(source,
                 "unsupported PLY property type \"" + property.type + "\" in \"" + line + "\"");
    }
  } else {
    parseError(source, "garbled PLY header line \"" + line + "\"");
  }
  return property;
}

/// Reads the header's elements and properties up to and including
/// end_header, counting its lines.
void readPlyElements(std::istream& in, PlyHeader& header, const std::string& source) {
  std::string line;
  bool ended = false;
  while (readHeaderLine(in, line, source)) {
    ++header.headerLines;
    const std::vector<std::string_view> words = splitWords(line);
    if (words.empty() || words[0] == "comment" || words[0] == "obj_info") continue;
    if (words[0] == "end_header") {
      ended = true;
      break;
    }
    if (words[0] == "element") {
      std::uint64_t count = 0;
      if (words.size() != 3 || !parseCount(words[2], count)) {
        parseError(source, "garbled PLY header line \"" + line + "\"");
      }
      header.elements.push_back({std::string(words[1]), count, {}});
    } else if (words[0] == "property") {
      if (header.elements.empty())
        parseError(source, "garbled PLY header (property before element)");
      header.elements.back().properties.push_back(parseProperty(words, line, source));
    } else {
      parseError(source, "garbled PLY header line \"" + line.substr(0, 60) + "\"");
    }
  }
  if (!ended) parseError(source, "garbled or truncated PLY header (no end_header line)");
  for (const PlyElement& element : header.elements) {
    // Rows without properties take no bytes: CGAL would loop over them.
    if (element.count > 0 && element.properties.empty()) {
      parseError(source, "garbled PLY header (element \"" + element.name + "\" declares " +
                             std::to_string(element.count) + " rows but no properties)");
    }
  }
}

/// Finds the vertex and face elements and checks their properties: float
/// x y z, all or none of float nx ny nz, and faces' vertex indices.
void checkPlyVertices(PlyHeader& header, const std::string& source) {
  for (const PlyElement& element : header.elements) {
    if (!header.vertices && (element.name == "vertex" || element.name == "vertices")) {
      header.vertices = &element;
    }
    if (!header.faces && (element.name == "face" || element.name == "faces"))
      header.faces = &element;
  }
  if (!header.vertices) parseError(source, "PLY file has no vertex element");
  for (const char* axis : {"x", "y", "z"}) {
    const PlyProperty* p = header.vertices->find(axis);
    if (!p) parseError(source, std::string("PLY vertices have no \"") + axis + "\" property");
    if (!p->countType.empty() || !isPlyFloat(p->type)) {
      parseError(source, std::string("PLY vertex property \"") + axis +
                             "\" must be float or double, not " +
                             (p->countType.empty() ? p->type : "a list"));
    }
  }
  int normalCount = 0;
  for (const char* axis : {"nx", "ny", "nz"}) {
    if (const PlyProperty* p = header.vertices->find(axis)) {
      if (!p->countType.empty() || !isPlyFloat(p->type)) {
        parseError(source,
                   std::string("PLY vertex property \"") + axis + "\" must be float or double");
      }
      ++normalCount;
    }
  }
  if (normalCount != 0 && normalCount != 3) {
    parseError(source, "PLY vertices have only some of the normal properties nx ny nz");
  }
  header.hasNormals = normalCount == 3;
  if (header.faces && header.faces->count > 0) {
    const PlyProperty* indices = header.faces->find("vertex_indices");
    if (!indices) indices = header.faces->find("vertex_index");
    const bool ok = indices && !indices->countType.empty() &&
                    (indices->type == "int" || indices->type == "int32" ||
                     indices->type == "uint" || indices->type == "uint32");
    if (!ok) {
      parseError(source, "PLY faces have no vertex_indices list of int or uint");
    }
  }
}

/// Checks that the data is at least its minimum size: fixed-size rows are
/// exact, lists count as empty, ASCII values as one digit and a separator.
void checkPlyDataSize(const PlyHeader& header, const std::string& source) {
  std::uint64_t need = 0;
  for (const PlyElement& element : header.elements) {
    std::uint64_t row = 0;
    for (const PlyProperty& p : element.properties) {
      if (header.data == PlyData::Ascii) {
        row += 2;
      } else {
        row += static_cast<std::uint64_t>(plyTypeSize(p.countType.empty() ? p.type : p.countType));
      }
    }
    need = saturatingMulAdd(need, element.count, row);
  }
  if (header.data == PlyData::Ascii && need > 0) --need;
  if (header.dataBytes < need) {
    parseError(source, "truncated PLY file: the header declares " + declaredCounts(header) +
                           ", which need at least " + std::to_string(need) +
                           " bytes of data, but only " + std::to_string(header.dataBytes) +
                           " bytes follow the header");
  }
}

}  // namespace

const PlyProperty* PlyElement::find(std::string_view property) const {
  for (const PlyProperty& p : properties) {
    if (p.name == property) return &p;
  }
  return nullptr;
}

int plyTypeSize(std::string_view type) {
  if (type == "char" || type == "uchar" || type == "int8" || type == "uint8") return 1;
  if (type == "short" || type == "ushort" || type == "int16" || type == "uint16") return 2;
  if (type == "int" || type == "uint" || type == "int32" || type == "uint32") return 4;
  if (type == "float" || type == "float32") return 4;
  if (type == "double" || type == "float64") return 8;
  return 0;
}

PlyHeader parsePlyHeader(std::istream& in, const std::string& source) {
  PlyHeader header;
  header.data = readPlyFormat(in, source);
  header.headerLines = 2;
  readPlyElements(in, header, source);
  header.dataBytes = bytesLeft(in, source);
  checkPlyVertices(header, source);
  checkPlyDataSize(header, source);
  return header;
}

void checkPlyData(std::istream& in, const PlyHeader& header, const std::string& source) {
  if (header.data == PlyData::Ascii) {
    checkAsciiData(in, header, source);
  } else {
    checkBinaryData(in, header, source);
  }
}

std::string plyFormatName(PlyData data) {
  constexpr std::array<const char*, 3> kNames = {"ply-ascii", "ply-binary-le", "ply-binary-be"};
  return kNames[static_cast<std::size_t>(data)];  // in the order of PlyData
}

}  // namespace csgvox::detail
