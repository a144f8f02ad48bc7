#include "scenes/body_overlap.h"

#include <BulletCollision/NarrowPhaseCollision/btGjkEpaPenetrationDepthSolver.h>
#include <BulletCollision/NarrowPhaseCollision/btGjkPairDetector.h>
#include <BulletCollision/NarrowPhaseCollision/btPointCollector.h>
#include <BulletCollision/NarrowPhaseCollision/btVoronoiSimplexSolver.h>

#include <algorithm>

#include "scenes/convex_piece_shape.h"

namespace gpucol::scenes {

BodyOverlap::BodyOverlap(const SceneDescription& scene) {
  m_pieces.resize(scene.meshes.size());
  for (std::size_t mesh = 0; mesh < scene.meshes.size(); ++mesh) {
    if (mesh >= scene.convexPieces.size() || scene.convexPieces[mesh].empty()) {
      m_complete = false;
      continue;
    }
    for (const ConvexPiece& piece : scene.convexPieces[mesh]) {
      Piece p;
      p.pose = piece.pose;
      p.shape = makePieceShape(piece);
      m_pieces[mesh].push_back(std::move(p));
    }
  }
}

BodyOverlap::~BodyOverlap() = default;

float BodyOverlap::deepest(std::size_t meshA, const btTransform& a, std::size_t meshB, const btTransform& b) const {
  float deepest = 0;
  for (const Piece& pa : m_pieces[meshA]) {
    const btTransform ta = a * pa.pose;
    btVector3 loA, hiA;
    pa.shape->getAabb(ta, loA, hiA);
    for (const Piece& pb : m_pieces[meshB]) {
      const btTransform tb = b * pb.pose;
      btVector3 loB, hiB;
      pb.shape->getAabb(tb, loB, hiB);
      if (!TestAabbAgainstAabb2(loA, hiA, loB, hiB)) continue;
      btVoronoiSimplexSolver simplex;
      btGjkEpaPenetrationDepthSolver epa;
      btGjkPairDetector gjk(pa.shape.get(), pb.shape.get(), &simplex, &epa);
      btGjkPairDetector::ClosestPointInput input;
      input.m_transformA = ta;
      input.m_transformB = tb;
      btPointCollector out;
      gjk.getClosestPoints(input, out, nullptr);
      if (out.m_hasResult) deepest = std::max(deepest, float(-out.m_distance));
    }
  }
  return deepest;
}

}  // namespace gpucol::scenes
