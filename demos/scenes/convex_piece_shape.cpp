#include "scenes/convex_piece_shape.h"

#include <BulletCollision/CollisionShapes/btBoxShape.h>
#include <BulletCollision/CollisionShapes/btCapsuleShape.h>
#include <BulletCollision/CollisionShapes/btConvexHullShape.h>
#include <BulletCollision/CollisionShapes/btSphereShape.h>

#include <stdexcept>

namespace gpucol::scenes {

std::unique_ptr<btConvexShape> makePieceShape(const ConvexPiece& piece) {
  switch (piece.kind) {
    case ConvexPiece::Kind::Box:
      return std::make_unique<btBoxShape>(piece.size);
    case ConvexPiece::Kind::Sphere:
      return std::make_unique<btSphereShape>(piece.size.x());
    case ConvexPiece::Kind::Capsule:
      return std::make_unique<btCapsuleShape>(piece.size.x(), 2 * piece.size.y());
    case ConvexPiece::Kind::Hull: {
      if (piece.points.size() < 4)
        throw std::invalid_argument("convex piece: a hull needs at least 4 points");
      auto hull = std::make_unique<btConvexHullShape>(&piece.points[0].x(), int(piece.points.size()),
                                                      int(sizeof(btVector3)));
      hull->optimizeConvexHull();
      // Bullet rounds a hull outward by its margin (boxes keep theirs inside): a thin one keeps the solid.
      hull->setMargin(kHullMargin);
      return hull;
    }
  }
  return nullptr;
}

}  // namespace gpucol::scenes
