#pragma once

#include <LinearMath/btTransform.h>
#include <LinearMath/btVector3.h>
#include <gpucol/triangle_mesh.h>

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

namespace gpucol::scenes {

/// One rigid body of a scene: which of the scene's meshes it is, its mass and where it starts.
struct SceneBody {
  std::size_t mesh = 0;  ///< Index into SceneDescription::meshes.
  float mass = 0;        ///< Kilograms; 0 makes the body static.
  btTransform start;     ///< Pose at step 0 (the mesh's frame is the body's frame).
};

/// One convex piece of a mesh's solid, for the reference world built of Bullet's own convex shapes.
struct ConvexPiece {
  enum class Kind { Box, Sphere, Capsule, Hull };
  Kind kind = Kind::Box;
  /// Box: half extents. Sphere: the radius in x. Capsule: the radius in x, and half the distance between its
  /// caps' centres in y (the capsule lies along its own y axis). Hull: unused.
  btVector3 size{0, 0, 0};
  btTransform pose = btTransform::getIdentity();  ///< Where the piece lies in the mesh's frame.
  std::vector<btVector3> points;                  ///< Hull: the points whose convex hull is the piece.
};

/// A world to build, with either collision backend: meshes shared between bodies (one shape per mesh), the
/// bodies, gravity and the ground's height. Dynamic meshes are in their principal frame, so that a diagonal
/// inertia is the whole tensor.
struct SceneDescription {
  std::string name;                                         ///< "stack", "pile", or the mesh file's name.
  std::vector<std::shared_ptr<const TriangleMesh>> meshes;  ///< Shared by the bodies that use them.
  /// Per mesh, the same solid as convex pieces (CollisionBackend::Primitives); empty where none is known.
  std::vector<std::vector<ConvexPiece>> convexPieces;
  std::vector<SceneBody> bodies;                            ///< Static and dynamic bodies, in creation order.
  btVector3 gravity{0, -9.81f, 0};                          ///< Metres per second squared, y is up.
  float groundTop =
      0;  ///< Height of the ground's upper face: zero of the potential energy; below it is "fell".
  /// How far below groundTop a centre of mass may be before the body counts as through the ground (metres):
  /// thin bodies that land fast dip below the face for a step, with Bullet's own convex shapes too.
  float fallTolerance = 0;
  /// Size of the scene (metres): positions beyond a hundred times this from the origin count as an explosion.
  float extent = 10;
  /// Index among the dynamic bodies of the one whose height drift is reported (the stack's top box), or -1.
  int trackedBody = -1;
};

}  // namespace gpucol::scenes
