#pragma once
// One Bullet convex shape per ConvexPiece, for the reference world and for the overlap measure alike, so
// both see the same solids.
#include <BulletCollision/CollisionShapes/btConvexShape.h>

#include <memory>

#include "scenes/scene_description.h"

namespace gpucol::scenes {

/// Collision margin of hull pieces (metres): Bullet's default, 4 cm, would grow a 0.3 m body by a quarter.
inline constexpr float kHullMargin = 0.002f;

/// The piece as a Bullet shape in its own frame (btBoxShape, btSphereShape, btCapsuleShape or
/// btConvexHullShape with margin kHullMargin); place it with `piece.pose`.
std::unique_ptr<btConvexShape> makePieceShape(const ConvexPiece& piece);

}  // namespace gpucol::scenes
