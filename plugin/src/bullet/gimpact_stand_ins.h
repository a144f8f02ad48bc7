#pragma once

#include <cstdint>
#include <memory>
#include <unordered_map>
#include <vector>

#include "gpucol/config.h"
#include "gpucol/mesh_shape.h"

class btCollisionShape;
class btGImpactMeshShape;

namespace gpucol {

/// The MeshShape that stands in for each btGImpactMeshShape a gpucol::CollisionDispatcher collides: built the
/// first time a pair needs the shape (its tree once, not per pair), kept, and built again when the shape's
/// triangles change. A change is found by a fingerprint taken at most once per step: each part's arrays
/// (address, counts, types, strides), a hash of its vertex coordinates, its scaling and its margin. Users who
/// move a GImpact mesh's vertices call postUpdate()/updateBound() for GImpact's sake; the fingerprint sees
/// the new vertices whether they do or not.
class GImpactStandIns {
 public:
  explicit GImpactStandIns(const Config& config) : m_config(config) {}

  /// True when `shape` is a btGImpactMeshShape (a GImpact trimesh, not a compound or a single part).
  static bool isGImpactMesh(const btCollisionShape* shape);

  /// The stand-in for `shape` in this step; null when its triangles cannot be read (bad indices, NaN
  /// vertices: said once), so that its pairs are not collided by gpucol.
  const MeshShape* get(const btGImpactMeshShape& shape);

  /// Starts a new step: each shape's fingerprint is taken again at its first get(). Shapes that no pair asked
  /// for during kForgetAfterSteps steps are forgotten (a deleted shape's stand-in does not stay for good).
  void beginStep();

  /// Stand-ins built (first or again) since the counter was last reset.
  std::uint64_t built() const { return m_built; }
  /// Resets built() to 0.
  void resetBuilt() { m_built = 0; }

  /// A minute of steps at 60 Hz: long enough that a shape resting out of reach keeps its stand-in.
  static constexpr std::uint64_t kForgetAfterSteps = 3600;

 private:
  struct Entry {
    std::unique_ptr<MeshShape> shape;  // null when the triangles could not be read
    std::vector<std::uint64_t> fingerprint;
    std::uint64_t checkedStep = 0;
  };

  Config m_config;
  std::unordered_map<const btGImpactMeshShape*, Entry> m_entries;
  std::uint64_t m_step = 1;
  std::uint64_t m_built = 0;
};

}  // namespace gpucol
