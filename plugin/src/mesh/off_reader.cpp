#include "mesh/off_reader.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <vector>

#include "gpucol/triangle_mesh.h"
#include "mesh/mesh_file.h"
#include "mesh/printable_text.h"
#include "mesh/strict_number.h"
#include "mesh/text_lines.h"

namespace gpucol {

namespace {

/// Reads word k of the current line as an integer in [min, max], or fails naming `what` and the word.
std::int64_t integerAt(const TextLines& lines, std::size_t k, std::int64_t min, std::int64_t max,
                       const char* what) {
  std::int64_t value = 0;
  const NumberStatus status = parseInteger(lines.words()[k], min, max, value);
  if (status != NumberStatus::kOk) {
    std::ostringstream range;
    range << "(" << min << " to " << max << ")";
    lines.fail(std::string(what) + " " + printable(lines.words()[k]) + " " +
               numberProblem(status, range.str()));
  }
  return value;
}

}  // namespace

RawMesh readOff(const std::string& bytes, const std::string& path) {
  TextLines lines(bytes, 0, 1, path, "OFF", '#');
  if (!lines.next()) throwMalformed(path, "OFF", "the file holds only comments and blank lines");
  const std::vector<std::string_view>& w = lines.words();
  if (w[0] != "OFF" || w.size() != 1) {
    const std::string_view head = w[0];
    if (head.size() > 3 && head.substr(head.size() - 3) == "OFF")
      lines.fail(
          "the header " + printable(head) +
          " announces a variant (colours, normals, texture coordinates or other dimensions); gpucol reads "
          "plain OFF");
    if (head == "OFF")
      lines.fail("the header line must be 'OFF' alone (binary OFF and counts on it are refused)");
    lines.fail("it does not start with the line 'OFF' but with " + printable(head));
  }
  if (!lines.next()) lines.fail("the file ends before the line of counts");
  if (w.size() != 3) lines.fail("the line of counts must hold three integers: vertices, faces and edges");
  const std::uint64_t vertices = std::uint64_t(integerAt(lines, 0, 0, UINT32_MAX, "the vertex count"));
  const std::uint64_t faces = std::uint64_t(integerAt(lines, 1, 0, UINT32_MAX, "the face count"));
  integerAt(lines, 2, 0, INT64_MAX, "the edge count");
  // Before anything is allocated: a vertex line takes at least 6 bytes ("0 0 0\n"), a face line 2 (its count,
  // so that a bad face is named by its line), and the file's last line end may be missing.
  const std::uint64_t need = 6 * vertices + 2 * faces;
  if (need > lines.bytesLeft() + 1) {
    std::ostringstream out;
    out << "truncated: " << vertices << " vertices and " << faces << " faces need at least " << need - 1
        << " bytes, but only " << lines.bytesLeft() << " follow the line of counts";
    lines.fail(out.str());
  }

  RawMesh mesh(path, "OFF", "line");
  mesh.xyz.resize(3 * std::size_t(vertices));
  // Room for the triangles the file can hold ("3 0 1 2\n"), whatever the declared count.
  const std::size_t room = std::min(std::size_t(faces), lines.bytesLeft() / 8);
  mesh.reserveFaces(room, 3 * room);
  for (std::uint64_t v = 0; v < vertices; ++v) {
    if (!lines.next()) {
      std::ostringstream out;
      out << "truncated: the file ends before vertex " << v << " of " << vertices;
      throwMalformed(path, "OFF", out.str());
    }
    if (w.size() != 3) {
      std::ostringstream out;
      out << "vertex " << v << " has " << w.size() << " values; a vertex line holds x y z";
      lines.fail(out.str());
    }
    for (std::size_t axis = 0; axis < 3; ++axis) {
      double value = 0;
      const NumberStatus status = parseReal(w[axis], value);
      std::ostringstream out;
      out << "vertex " << v << " coordinate "
          << "xyz"[axis] << " ";
      if (status != NumberStatus::kOk)
        lines.fail(out.str() + printable(w[axis]) + " " + numberProblem(status));
      if (std::abs(value) > double(TriangleMesh::kMaxCoordinate)) {
        out << printable(w[axis]) << " is beyond gpucol's limit of +-" << TriangleMesh::kMaxCoordinate;
        lines.fail(out.str());
      }
      mesh.xyz[3 * std::size_t(v) + axis] = float(value);
    }
  }
  std::vector<std::uint32_t> corners;
  for (std::uint64_t f = 0; f < faces; ++f) {
    if (!lines.next()) {
      std::ostringstream out;
      out << "truncated: the file ends before face " << f << " of " << faces;
      throwMalformed(path, "OFF", out.str());
    }
    const std::int64_t n = integerAt(lines, 0, 0, UINT32_MAX, "the corner count");
    std::ostringstream out;
    out << "face " << f;
    const std::string face = out.str();
    if (n < 3)
      lines.fail(face + " has " + std::to_string(n) + (n == 1 ? " corner" : " corners") +
                 "; a face needs at least 3 (points and lines are refused)");
    if (std::uint64_t(n) != w.size() - 1) {
      std::ostringstream count;
      count << face << " declares " << n << " corners but the line holds " << w.size() - 1
            << " values after the count (colours and other values on a face line are refused)";
      lines.fail(count.str());
    }
    corners.resize(std::size_t(n));
    for (std::size_t k = 0; k < corners.size(); ++k) {
      std::int64_t index = 0;
      const NumberStatus status = parseInteger(w[k + 1], 0, std::int64_t(vertices) - 1, index);
      if (status != NumberStatus::kOk) {
        std::ostringstream bad;
        bad << face << " corner " << k + 1 << ": the vertex index " << printable(w[k + 1]) << " "
            << numberProblem(status, "for " + std::to_string(vertices) + " vertices (0 to " +
                                         std::to_string(std::int64_t(vertices) - 1) + ")");
        lines.fail(bad.str());
      }
      corners[k] = std::uint32_t(index);
    }
    mesh.addFace(corners.data(), corners.size(), lines.line());
  }
  if (lines.next())
    lines.fail("text after the last face; the line of counts declares " + std::to_string(faces) + " faces");
  return mesh;
}

}  // namespace gpucol
