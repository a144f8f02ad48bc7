#include "mesh/ply_precheck.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <iomanip>
#include <sstream>
#include <vector>

#include "gpucol/mesh_error.h"

namespace gpucol {

namespace {

/// One property of a PLY element: a scalar, or a list with a count type and an item type.
struct PlyProperty {
  std::string name;
  std::string type;   ///< The type words as written: "float", or "list uchar int".
  int size = 0;       ///< Bytes of a scalar or of one list item in the binary formats.
  int countSize = 0;  ///< Bytes of the list count; 0 for a scalar.
  bool countSigned = false;
};

struct PlyElement {
  std::string name;
  std::uint64_t count = 0;
  std::vector<PlyProperty> properties;
};

enum class PlyFormat { kAscii, kBinaryLittle, kBinaryBig };

[[noreturn]] void fail(const std::string& path, const std::string& what) {
  throw MeshError(path + ": malformed PLY file: " + what);
}

/// Byte size of a PLY scalar type name (PLY 1.0 names and their sized aliases), 0 if unknown.
int typeSize(const std::string& type) {
  if (type == "char" || type == "uchar" || type == "int8" || type == "uint8") return 1;
  if (type == "short" || type == "ushort" || type == "int16" || type == "uint16") return 2;
  if (type == "int" || type == "uint" || type == "int32" || type == "uint32" || type == "float" ||
      type == "float32")
    return 4;
  if (type == "double" || type == "float64") return 8;
  return 0;
}

/// assimp 5.2.5's line ends (IOStreamBuffer::getNextLine and ParsingUtils' IsLineEnd).
bool isAssimpLineEnd(char c) {
  return c == '\n' || c == '\r' || c == '\0' || c == '\f';
}

/// Throws when a line of PLY text holds a control byte other than a tab (a final '\r' is already removed).
/// assimp ends lines at '\0', '\r' and '\f' and splits words only at spaces and tabs, while this check splits
/// lines at '\n' and words at any white space, so such a line reads differently in the two: "end_header\v"
/// ends the header here but not in assimp, which then loops forever looking for it. Valid PLY text has none.
void requirePlainText(const std::string& text, const char* where, std::size_t line, const std::string& path) {
  for (std::size_t k = 0; k < text.size(); ++k) {
    const unsigned char c = static_cast<unsigned char>(text[k]);
    if ((c < 0x20 && c != '\t') || c == 0x7f) {
      std::ostringstream out;
      out << where << " line " << line << " holds the control byte 0x" << std::hex << std::setw(2)
          << std::setfill('0') << unsigned(c) << std::dec << " at column " << k + 1
          << "; PLY text may hold only printable characters, spaces and tabs";
      fail(path, out.str());
    }
  }
}

/// True for the list assimp reads a face's corners from: 'vertex_indices' or 'vertex_index' of element
/// 'face'.
bool isFaceCornerList(const PlyElement& element, const PlyProperty& p) {
  return p.countSize != 0 && element.name == "face" &&
         (p.name == "vertex_indices" || p.name == "vertex_index");
}

/// Throws for a face with no corners: assimp gives it the polygon type, and its Triangulate step then aborts
/// on an assert (numOut != mNumFaces) when no face has more than three corners. A face needs three corners
/// anyway.
void requireCorners(const PlyElement& element, const PlyProperty& p, std::uint64_t record, std::int64_t items,
                    const std::string& path) {
  if (items != 0 || !isFaceCornerList(element, p)) return;
  std::ostringstream out;
  out << "element 'face' record " << record << " has an empty list '" << p.name
      << "' (a face without corners)";
  fail(path, out.str());
}

/// Reads an unsigned or signed list count of `bytes` bytes in the file's byte order.
std::int64_t readCount(const unsigned char* p, int bytes, bool isSigned, bool bigEndian) {
  std::uint64_t value = 0;
  for (int i = 0; i < bytes; ++i)
    value |= std::uint64_t(p[bigEndian ? i : bytes - 1 - i]) << (8 * (bytes - 1 - i));
  if (isSigned && (value >> (8 * bytes - 1)) != 0)
    return std::int64_t(value) - (std::int64_t(1) << (8 * bytes));
  return std::int64_t(value);
}

void checkBinary(const std::vector<PlyElement>& elements, const unsigned char* data, std::size_t size,
                 std::size_t offset, bool bigEndian, const std::string& path) {
  for (const PlyElement& element : elements) {
    bool fixed = true;
    std::uint64_t recordSize = 0;
    for (const PlyProperty& p : element.properties) {
      fixed = fixed && p.countSize == 0;
      recordSize += std::uint64_t(p.size);
    }
    if (element.properties.empty() && element.count != 0) {
      // Zero bytes per record, so no file size bounds the count, and assimp loops over it: a 'vertex' or
      // 'face' element of 4e9 such records kept it busy for more than 30 s. The ASCII check refuses these as
      // lines with values where none are expected.
      std::ostringstream out;
      out << "element '" << element.name << "' declares " << element.count << " records but no properties";
      fail(path, out.str());
    }
    if (fixed) {
      // Whole element at once; compare by division so a huge declared count cannot overflow.
      const std::uint64_t left = size - offset;
      if (recordSize != 0 && element.count > left / recordSize) {
        std::ostringstream out;
        out << "truncated: element '" << element.name << "' declares " << element.count << " records of "
            << recordSize << " bytes, but only " << left << " bytes follow (file size " << size << ")";
        fail(path, out.str());
      }
      offset += std::size_t(element.count * recordSize);
      continue;
    }
    for (std::uint64_t i = 0; i < element.count; ++i) {
      for (const PlyProperty& p : element.properties) {
        std::uint64_t need = std::uint64_t(p.countSize == 0 ? p.size : p.countSize);
        std::int64_t items = 0;
        if (p.countSize != 0 && size - offset >= need) {
          items = readCount(data + offset, p.countSize, p.countSigned, bigEndian);
          if (items < 0) {
            std::ostringstream out;
            out << "element '" << element.name << "' record " << i << " property '" << p.name
                << "' has a negative list length " << items;
            fail(path, out.str());
          }
          requireCorners(element, p, i, items, path);
          need += std::uint64_t(items) * std::uint64_t(p.size);
        }
        if (size - offset < need) {
          std::ostringstream out;
          out << "truncated: element '" << element.name << "' record " << i << " of " << element.count
              << " (property '" << p.name << "') needs " << need << " bytes at offset " << offset
              << ", but the file ends at " << size;
          fail(path, out.str());
        }
        offset += std::size_t(need);
      }
    }
  }
}

void checkAscii(const std::vector<PlyElement>& elements, const char* data, std::size_t size,
                std::size_t offset, const std::string& path) {
  // assimp reads an ASCII record per line; a record must be one line holding exactly its numbers.
  std::size_t line = 0;
  const auto nextLine = [&](std::vector<std::string>& tokens) {
    tokens.clear();
    while (offset < size) {
      std::size_t end = offset;
      while (end < size && data[end] != '\n') ++end;
      std::string text(data + offset, end - offset);
      if (!text.empty() && text.back() == '\r') text.pop_back();
      offset = end < size ? end + 1 : end;
      ++line;
      requirePlainText(text, "body", line, path);
      std::istringstream in(text);
      for (std::string token; in >> token;) tokens.push_back(token);
      if (!tokens.empty()) return true;
    }
    return false;
  };
  std::vector<std::string> tokens;
  for (const PlyElement& element : elements) {
    for (std::uint64_t i = 0; i < element.count; ++i) {
      if (!nextLine(tokens)) {
        std::ostringstream out;
        out << "truncated: the file ends before element '" << element.name << "' record " << i << " of "
            << element.count;
        fail(path, out.str());
      }
      // Which property each value belongs to, so a bad value can be named.
      std::vector<const PlyProperty*> owner;
      for (const PlyProperty& p : element.properties) {
        if (p.countSize == 0) {
          owner.push_back(&p);
          continue;
        }
        char* end = nullptr;
        const long items =
            owner.size() < tokens.size() ? std::strtol(tokens[owner.size()].c_str(), &end, 10) : -1;
        if (owner.size() >= tokens.size() || *end != '\0' || items < 0) {
          std::ostringstream out;
          out << "element '" << element.name << "' record " << i << " (line " << line
              << " of the body): list '" << p.name << "' has no valid length";
          fail(path, out.str());
        }
        requireCorners(element, p, i, items, path);
        if (std::size_t(items) > tokens.size()) break;  // reported as a count mismatch below
        owner.insert(owner.end(), 1 + std::size_t(items), &p);
      }
      if (tokens.size() != owner.size()) {
        std::ostringstream out;
        out << "element '" << element.name << "' record " << i << " (line " << line << " of the body) has "
            << tokens.size() << " values where " << owner.size() << " are expected";
        fail(path, out.str());
      }
      for (std::size_t k = 0; k < tokens.size(); ++k) {
        // assimp's number parser misreads words such as "nan" and shifts the record, so only finite
        // numbers pass, and only decimal ones: strtod also takes hexadecimal ("0x10"), which assimp reads
        // as 0 followed by garbage.
        char* end = nullptr;
        const double value = std::strtod(tokens[k].c_str(), &end);
        if (*end != '\0' || !std::isfinite(value) ||
            tokens[k].find_first_not_of("0123456789+-.eE") != std::string::npos) {
          std::ostringstream out;
          out << "element '" << element.name << "' record " << i << " (line " << line
              << " of the body): property '" << owner[k]->name << "' has the value '" << tokens[k]
              << "', not a finite decimal number";
          fail(path, out.str());
        }
      }
    }
  }
}

}  // namespace

bool looksLikePly(const char* data, std::size_t size) {
  return size >= 4 && std::memcmp(data, "ply", 3) == 0 && (data[3] == '\n' || data[3] == '\r');
}

bool reachesAssimpPlyReader(const char* data, std::size_t size, const std::string& path) {
  // assimp 5.2.5 Importer::ReadFile: a path whose end matches one reader's extension goes to that reader
  // alone, with no look at the bytes.
  if (path.size() >= 4) {
    std::string extension = path.substr(path.size() - 4);
    for (char& c : extension) c = char(std::tolower(static_cast<unsigned char>(c)));
    if (extension == ".ply") return true;
  }
  // PLYImporter::InternReadFile takes the first line from IOStreamBuffer::getNextLine, which skips to just
  // past the first '\n' when the file starts with a line end, and compares three bytes without regard to
  // case.
  std::size_t start = 0;
  if (size > 0 && isAssimpLineEnd(data[0])) {
    while (start < size && data[start] != '\n') ++start;
    ++start;
  }
  if (start + 3 > size) return false;
  const char* magic = "ply";
  for (int k = 0; k < 3; ++k) {
    if (std::tolower(static_cast<unsigned char>(data[start + std::size_t(k)])) != magic[k]) return false;
  }
  return true;
}

std::string checkPlyStructure(const char* data, std::size_t size, const std::string& path) {
  if (!looksLikePly(data, size)) {
    // Show how it does start, escaped, so a stray byte after "ply" or before it can be seen.
    std::ostringstream out;
    out << "it does not start with the line 'ply' but with \"";
    const std::size_t shown = std::min<std::size_t>(size, 16);
    for (std::size_t k = 0; k < shown; ++k) {
      const unsigned char c = static_cast<unsigned char>(data[k]);
      if (c >= 0x20 && c < 0x7f && c != '"' && c != '\\')
        out << char(c);
      else
        out << "\\x" << std::hex << std::setw(2) << std::setfill('0') << unsigned(c) << std::dec;
    }
    out << (size > shown ? "...\"" : "\"");
    fail(path, out.str());
  }
  std::size_t offset = 0;
  bool formatSeen = false, ended = false;
  PlyFormat format = PlyFormat::kAscii;
  std::string formatName;
  std::vector<PlyElement> elements;
  std::size_t line = 0;
  while (!ended) {
    std::size_t end = offset;
    while (end < size && data[end] != '\n') ++end;
    if (end == size) fail(path, "the header has no 'end_header' line");
    std::string text(data + offset, end - offset);
    if (!text.empty() && text.back() == '\r') text.pop_back();
    offset = end + 1;
    requirePlainText(text, "header", ++line, path);
    std::istringstream in(text);
    std::string keyword;
    in >> keyword;
    if (keyword == "ply" || keyword == "comment" || keyword == "obj_info" || keyword.empty()) continue;
    if (keyword == "end_header") {
      ended = true;
    } else if (keyword == "format") {
      std::string name, version;
      in >> name >> version;
      if (name == "ascii")
        format = PlyFormat::kAscii;
      else if (name == "binary_little_endian")
        format = PlyFormat::kBinaryLittle;
      else if (name == "binary_big_endian")
        format = PlyFormat::kBinaryBig;
      else
        fail(path, "unknown format '" + name + "'");
      formatName = name;
      formatSeen = true;
    } else if (keyword == "element") {
      PlyElement element;
      std::string count;
      in >> element.name >> count;
      char* endCount = nullptr;
      errno = 0;
      element.count = std::strtoull(count.c_str(), &endCount, 10);
      if (element.name.empty() || count.empty() || *endCount != '\0' || count[0] == '-')
        fail(path, "bad element line '" + text + "'");
      // assimp keeps counts in 32 bits (wrapping larger ones), and gpucol's indices are 32-bit too.
      if (element.count > UINT32_MAX || errno == ERANGE)
        fail(path, "element '" + element.name + "' count " + count + " is above 4294967295");
      elements.push_back(element);
    } else if (keyword == "property") {
      if (elements.empty()) fail(path, "property before any element: '" + text + "'");
      PlyProperty property;
      std::string type;
      in >> type;
      if (type == "list") {
        std::string countType, itemType;
        in >> countType >> itemType >> property.name;
        property.type = "list " + countType + " " + itemType;
        property.countSize = typeSize(countType);
        property.size = typeSize(itemType);
        property.countSigned = countType == "char" || countType == "short" || countType == "int" ||
                               countType.rfind("int", 0) == 0;
        if (property.countSize == 0 || property.size == 0 || countType == "float" || countType == "double" ||
            countType.rfind("float", 0) == 0)
          fail(path, "bad list property line '" + text + "'");
      } else {
        in >> property.name;
        property.type = type;
        property.size = typeSize(type);
        if (property.size == 0) fail(path, "unknown property type in '" + text + "'");
      }
      if (property.name.empty()) fail(path, "property without a name: '" + text + "'");
      elements.back().properties.push_back(property);
    } else {
      fail(path, "unexpected header line '" + text + "'");
    }
  }
  if (!formatSeen) fail(path, "the header has no 'format' line");
  if (format == PlyFormat::kAscii) {
    checkAscii(elements, data, size, offset, path);
  } else {
    checkBinary(elements, reinterpret_cast<const unsigned char*>(data), size, offset,
                format == PlyFormat::kBinaryBig, path);
  }
  // The header again, in the one layout where assimp's reader sees what this check saw. assimp ends an
  // element's property list at the first other line, so a comment or two blank lines between properties
  // shorten the record it reads (binary: it then aborts on an assert in Triangulate). Comments and obj_info
  // lines carry no geometry.
  std::ostringstream header;
  header << "ply\nformat " << formatName << " 1.0\n";
  for (const PlyElement& element : elements) {
    header << "element " << element.name << ' ' << element.count << '\n';
    for (const PlyProperty& p : element.properties) header << "property " << p.type << ' ' << p.name << '\n';
  }
  header << "end_header\n";
  return header.str().append(data + offset, size - offset);
}

}  // namespace gpucol
