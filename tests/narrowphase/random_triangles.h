#pragma once

// Random triangle pairs for the near phase tests, in families that stress the exact test: general
// near pairs, near-coplanar, exactly coplanar, touching, and slightly separated pairs.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <random>
#include <string>

#include "reference_triangles.h"

namespace gpucol::test {

/// The families of pairs that randomPair draws.
enum class PairFamily {
  General,        ///< Two random triangles in overlapping boxes.
  NearCoplanar,   ///< B in A's plane, lifted and tilted by 1e-7..1e-2 of the size.
  ExactCoplanar,  ///< Dyadic coordinates in a plane that float represents exactly.
  SharedVertex,   ///< B has one of A's vertices.
  VertexOnFace,   ///< A vertex of B on A's face (up to float rounding).
  EdgeOnEdge,     ///< A point of an edge of B on an edge of A (up to float rounding).
  NearTouching,   ///< A touching pair moved by 1e-7..1e-2 of its size along a random direction.
  Count
};

/// Name of a family, for messages.
std::string familyName(PairFamily family);

/// A uniformly random rotation.
Eigen::Matrix3d randomRotation(std::mt19937_64& rng);

/// A random non-degenerate triangle pair of the given family; the pair is also scaled by a random power of
/// ten in [1e-3, 1e3] and translated, so the tests see the tolerances working in relative terms.
void randomPair(PairFamily family, std::mt19937_64& rng, TriangleF& a, TriangleF& b);

/// A triangle whose smallest angle is not tiny (sin^2 at every vertex above 1e-4): the random families
/// use such triangles so that their results depend on the pair, not on a sliver's ill-defined plane.
bool wellShaped(const TriangleF& t);

}  // namespace gpucol::test
