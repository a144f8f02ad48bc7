#include "mesh/stl_reader.h"

#include <cmath>
#include <cstring>
#include <sstream>
#include <vector>

#include "gpucol/triangle_mesh.h"
#include "mesh/mesh_file.h"
#include "mesh/printable_text.h"
#include "mesh/strict_number.h"
#include "mesh/text_lines.h"

namespace gpucol {

namespace {

constexpr std::size_t kBinaryHeader = 84;  // 80 bytes of header, then the facet count
constexpr std::size_t kBinaryFacet = 50;   // normal, three corners (12 floats), attribute word

bool sameWord(std::string_view word, const char* keyword) {
  if (word.size() != std::strlen(keyword)) return false;
  for (std::size_t k = 0; k < word.size(); ++k) {
    const char c = word[k] >= 'A' && word[k] <= 'Z' ? char(word[k] - 'A' + 'a') : word[k];
    if (c != keyword[k]) return false;
  }
  return true;
}

/// The little-endian facet count at byte 80.
std::uint32_t binaryFacetCount(const std::string& bytes) {
  const unsigned char* p = reinterpret_cast<const unsigned char*>(bytes.data()) + 80;
  return std::uint32_t(p[0]) | std::uint32_t(p[1]) << 8 | std::uint32_t(p[2]) << 16 |
         std::uint32_t(p[3]) << 24;
}

float littleFloat(const unsigned char* p) {
  const std::uint32_t bits =
      std::uint32_t(p[0]) | std::uint32_t(p[1]) << 8 | std::uint32_t(p[2]) << 16 | std::uint32_t(p[3]) << 24;
  float value;
  std::memcpy(&value, &bits, sizeof value);
  return value;
}

RawMesh readBinary(const std::string& bytes, const std::string& path, std::uint32_t facets) {
  RawMesh mesh(path, "STL", "facet");
  mesh.xyz.resize(9 * std::size_t(facets));
  mesh.reserveFaces(facets, 3 * std::size_t(facets));
  const unsigned char* data = reinterpret_cast<const unsigned char*>(bytes.data());
  for (std::uint32_t f = 0; f < facets; ++f) {
    const unsigned char* facet = data + kBinaryHeader + kBinaryFacet * std::size_t(f);
    for (int k = 0; k < 9; ++k) {
      const float value = littleFloat(facet + 12 + 4 * k);
      if (!std::isfinite(value) || std::abs(value) > TriangleMesh::kMaxCoordinate) {
        std::ostringstream out;
        out << "facet " << f << " corner " << k / 3 + 1 << " coordinate "
            << "xyz"[k % 3] << " is " << value;
        if (std::isfinite(value)) out << ", beyond gpucol's limit of +-" << TriangleMesh::kMaxCoordinate;
        throwMalformed(path, "STL", out.str());
      }
      mesh.xyz[9 * std::size_t(f) + std::size_t(k)] = value;
    }
    const std::uint32_t corners[3] = {3 * f, 3 * f + 1, 3 * f + 2};
    mesh.addFace(corners, 3, f);
  }
  return mesh;
}

RawMesh readAscii(const std::string& bytes, const std::string& path) {
  TextLines lines(bytes, 0, 1, path, "STL", '\0');
  RawMesh mesh(path, "STL", "line");
  const std::vector<std::string_view>& w = lines.words();
  // Moves to the next line and requires it to be `keyword` (and `second`) followed by `values` words.
  const auto expect = [&](const char* keyword, std::size_t values, const char* second, const char* context) {
    if (!lines.next()) {
      throwMalformed(path, "STL",
                     std::string("truncated: the file ends where '") + keyword + "' is expected " + context);
    }
    const std::size_t words = 1 + (second ? 1 : 0) + values;
    if (!sameWord(w[0], keyword) || (second && (w.size() < 2 || !sameWord(w[1], second))) ||
        w.size() != words) {
      std::string wanted = keyword;
      if (second) wanted += std::string(" ") + second;
      if (values) wanted += " and " + std::to_string(values) + " numbers";
      lines.fail("expected '" + wanted + "' " + context + ", found a line starting with " + printable(w[0]));
    }
  };
  // The bytes start with "solid" (checked by the caller); solids follow each other to the end of the file.
  if (!lines.next() || !sameWord(w[0], "solid")) lines.fail("an ASCII STL file starts with 'solid'");
  std::uint64_t facet = 0;
  for (;;) {
    if (!lines.next()) throwMalformed(path, "STL", "truncated: the file ends before 'endsolid'");
    if (sameWord(w[0], "endsolid")) {
      if (!lines.next()) break;
      if (!sameWord(w[0], "solid"))
        lines.fail("only another 'solid' may follow 'endsolid', not " + printable(w[0]));
      continue;
    }
    const std::string context = "in facet " + std::to_string(facet);
    if (!sameWord(w[0], "facet") || w.size() != 5 || !sameWord(w[1], "normal"))
      lines.fail("expected 'facet normal i j k' or 'endsolid', found a line starting with " +
                 printable(w[0]));
    const std::size_t facetLine = lines.line();
    for (std::size_t k = 2; k < 5; ++k) {
      double value = 0;
      const NumberStatus status = parseReal(w[k], value);
      if (status != NumberStatus::kOk)
        lines.fail("facet " + std::to_string(facet) + ": the normal component " + printable(w[k]) + " " +
                   numberProblem(status));
    }
    expect("outer", 0, "loop", context.c_str());
    std::uint32_t corners[3];
    for (int c = 0; c < 3; ++c) {
      expect("vertex", 3, nullptr, context.c_str());
      const std::uint64_t v = mesh.xyz.size() / 3;
      if (v >= UINT32_MAX) lines.fail("more than 4294967295 vertices, beyond gpucol's 32-bit indices");
      for (std::size_t k = 1; k < 4; ++k) {
        double value = 0;
        const NumberStatus status = parseReal(w[k], value);
        std::ostringstream out;
        out << "facet " << facet << " vertex " << c + 1 << " coordinate "
            << "xyz"[k - 1] << " " << printable(w[k]) << " ";
        if (status != NumberStatus::kOk) lines.fail(out.str() + numberProblem(status));
        if (std::abs(value) > double(TriangleMesh::kMaxCoordinate)) {
          out << "is beyond gpucol's limit of +-" << TriangleMesh::kMaxCoordinate;
          lines.fail(out.str());
        }
        mesh.xyz.push_back(float(value));
      }
      corners[c] = std::uint32_t(v);
    }
    if (!lines.next())
      throwMalformed(path, "STL", "truncated: the file ends in facet " + std::to_string(facet));
    if (sameWord(w[0], "vertex"))
      lines.fail("facet " + std::to_string(facet) + " has a fourth vertex; an STL facet is a triangle");
    if (!sameWord(w[0], "endloop") || w.size() != 1)
      lines.fail("expected 'endloop' " + context + ", found a line starting with " + printable(w[0]));
    expect("endfacet", 0, nullptr, context.c_str());
    mesh.addFace(corners, 3, facetLine);
    ++facet;
  }
  if (mesh.faceCount() == 0) throwMalformed(path, "STL", "the file has no facets");
  return mesh;
}

}  // namespace

RawMesh readStl(const std::string& bytes, const std::string& path) {
  if (bytes.size() >= kBinaryHeader) {
    const std::uint32_t facets = binaryFacetCount(bytes);
    if (bytes.size() == kBinaryHeader + kBinaryFacet * std::uint64_t(facets)) {
      if (facets == 0) throwMalformed(path, "STL", "the binary file declares 0 facets");
      return readBinary(bytes, path, facets);
    }
  }
  std::size_t start = 0;
  while (start < bytes.size() && (bytes[start] == ' ' || bytes[start] == '\t')) ++start;
  if (bytes.size() - start >= 5 && sameWord(std::string_view(bytes).substr(start, 5), "solid") &&
      (bytes.size() - start == 5 || bytes[start + 5] == ' ' || bytes[start + 5] == '\t' ||
       bytes[start + 5] == '\n' || bytes[start + 5] == '\r'))
    return readAscii(bytes, path);
  std::ostringstream out;
  out << "neither binary STL (84 + 50 N bytes for the N facets declared at byte 80";
  if (bytes.size() >= kBinaryHeader) {
    out << ": " << binaryFacetCount(bytes) << " facets need "
        << kBinaryHeader + kBinaryFacet * std::uint64_t(binaryFacetCount(bytes)) << " bytes, the file has "
        << bytes.size();
  } else {
    out << "; the file has only " << bytes.size() << " bytes";
  }
  out << ") nor ASCII STL (starting with 'solid'); it starts with " << printable(bytes, 16);
  throwMalformed(path, "STL", out.str());
}

}  // namespace gpucol
