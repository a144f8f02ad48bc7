#include "mesh/ply_reader.h"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <optional>
#include <sstream>
#include <vector>

#include "gpucol/triangle_mesh.h"
#include "mesh/mesh_file.h"
#include "mesh/printable_text.h"
#include "mesh/strict_number.h"
#include "mesh/text_lines.h"

namespace gpucol {

namespace {

enum class PlyType { kInt8, kUint8, kInt16, kUint16, kInt32, kUint32, kFloat32, kFloat64, kUnknown };

struct PlyTypeInfo {
  const char* name;
  const char* alias;
  PlyType type;
  int size;
  double min, max;  ///< Range of an integer type; float types are checked against their own range.
};

constexpr PlyTypeInfo kTypes[] = {
    {"char", "int8", PlyType::kInt8, 1, -128.0, 127.0},
    {"uchar", "uint8", PlyType::kUint8, 1, 0.0, 255.0},
    {"short", "int16", PlyType::kInt16, 2, -32768.0, 32767.0},
    {"ushort", "uint16", PlyType::kUint16, 2, 0.0, 65535.0},
    {"int", "int32", PlyType::kInt32, 4, -2147483648.0, 2147483647.0},
    {"uint", "uint32", PlyType::kUint32, 4, 0.0, 4294967295.0},
    {"float", "float32", PlyType::kFloat32, 4, 0.0, 0.0},
    {"double", "float64", PlyType::kFloat64, 8, 0.0, 0.0},
};

const PlyTypeInfo* typeNamed(std::string_view name) {
  for (const PlyTypeInfo& info : kTypes) {
    if (name == info.name || name == info.alias) return &info;
  }
  return nullptr;
}

bool isInteger(const PlyTypeInfo& t) {
  return t.type != PlyType::kFloat32 && t.type != PlyType::kFloat64;
}

/// One property: a scalar, or a list with a count type and an item type.
struct PlyProperty {
  std::string name;
  const PlyTypeInfo* type = nullptr;   ///< The scalar's type, or the list items' type.
  const PlyTypeInfo* count = nullptr;  ///< The list count's type; null for a scalar.
  enum class Role { kSkipped, kX, kY, kZ, kCorners } role = Role::kSkipped;
};

struct PlyElement {
  std::string name;
  std::uint64_t count = 0;
  std::size_t line = 0;  ///< Header line that declares it.
  std::vector<PlyProperty> properties;
};

enum class PlyFormat { kAscii, kBinaryLittle, kBinaryBig };

/// a * b + c, saturated at UINT64_MAX: byte counts a hostile header may push past 64 bits.
std::uint64_t mulAdd(std::uint64_t a, std::uint64_t b, std::uint64_t c) {
  if (b != 0 && a > (UINT64_MAX - c) / b) return UINT64_MAX;
  return a * b + c;
}

class PlyReader {
 public:
  PlyReader(const std::string& bytes, const std::string& path) : m_bytes(bytes), m_path(path) {}

  RawMesh read() {
    readHeader();
    requireGeometry();
    checkSize();
    // Faces of an ASCII file are named by their line, those of a binary file by their record.
    m_mesh.emplace(m_path, "PLY", m_format == PlyFormat::kAscii ? "line" : "element 'face' record");
    m_mesh->xyz.assign(3 * std::size_t(m_elements[m_vertex].count), 0.0f);
    // Room for the faces the file can hold as triangles of one-byte (binary) or one-digit (ASCII) indices.
    const std::size_t room = (m_bytes.size() - m_bodyStart) / (m_format == PlyFormat::kAscii ? 8 : 4);
    const std::size_t faces = std::min(std::size_t(m_elements[m_face].count), room);
    m_mesh->reserveFaces(faces, 3 * faces);
    if (m_format == PlyFormat::kAscii) {
      readAscii();
    } else {
      readBinary();
    }
    return std::move(*m_mesh);
  }

 private:
  [[noreturn]] void fail(const std::string& what) const { throwMalformed(m_path, "PLY", what); }

  void readHeader() {
    if (m_bytes.size() < 4 || m_bytes.compare(0, 3, "ply") != 0 || (m_bytes[3] != '\n' && m_bytes[3] != '\r'))
      fail("it does not start with the line 'ply' but with " + printable(m_bytes, 16));
    m_text.emplace(m_bytes, 0, 1, m_path, "PLY", '\0');
    TextLines& lines = *m_text;
    lines.next();  // "ply"
    if (lines.words().size() != 1) lines.fail("the first line must be 'ply' alone");
    bool formatSeen = false;
    for (;;) {
      if (!lines.next()) fail("the header has no 'end_header' line");
      const std::vector<std::string_view>& w = lines.words();
      const std::string_view keyword = w[0];
      if (keyword == "comment" || keyword == "obj_info") continue;
      if (keyword == "end_header") {
        if (w.size() != 1) lines.fail("'end_header' must stand alone on its line");
        break;
      }
      if (keyword == "format") {
        if (formatSeen) lines.fail("a second 'format' line");
        if (w.size() != 3 || w[2] != "1.0")
          lines.fail("the format line must read 'format <ascii|binary_little_endian|binary_big_endian> 1.0'");
        if (w[1] == "ascii") {
          m_format = PlyFormat::kAscii;
        } else if (w[1] == "binary_little_endian") {
          m_format = PlyFormat::kBinaryLittle;
        } else if (w[1] == "binary_big_endian") {
          m_format = PlyFormat::kBinaryBig;
        } else {
          lines.fail("unknown format " + printable(w[1]));
        }
        formatSeen = true;
      } else if (keyword == "element") {
        if (w.size() != 3) lines.fail("an element line must read 'element <name> <count>'");
        PlyElement element;
        element.name = std::string(w[1]);
        element.line = lines.line();
        std::int64_t count = 0;
        const NumberStatus status = parseInteger(w[2], 0, UINT32_MAX, count);
        if (status != NumberStatus::kOk)
          lines.fail("element " + printable(w[1]) + " count " + printable(w[2]) + " " +
                     numberProblem(status, "(0 to 4294967295)"));
        element.count = std::uint64_t(count);
        for (const PlyElement& other : m_elements) {
          if (other.name == element.name)
            lines.fail("a second element " + printable(w[1]) + " (the first is on line " +
                       std::to_string(other.line) + ")");
        }
        if (element.name == "tristrips" || element.name == "range_grid")
          lines.fail("element " + printable(w[1]) +
                     " holds geometry gpucol does not read; store the triangles in element 'face'");
        m_elements.push_back(std::move(element));
      } else if (keyword == "property") {
        if (m_elements.empty()) lines.fail("a property before any element");
        PlyProperty property;
        if (w.size() == 5 && w[1] == "list") {
          property.count = typeNamed(w[2]);
          property.type = typeNamed(w[3]);
          property.name = std::string(w[4]);
          if (property.count == nullptr || property.type == nullptr || !isInteger(*property.count))
            lines.fail("a list property must read 'property list <integer type> <type> <name>'");
        } else if (w.size() == 3 && w[1] != "list") {
          property.type = typeNamed(w[1]);
          property.name = std::string(w[2]);
          if (property.type == nullptr) lines.fail("unknown property type " + printable(w[1]));
        } else {
          lines.fail(
              "a property line must read 'property <type> <name>' or 'property list <type> <type> <name>'");
        }
        PlyElement& element = m_elements.back();
        for (const PlyProperty& other : element.properties) {
          if (other.name == property.name)
            lines.fail("element " + printable(element.name) + " has a second property " +
                       printable(property.name));
        }
        element.properties.push_back(std::move(property));
      } else {
        lines.fail("unexpected header line starting with " + printable(keyword));
      }
    }
    if (!formatSeen) fail("the header has no 'format' line");
    m_bodyStart = m_bytes.size() - lines.bytesLeft();
  }

  /// Finds 'vertex' with scalar x, y, z and 'face' with its corner list.
  void requireGeometry() {
    m_vertex = m_face = m_elements.size();
    for (std::size_t e = 0; e < m_elements.size(); ++e) {
      if (m_elements[e].name == "vertex") m_vertex = e;
      if (m_elements[e].name == "face") m_face = e;
    }
    if (m_vertex == m_elements.size()) fail("the header declares no element 'vertex'");
    if (m_face == m_elements.size()) fail("the header declares no element 'face'");
    const char* axes[3] = {"x", "y", "z"};
    for (int axis = 0; axis < 3; ++axis) {
      PlyProperty* found = nullptr;
      for (PlyProperty& p : m_elements[m_vertex].properties) {
        if (p.name == axes[axis]) found = &p;
      }
      if (found == nullptr) fail(std::string("element 'vertex' has no property '") + axes[axis] + "'");
      if (found->count != nullptr)
        fail(std::string("property '") + axes[axis] +
             "' of element 'vertex' is a list; a coordinate is a scalar");
      found->role = PlyProperty::Role(int(PlyProperty::Role::kX) + axis);
    }
    PlyProperty* corners = nullptr;
    for (PlyProperty& p : m_elements[m_face].properties) {
      if (p.name != "vertex_indices" && p.name != "vertex_index") continue;
      if (corners != nullptr) fail("element 'face' has both 'vertex_indices' and 'vertex_index'");
      corners = &p;
    }
    if (corners == nullptr) fail("element 'face' has no list 'vertex_indices' (or 'vertex_index')");
    if (corners->count == nullptr) fail("property '" + corners->name + "' of element 'face' is not a list");
    if (!isInteger(*corners->type))
      fail("the list '" + corners->name + "' of element 'face' holds " + corners->type->name +
           " values; vertex indices are integers");
    corners->role = PlyProperty::Role::kCorners;
  }

  /// Before anything is allocated: the fewest bytes each element's records can take (a list as its count
  /// alone, so that a bad list is named by its record), added up element by element, must fit in what follows
  /// the header.
  void checkSize() {
    const std::uint64_t left = m_bytes.size() - m_bodyStart;
    std::uint64_t need = 0;
    for (const PlyElement& element : m_elements) {
      std::uint64_t record = 0;  // binary bytes, or ASCII values
      for (const PlyProperty& p : element.properties) {
        if (m_format == PlyFormat::kAscii) {
          record += 1;
        } else {
          record += std::uint64_t(p.count == nullptr ? p.type->size : p.count->size);
        }
      }
      if (record == 0 && element.count != 0) {
        // Records of no bytes: no file size would bound their count.
        std::ostringstream out;
        out << "element " << printable(element.name) << " declares " << element.count
            << " records but no properties";
        fail(out.str());
      }
      // An ASCII value takes a digit and a space or line end; the file's last line end may be missing.
      const std::uint64_t bytes = m_format == PlyFormat::kAscii ? 2 * record : record;
      need = mulAdd(element.count, bytes, need);
      const std::uint64_t slack = m_format == PlyFormat::kAscii ? 1 : 0;
      if (need > left + slack) {
        std::ostringstream out;
        out << "truncated: element " << printable(element.name) << " declares " << element.count
            << " records of at least " << bytes << " bytes";
        if (&element != &m_elements.front()) out << " (after the elements before it)";
        out << ", but only " << left << " bytes follow the header (file size " << m_bytes.size() << ")";
        fail(out.str());
      }
    }
  }

  /// Names a value in messages: "element 'vertex' record 3 property 'z'".
  static std::string placeOf(const PlyElement& element, std::uint64_t record, const PlyProperty& p) {
    return "element " + printable(element.name) + " record " + std::to_string(record) + " property " +
           printable(p.name);
  }

  /// Stores a vertex coordinate, after checking it against gpucol's limit; other scalars are skipped.
  template <typename Fail>
  void useScalar(const PlyProperty& p, std::uint64_t record, double value, const Fail& failHere) {
    if (p.role >= PlyProperty::Role::kX && p.role <= PlyProperty::Role::kZ) {
      if (std::abs(value) > double(TriangleMesh::kMaxCoordinate)) {
        std::ostringstream out;
        out << "the coordinate " << value << " is beyond gpucol's limit of +-"
            << TriangleMesh::kMaxCoordinate;
        failHere(out.str());
      }
      m_mesh->xyz[3 * std::size_t(record) + std::size_t(int(p.role) - int(PlyProperty::Role::kX))] =
          float(value);
    }
  }

  void readAscii() {
    TextLines& lines = *m_text;
    std::vector<std::uint32_t> corners;
    const std::uint64_t vertexCount = m_elements[m_vertex].count;
    for (std::size_t e = 0; e < m_elements.size(); ++e) {
      const PlyElement& element = m_elements[e];
      for (std::uint64_t record = 0; record < element.count; ++record) {
        if (!lines.next()) {
          std::ostringstream out;
          out << "truncated: the file ends before element " << printable(element.name) << " record " << record
              << " of " << element.count;
          fail(out.str());
        }
        const std::vector<std::string_view>& w = lines.words();
        std::size_t k = 0;
        const auto failHere = [&](const PlyProperty& p, const std::string& what) {
          lines.fail(placeOf(element, record, p) + ": " + what);
        };
        // Reads word k as a value of `type`, exactly.
        const auto value = [&](const PlyProperty& p, const PlyTypeInfo& type) {
          if (k >= w.size()) {
            std::ostringstream out;
            out << "element " << printable(element.name) << " record " << record << " ends before property "
                << printable(p.name) << " (" << w.size() << " values on the line)";
            lines.fail(out.str());
          }
          const std::string_view word = w[k++];
          double v = 0;
          if (isInteger(type)) {
            std::int64_t i = 0;
            const NumberStatus status = parseInteger(word, std::int64_t(type.min), std::int64_t(type.max), i);
            if (status != NumberStatus::kOk) {
              std::ostringstream range;
              range << "for " << type.name << " (" << std::int64_t(type.min) << " to "
                    << std::int64_t(type.max) << ")";
              failHere(p, "the value " + printable(word) + " " + numberProblem(status, range.str()));
            }
            v = double(i);
          } else {
            const NumberStatus status = parseReal(word, v);
            const bool overflow =
                status == NumberStatus::kOk && type.type == PlyType::kFloat32 && std::abs(v) > FLT_MAX;
            if (status != NumberStatus::kOk || overflow)
              failHere(p, "the value " + printable(word) + " " +
                              numberProblem(overflow ? NumberStatus::kOutOfRange : status,
                                            type.type == PlyType::kFloat32 ? "for float" : "for double"));
          }
          return v;
        };
        for (const PlyProperty& p : element.properties) {
          if (p.count == nullptr) {
            const double v = value(p, *p.type);
            useScalar(p, record, v, [&](const std::string& what) { failHere(p, what); });
            continue;
          }
          const double items = value(p, *p.count);
          if (items < 0)
            failHere(p, "the list length " + std::to_string(std::int64_t(items)) + " is negative");
          if (p.role == PlyProperty::Role::kCorners) {
            if (items < 3) failHere(p, cornerCountProblem(std::uint64_t(items)));
            corners.clear();
          }
          if (items > double(w.size() - k)) {
            std::ostringstream out;
            out << "element " << printable(element.name) << " record " << record << " has " << w.size()
                << " values, too few for a list of " << std::uint64_t(items) << " in property "
                << printable(p.name);
            lines.fail(out.str());
          }
          for (std::uint64_t item = 0; item < std::uint64_t(items); ++item) {
            const double v = value(p, *p.type);
            if (p.role == PlyProperty::Role::kCorners)
              corners.push_back(
                  checkedIndex(v, vertexCount, [&](const std::string& what) { failHere(p, what); }));
          }
          if (p.role == PlyProperty::Role::kCorners)
            m_mesh->addFace(corners.data(), corners.size(), lines.line());
        }
        if (k != w.size()) {
          std::ostringstream out;
          out << "element " << printable(element.name) << " record " << record << " has " << w.size()
              << " values where " << k << " are expected (an ASCII record is one line)";
          lines.fail(out.str());
        }
      }
    }
    if (lines.next()) lines.fail("text after the last record of the last element");
  }

  static std::string cornerCountProblem(std::uint64_t corners) {
    return "a face of " + std::to_string(corners) + (corners == 1 ? " corner" : " corners") +
           "; a face needs at least 3 (points and lines are refused)";
  }

  /// The vertex index `v`, refused unless it names one of `vertices` vertices.
  template <typename Fail>
  static std::uint32_t checkedIndex(double v, std::uint64_t vertices, const Fail& failHere) {
    if (v < 0 || v >= double(vertices)) {
      std::ostringstream out;
      out << "the vertex index " << std::int64_t(v) << " is out of range for " << vertices << " vertices";
      failHere(out.str());
    }
    return std::uint32_t(v);
  }

  /// The value of `type` at p, in the file's byte order.
  double decode(const unsigned char* p, const PlyTypeInfo& type) const {
    unsigned char b[8];
    const bool big = m_format == PlyFormat::kBinaryBig;
    for (int i = 0; i < type.size; ++i) b[i] = p[big ? type.size - 1 - i : i];  // little-endian host
    switch (type.type) {
      case PlyType::kInt8:
        return double(std::int8_t(b[0]));
      case PlyType::kUint8:
        return double(b[0]);
      case PlyType::kInt16: {
        std::int16_t v;
        std::memcpy(&v, b, 2);
        return double(v);
      }
      case PlyType::kUint16: {
        std::uint16_t v;
        std::memcpy(&v, b, 2);
        return double(v);
      }
      case PlyType::kInt32: {
        std::int32_t v;
        std::memcpy(&v, b, 4);
        return double(v);
      }
      case PlyType::kUint32: {
        std::uint32_t v;
        std::memcpy(&v, b, 4);
        return double(v);
      }
      case PlyType::kFloat32: {
        float v;
        std::memcpy(&v, b, 4);
        return double(v);
      }
      case PlyType::kFloat64: {
        double v;
        std::memcpy(&v, b, 8);
        return v;
      }
      case PlyType::kUnknown:
        break;
    }
    return 0;
  }

  void readBinary() {
    const unsigned char* data = reinterpret_cast<const unsigned char*>(m_bytes.data());
    const std::size_t size = m_bytes.size();
    std::size_t offset = m_bodyStart;
    std::vector<std::uint32_t> corners;
    const std::uint64_t vertexCount = m_elements[m_vertex].count;
    for (const PlyElement& element : m_elements) {
      for (std::uint64_t record = 0; record < element.count; ++record) {
        const auto failHere = [&](const PlyProperty& p, const std::string& what) {
          fail(placeOf(element, record, p) + ": " + what);
        };
        const auto take = [&](const PlyProperty& p, const PlyTypeInfo& type, std::uint64_t items) {
          if (items > (size - offset) / std::uint64_t(type.size)) {
            std::ostringstream out;
            out << "truncated: " << placeOf(element, record, p) << " of " << element.count << " needs "
                << items * std::uint64_t(type.size) << " bytes at offset " << offset
                << ", but the file ends at " << size;
            fail(out.str());
          }
        };
        const auto scalar = [&](const PlyProperty& p, const PlyTypeInfo& type) {
          take(p, type, 1);
          const double v = decode(data + offset, type);
          offset += std::size_t(type.size);
          if (!std::isfinite(v)) {
            std::ostringstream out;
            out << "the value " << v << " is not finite";
            failHere(p, out.str());
          }
          return v;
        };
        for (const PlyProperty& p : element.properties) {
          if (p.count == nullptr) {
            const double v = scalar(p, *p.type);
            useScalar(p, record, v, [&](const std::string& what) { failHere(p, what); });
            continue;
          }
          const double items = scalar(p, *p.count);
          if (items < 0)
            failHere(p, "the list length " + std::to_string(std::int64_t(items)) + " is negative");
          if (p.role == PlyProperty::Role::kCorners) {
            if (items < 3) failHere(p, cornerCountProblem(std::uint64_t(items)));
            corners.clear();
          }
          take(p, *p.type, std::uint64_t(items));
          for (std::uint64_t item = 0; item < std::uint64_t(items); ++item) {
            const double v = scalar(p, *p.type);
            if (p.role == PlyProperty::Role::kCorners)
              corners.push_back(
                  checkedIndex(v, vertexCount, [&](const std::string& what) { failHere(p, what); }));
          }
          if (p.role == PlyProperty::Role::kCorners) m_mesh->addFace(corners.data(), corners.size(), record);
        }
      }
    }
    if (offset != size) {
      std::ostringstream out;
      out << size - offset << " bytes follow the last record of the last element (at offset " << offset
          << "); the header declares fewer records than the file holds";
      fail(out.str());
    }
  }

  const std::string& m_bytes;
  const std::string& m_path;
  std::optional<RawMesh> m_mesh;
  std::optional<TextLines> m_text;
  PlyFormat m_format = PlyFormat::kAscii;
  std::vector<PlyElement> m_elements;
  std::size_t m_bodyStart = 0;
  std::size_t m_vertex = 0, m_face = 0;
};

}  // namespace

RawMesh readPly(const std::string& bytes, const std::string& path) {
  return PlyReader(bytes, path).read();
}

}  // namespace gpucol
