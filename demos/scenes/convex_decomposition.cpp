#include "scenes/convex_decomposition.h"

#include <HACD/hacdHACD.h>

#include <stdexcept>
#include <string>

namespace gpucol::scenes {

std::vector<ConvexPiece> decomposeConvex(const TriangleMesh& mesh, const DecompositionOptions& options) {
  const std::vector<float>& xyz = mesh.positions();
  const std::vector<std::uint32_t>& indices = mesh.indices();
  std::vector<HACD::Vec3<HACD::Real>> points;
  points.reserve(mesh.vertexCount());
  for (std::size_t i = 0; i < xyz.size(); i += 3) points.emplace_back(xyz[i], xyz[i + 1], xyz[i + 2]);
  std::vector<HACD::Vec3<long>> triangles;
  triangles.reserve(mesh.triangleCount());
  for (std::size_t i = 0; i < indices.size(); i += 3)
    triangles.emplace_back(long(indices[i]), long(indices[i + 1]), long(indices[i + 2]));

  HACD::HACD hacd;
  hacd.SetPoints(points.data());
  hacd.SetNPoints(points.size());
  hacd.SetTriangles(triangles.data());
  hacd.SetNTriangles(triangles.size());
  hacd.SetNClusters(options.minHulls);
  hacd.SetConcavity(options.concavity);
  hacd.SetNVerticesPerCH(options.maxHullVertices);
  // Compactness over volume, as Bullet's own decomposition demo weighs them.
  hacd.SetCompacityWeight(0.1);
  hacd.SetVolumeWeight(0.0);
  hacd.SetAddExtraDistPoints(options.extraPoints);
  hacd.SetAddNeighboursDistPoints(false);
  hacd.SetAddFacesPoints(options.extraPoints);
  if (!hacd.Compute()) throw std::runtime_error("HACD failed on mesh '" + mesh.name() + "'");

  std::vector<ConvexPiece> pieces;
  for (std::size_t c = 0; c < hacd.GetNClusters(); ++c) {
    std::vector<HACD::Vec3<HACD::Real>> hullPoints(hacd.GetNPointsCH(c));
    std::vector<HACD::Vec3<long>> hullTriangles(hacd.GetNTrianglesCH(c));
    if (hullPoints.size() < 4) continue;  // a flat cluster holds no volume
    hacd.GetCH(c, hullPoints.data(), hullTriangles.data());
    ConvexPiece piece;
    piece.kind = ConvexPiece::Kind::Hull;
    for (const auto& p : hullPoints)
      piece.points.emplace_back(btScalar(p.X()), btScalar(p.Y()), btScalar(p.Z()));
    pieces.push_back(std::move(piece));
  }
  if (pieces.empty()) throw std::runtime_error("HACD gave no hull for mesh '" + mesh.name() + "'");
  return pieces;
}

}  // namespace gpucol::scenes
