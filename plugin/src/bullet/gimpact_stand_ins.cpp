#include "bullet/gimpact_stand_ins.h"

#include <BulletCollision/Gimpact/btGImpactShape.h>

#include <cstring>
#include <exception>
#include <iterator>
#include <string>

#include "bullet/warn_once.h"

namespace gpucol {
namespace {

// Four independent FNV-1a style lanes over 32-bit words, so that the multiplies do not wait on each other; a
// hash, not a proof, of "the same vertices".
class WordHash {
 public:
  void add(const unsigned char* bytes, std::size_t words) {
    for (std::size_t i = 0; i < words; ++i) {
      std::uint32_t w;
      std::memcpy(&w, bytes + 4 * i, 4);
      std::uint64_t& lane = m_lanes[m_next++ & 3];
      lane = (lane ^ w) * 0x100000001b3ull;
    }
  }
  std::uint64_t value() const {
    std::uint64_t h = 0xcbf29ce484222325ull;
    for (std::uint64_t lane : m_lanes) h = (h ^ lane) * 0x100000001b3ull;
    return h;
  }

 private:
  std::uint64_t m_lanes[4] = {0xcbf29ce484222325ull, 0x84222325cbf29ce4ull, 0x9ce484222325cbf2ull,
                              0x2325cbf29ce48422ull};
  std::size_t m_next = 0;
};

std::uint64_t bits(btScalar value) {
  double d = double(value);
  std::uint64_t out;
  std::memcpy(&out, &d, sizeof(out));
  return out;
}

std::vector<std::uint64_t> fingerprint(const btGImpactMeshShape& shape) {
  std::vector<std::uint64_t> out;
  const btStridingMeshInterface& mesh = *shape.getMeshInterface();
  out.push_back(std::uint64_t(mesh.getNumSubParts()));
  for (int part = 0; part < mesh.getNumSubParts(); ++part) {
    const unsigned char *vertices, *indices;
    int vertexCount, vertexStride, indexStride, triangleCount;
    PHY_ScalarType vertexType, indexType;
    mesh.getLockedReadOnlyVertexIndexBase(&vertices, vertexCount, vertexType, vertexStride, &indices,
                                          indexStride, triangleCount, indexType, part);
    out.insert(out.end(),
               {std::uint64_t(reinterpret_cast<std::uintptr_t>(vertices)),
                std::uint64_t(reinterpret_cast<std::uintptr_t>(indices)), std::uint64_t(vertexCount),
                std::uint64_t(vertexStride), std::uint64_t(indexStride), std::uint64_t(triangleCount),
                std::uint64_t(vertexType), std::uint64_t(indexType)});
    const std::size_t words = vertexType == PHY_DOUBLE ? 6 : vertexType == PHY_FLOAT ? 3 : 0;
    WordHash hash;
    for (int v = 0; vertices != nullptr && v < vertexCount; ++v) {
      hash.add(vertices + std::size_t(v) * std::size_t(vertexStride), words);
    }
    out.push_back(hash.value());
    mesh.unLockReadOnlyVertexBase(part);
  }
  for (int part = 0; part < shape.getMeshPartCount(); ++part) {
    const btVector3& s = shape.getMeshPart(part)->getLocalScaling();
    out.insert(out.end(),
               {bits(s.x()), bits(s.y()), bits(s.z()), bits(shape.getMeshPart(part)->getMargin())});
  }
  return out;
}

}  // namespace

bool GImpactStandIns::isGImpactMesh(const btCollisionShape* shape) {
  return shape != nullptr && shape->getShapeType() == GIMPACT_SHAPE_PROXYTYPE &&
         static_cast<const btGImpactShapeInterface*>(shape)->getGImpactShapeType() ==
             CONST_GIMPACT_TRIMESH_SHAPE;
}

const MeshShape* GImpactStandIns::get(const btGImpactMeshShape& shape) {
  Entry& entry = m_entries[&shape];
  if (entry.checkedStep == m_step) return entry.shape.get();
  const bool firstLook = entry.checkedStep == 0;
  entry.checkedStep = m_step;
  std::vector<std::uint64_t> now = fingerprint(shape);
  if (!firstLook && now == entry.fingerprint) return entry.shape.get();
  entry.fingerprint = std::move(now);
  entry.shape.reset();
  try {
    entry.shape = MeshShape::fromGImpact(shape, m_config);
    ++m_built;
  } catch (const std::exception& e) {
    warnOnce("gimpact " + std::to_string(reinterpret_cast<std::uintptr_t>(&shape)),
             std::string("gpucol cannot collide a btGImpactMeshShape (its pairs go to the algorithm Bullet's "
                         "configuration gives, GImpact's where registered): ") +
                 e.what());
  }
  return entry.shape.get();
}

void GImpactStandIns::beginStep() {
  ++m_step;
  for (auto it = m_entries.begin(); it != m_entries.end();) {
    it = m_step - it->second.checkedStep > kForgetAfterSteps ? m_entries.erase(it) : std::next(it);
  }
}

}  // namespace gpucol
