#pragma once
// How deep bodies really overlap, whatever collision code ran: each pair of bodies in contact is measured on
// the convex pieces of its solids (SceneDescription::convexPieces) with Bullet's GJK and EPA. A mesh pair's
// contact depths are those of its crossing triangle pairs, not the bodies' (docs/contacts.md), so comparing
// piles of meshes with piles of convex shapes needs a measure both share.
#include <btBulletCollisionCommon.h>

#include <memory>
#include <vector>

#include "scenes/scene_description.h"

namespace gpucol::scenes {

/// The convex pieces of a scene's meshes as Bullet shapes, and the overlap of two bodies made of them.
class BodyOverlap {
 public:
  /// Shapes for the pieces of every mesh of `scene` (meshes without pieces get none).
  explicit BodyOverlap(const SceneDescription& scene);
  ~BodyOverlap();
  BodyOverlap(const BodyOverlap&) = delete;
  BodyOverlap& operator=(const BodyOverlap&) = delete;

  /// True when every mesh of the scene has convex pieces.
  bool complete() const { return m_complete; }
  /// Deepest overlap (metres, >= 0; 0 when apart or touching) of any piece of mesh `meshA` at `a` with any
  /// piece of mesh `meshB` at `b`.
  float deepest(std::size_t meshA, const btTransform& a, std::size_t meshB, const btTransform& b) const;

 private:
  struct Piece {
    std::unique_ptr<btConvexShape> shape;
    btTransform pose;
  };
  std::vector<std::vector<Piece>> m_pieces;  // by mesh
  bool m_complete = true;
};

}  // namespace gpucol::scenes
