// TriangleMesh::fromStridingMesh: the triangles of a Bullet mesh interface, part by part.
#include <BulletCollision/CollisionShapes/btStridingMeshInterface.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <sstream>
#include <string>

#include "gpucol/mesh_error.h"
#include "gpucol/triangle_mesh.h"

namespace gpucol {
namespace {

const char* typeName(PHY_ScalarType type) {
  switch (type) {
    case PHY_FLOAT:
      return "PHY_FLOAT";
    case PHY_DOUBLE:
      return "PHY_DOUBLE";
    case PHY_INTEGER:
      return "PHY_INTEGER";
    case PHY_SHORT:
      return "PHY_SHORT";
    case PHY_FIXEDPOINT88:
      return "PHY_FIXEDPOINT88";
    case PHY_UCHAR:
      return "PHY_UCHAR";
  }
  return "an unknown type";
}

// A part's arrays, locked for reading for as long as this lives.
class LockedPart {
 public:
  LockedPart(const btStridingMeshInterface& mesh, int part) : m_mesh(mesh), m_part(part) {
    mesh.getLockedReadOnlyVertexIndexBase(&vertices, vertexCount, vertexType, vertexStride, &indices,
                                          indexStride, triangleCount, indexType, part);
  }
  ~LockedPart() { m_mesh.unLockReadOnlyVertexBase(m_part); }
  LockedPart(const LockedPart&) = delete;
  LockedPart& operator=(const LockedPart&) = delete;

  const unsigned char* vertices = nullptr;
  const unsigned char* indices = nullptr;
  int vertexCount = 0, vertexStride = 0, indexStride = 0, triangleCount = 0;
  PHY_ScalarType vertexType = PHY_FLOAT, indexType = PHY_INTEGER;

 private:
  const btStridingMeshInterface& m_mesh;
  int m_part;
};

// Corner k of triangle t, read as the part's index type (unaligned arrays are allowed: memcpy).
std::int64_t readIndex(const LockedPart& p, int t, int k) {
  const unsigned char* at = p.indices + std::size_t(t) * std::size_t(p.indexStride);
  if (p.indexType == PHY_INTEGER) {
    std::int32_t value;
    std::memcpy(&value, at + k * sizeof(value), sizeof(value));
    return value;
  }
  if (p.indexType == PHY_SHORT) {
    // Bullet reads 16-bit indices as unsigned.
    std::uint16_t value;
    std::memcpy(&value, at + k * sizeof(value), sizeof(value));
    return value;
  }
  return at[k];
}

double readCoordinate(const LockedPart& p, int v, int axis) {
  const unsigned char* at = p.vertices + std::size_t(v) * std::size_t(p.vertexStride);
  if (p.vertexType == PHY_DOUBLE) {
    double value;
    std::memcpy(&value, at + axis * sizeof(value), sizeof(value));
    return value;
  }
  float value;
  std::memcpy(&value, at + axis * sizeof(value), sizeof(value));
  return value;
}

[[noreturn]] void fail(const std::string& name, int part, const std::string& what) {
  std::ostringstream out;
  out << name << ": part " << part << " " << what;
  throw MeshError(out.str());
}

}  // namespace

TriangleMesh TriangleMesh::fromStridingMesh(const btStridingMeshInterface& meshInterface, std::string name) {
  const char* const axes = "xyz";
  std::vector<float> xyz;
  std::vector<std::uint32_t> indices;
  std::vector<MeshPart> parts;
  for (int partIndex = 0; partIndex < meshInterface.getNumSubParts(); ++partIndex) {
    const LockedPart p(meshInterface, partIndex);
    if (p.vertexType != PHY_FLOAT && p.vertexType != PHY_DOUBLE) {
      fail(name, partIndex,
           std::string("has vertices of ") + typeName(p.vertexType) +
               "; only PHY_FLOAT and PHY_DOUBLE are read");
    }
    if (p.indexType != PHY_INTEGER && p.indexType != PHY_SHORT && p.indexType != PHY_UCHAR) {
      fail(name, partIndex,
           std::string("has indices of ") + typeName(p.indexType) +
               "; only PHY_INTEGER, PHY_SHORT and PHY_UCHAR are read");
    }
    if (p.vertexCount < 0 || p.triangleCount < 0 || (p.vertexCount > 0 && p.vertices == nullptr) ||
        (p.triangleCount > 0 && p.indices == nullptr)) {
      fail(name, partIndex,
           "has " + std::to_string(p.vertexCount) + " vertices and " + std::to_string(p.triangleCount) +
               " triangles with arrays missing");
    }
    MeshPart part;
    part.firstTriangle = std::uint32_t(indices.size() / 3);
    part.firstVertex = std::uint32_t(xyz.size() / 3);
    part.vertexCount = std::uint32_t(p.vertexCount);
    part.triangleCount = std::uint32_t(p.triangleCount);
    for (int v = 0; v < p.vertexCount; ++v) {
      for (int axis = 0; axis < 3; ++axis) {
        const double value = readCoordinate(p, v, axis);
        // A finite double beyond float's range would become infinite: refused like a non-finite one.
        if (!std::isfinite(value) || std::abs(value) > double(std::numeric_limits<float>::max())) {
          std::ostringstream what;
          what << "vertex " << v << " has coordinate " << axes[axis] << " = " << value
               << (std::isfinite(value) ? ", too large for float" : ", not finite");
          fail(name, partIndex, what.str());
        }
        xyz.push_back(float(value));
      }
    }
    for (int t = 0; t < p.triangleCount; ++t) {
      std::int64_t corner[3];
      for (int k = 0; k < 3; ++k) {
        corner[k] = readIndex(p, t, k);
        if (corner[k] < 0 || corner[k] >= p.vertexCount) {
          std::ostringstream what;
          what << "triangle " << t << " corner " << k << " has vertex index " << corner[k]
               << ", out of range for the part's " << p.vertexCount << " vertices";
          fail(name, partIndex, what.str());
        }
      }
      for (int k = 0; k < 3; ++k) {
        if (corner[k] == corner[(k + 1) % 3]) {
          std::ostringstream what;
          what << "triangle " << t << " repeats vertex index " << corner[k] << " (corners "
               << std::min(k, (k + 1) % 3) << " and " << std::max(k, (k + 1) % 3) << ")";
          fail(name, partIndex, what.str());
        }
      }
      for (int k = 0; k < 3; ++k) indices.push_back(part.firstVertex + std::uint32_t(corner[k]));
    }
    parts.push_back(part);
  }
  if (parts.empty()) throw MeshError(name + ": the mesh interface has no parts");
  return fromParts(std::move(xyz), std::move(indices), std::move(parts), std::move(name));
}

}  // namespace gpucol
