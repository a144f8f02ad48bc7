#include "mesh/obj_reader.h"

#include <cmath>
#include <iterator>
#include <sstream>
#include <vector>

#include "gpucol/triangle_mesh.h"
#include "mesh/mesh_file.h"
#include "mesh/printable_text.h"
#include "mesh/strict_number.h"
#include "mesh/text_lines.h"

namespace gpucol {

namespace {

/// Statements that carry no geometry: names, groups, smoothing, materials and display attributes.
constexpr const char* kSkipped[] = {"o",          "g",         "s",     "mg",       "usemtl",   "mtllib",
                                    "usemap",     "maplib",    "bevel", "c_interp", "d_interp", "lod",
                                    "shadow_obj", "trace_obj", "ctech", "stech"};
/// Free-form geometry (curves and surfaces), which gpucol does not tessellate.
constexpr const char* kFreeForm[] = {"cstype", "deg",  "bmat", "step", "curv", "curv2", "surf", "parm",
                                     "trim",   "hole", "scrv", "sp",   "end",  "con",   "call", "csh"};

bool isOneOf(std::string_view word, const char* const* list, std::size_t n) {
  for (std::size_t k = 0; k < n; ++k) {
    if (word == list[k]) return true;
  }
  return false;
}

/// Reads a number word of the current line, or fails naming it.
double numberAt(const TextLines& lines, std::size_t k, const char* what) {
  double value = 0;
  const NumberStatus status = parseReal(lines.words()[k], value);
  if (status != NumberStatus::kOk)
    lines.fail(std::string(what) + " " + printable(lines.words()[k]) + " " + numberProblem(status));
  return value;
}

/// Resolves one index of a face corner (`part`: "vertex", "texture coordinate", "normal") against the
/// `defined` ones so far: 1-based, or negative counting back from the latest.
std::uint32_t resolve(const TextLines& lines, std::string_view word, std::uint64_t defined,
                      std::size_t corner, const char* part) {
  std::int64_t index = 0;
  const NumberStatus status = parseInteger(word, INT64_MIN, INT64_MAX, index);
  std::ostringstream out;
  out << "corner " << corner + 1 << ": the " << part << " index " << printable(word) << " ";
  if (status != NumberStatus::kOk) lines.fail(out.str() + numberProblem(status));
  if (index == 0) lines.fail(out.str() + "is 0; OBJ indices count from 1 (or back from -1)");
  if ((index > 0 && std::uint64_t(index) > defined) ||
      (index < 0 && std::uint64_t(-(index + 1)) >= defined)) {
    out << "names no " << part << ": " << defined << " defined before this line";
    lines.fail(out.str());
  }
  return std::uint32_t(index > 0 ? std::uint64_t(index) - 1 : defined - std::uint64_t(-(index + 1)) - 1);
}

}  // namespace

RawMesh readObj(const std::string& bytes, const std::string& path) {
  TextLines lines(bytes, 0, 1, path, "OBJ", '#');
  RawMesh mesh(path, "OBJ", "line");
  std::uint64_t textures = 0, normals = 0;
  std::vector<std::uint32_t> corners;
  while (lines.next()) {
    const std::vector<std::string_view>& w = lines.words();
    const std::string_view keyword = w[0];
    if (w.back().back() == '\\')
      lines.fail("line continuations ('\\' at the end of a line) are not read by gpucol");
    if (keyword == "v") {
      if (w.size() != 4 && w.size() != 5 && w.size() != 7)
        lines.fail("a vertex holds x y z (optionally w = 1, or r g b colours), not " +
                   std::to_string(w.size() - 1) + " values");
      const std::uint64_t v = mesh.xyz.size() / 3;
      if (v == UINT32_MAX) lines.fail("more than 4294967295 vertices, beyond gpucol's 32-bit indices");
      for (std::size_t k = 1; k < w.size(); ++k) {
        const double value = numberAt(lines, k,
                                      k <= 3                    ? "the coordinate"
                                      : k == 4 && w.size() == 5 ? "the weight"
                                                                : "the colour");
        if (k <= 3 && std::abs(value) > double(TriangleMesh::kMaxCoordinate)) {
          std::ostringstream out;
          out << "the coordinate " << printable(w[k]) << " is beyond gpucol's limit of +-"
              << TriangleMesh::kMaxCoordinate;
          lines.fail(out.str());
        }
        if (k == 4 && w.size() == 5 && value != 1)
          lines.fail("the weight " + printable(w[4]) + " is not 1; rational vertices are not read by gpucol");
        if (k <= 3) mesh.xyz.push_back(float(value));
      }
    } else if (keyword == "vt" || keyword == "vp") {
      if (w.size() < 2 || w.size() > 4)
        lines.fail("'" + std::string(keyword) + "' holds 1 to 3 values, not " + std::to_string(w.size() - 1));
      for (std::size_t k = 1; k < w.size(); ++k) numberAt(lines, k, "the value");
      if (keyword == "vt") ++textures;
    } else if (keyword == "vn") {
      if (w.size() != 4) lines.fail("a normal holds 3 values, not " + std::to_string(w.size() - 1));
      for (std::size_t k = 1; k < w.size(); ++k) numberAt(lines, k, "the value");
      ++normals;
    } else if (keyword == "f") {
      const std::size_t n = w.size() - 1;
      if (n < 3)
        lines.fail("a face of " + std::to_string(n) + (n == 1 ? " corner" : " corners") +
                   "; a face needs at least 3 (points and lines are refused)");
      corners.resize(n);
      for (std::size_t k = 0; k < n; ++k) {
        // v, v/vt, v//vn or v/vt/vn.
        const std::string_view corner = w[k + 1];
        const std::size_t slash = corner.find('/');
        corners[k] = resolve(lines, corner.substr(0, slash), mesh.xyz.size() / 3, k, "vertex");
        if (slash == std::string_view::npos) continue;
        const std::string_view rest = corner.substr(slash + 1);
        const std::size_t second = rest.find('/');
        const std::string_view texture = rest.substr(0, second);
        if (second == std::string_view::npos && texture.empty())
          lines.fail("corner " + std::to_string(k + 1) + " " + printable(corner) + " ends in '/'");
        if (!texture.empty()) resolve(lines, texture, textures, k, "texture coordinate");
        if (second != std::string_view::npos) {
          const std::string_view normal = rest.substr(second + 1);
          if (normal.find('/') != std::string_view::npos || normal.empty())
            lines.fail("corner " + std::to_string(k + 1) + " " + printable(corner) +
                       " is not v, v/vt, v//vn or v/vt/vn");
          resolve(lines, normal, normals, k, "normal");
        }
      }
      mesh.addFace(corners.data(), n, lines.line());
    } else if (keyword == "p" || keyword == "l") {
      lines.fail(std::string(keyword == "p" ? "a point" : "a line") + " ('" + std::string(keyword) +
                 "'); gpucol needs faces of at least 3 corners (points and lines are refused)");
    } else if (isOneOf(keyword, kFreeForm, std::size(kFreeForm))) {
      lines.fail("free-form geometry ('" + std::string(keyword) +
                 "': curves and surfaces) is not read by gpucol");
    } else if (!isOneOf(keyword, kSkipped, std::size(kSkipped))) {
      lines.fail("unknown statement " + printable(keyword));
    }
  }
  if (mesh.faceCount() == 0) throwMalformed(path, "OBJ", "the file has no faces ('f' lines)");
  return mesh;
}

}  // namespace gpucol
