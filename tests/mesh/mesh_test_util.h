#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "gpucol/triangle_mesh.h"

namespace gpucol::test {

/// Plain arrays of a mesh under construction.
struct MeshArrays {
  std::vector<float> xyz;
  std::vector<std::uint32_t> indices;
};

/// Axis-aligned box with half extents h, centred at c, each face split into n x n quads (2 triangles
/// each), outward counter-clockwise winding, corners shared.
MeshArrays boxArrays(std::array<double, 3> h, std::array<double, 3> c = {0, 0, 0}, int n = 1);

/// Icosahedron subdivided `levels` times, vertices projected onto the sphere of radius r.
MeshArrays icosphereArrays(double r, int levels);

/// Row-major rotation from an axis (need not be unit) and an angle in radians.
std::array<double, 9> axisAngle(std::array<double, 3> axis, double angle);

/// A fresh empty folder under the system temp dir, removed by the caller's TempDir.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  /// Path of `name` inside the folder.
  std::string file(const std::string& name) const;
  /// Writes bytes to `name` and returns its path.
  std::string write(const std::string& name, const std::string& bytes) const;

 private:
  std::string m_path;
};

/// Reads the whole file as bytes.
std::string readBytes(const std::string& path);

/// Reference reader for the test meshes' documented layout only (binary little-endian PLY, float
/// x y z, then `list uchar int` faces of 3): independent of assimp, to check that loading keeps the
/// file's vertices and triangles exactly. Fails the current test when the layout differs.
MeshArrays readReferencePly(const std::string& path);

}  // namespace gpucol::test
