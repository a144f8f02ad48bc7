#pragma once

#include <BulletDynamics/Dynamics/btRigidBody.h>
#include <LinearMath/btVector3.h>
#include <gpucol/config.h>

#include <cstddef>
#include <memory>
#include <unordered_map>
#include <vector>

#include "scenes/scene_description.h"

class btBroadphaseInterface;
class btCollisionConfiguration;
class btCollisionDispatcher;
class btCollisionShape;
class btConstraintSolver;
class btDiscreteDynamicsWorld;

namespace gpucol {
class CollisionDispatcher;
}

namespace gpucol::scenes {

class BodyOverlap;

/// The collision code a WorldScene runs on.
enum class CollisionBackend {
  Gpucol,   ///< gpucol::MeshShape, gpucol::CollisionDispatcher and gpucol::GridBroadphase.
  GImpact,  ///< btGImpactMeshShape, btCollisionDispatcher with GImpact registered, and btDbvtBroadphase.
  /// Bullet's convex shapes (boxes, spheres, compounds of boxes and capsules) of the scene's convex pieces,
  /// btCollisionDispatcher and btDbvtBroadphase: the reference that mesh piles are held to.
  Primitives,
  /// The GImpact world with one line changed: gpucol::CollisionDispatcher in place of btCollisionDispatcher
  /// (GImpact still registered on it, btGImpactMeshShape bodies, btDbvtBroadphase).
  GImpactOnGpucol,
};

/// "gpucol", "gimpact", "primitives" or "gimpact-gpucol".
const char* backendName(CollisionBackend backend);

/// How a WorldScene is built.
struct WorldOptions {
  CollisionBackend backend = CollisionBackend::Gpucol;  ///< Which collision code.
  Config config;                                        ///< gpucol's knobs (Gpucol backend only).
  /// Collision margin of every GImpact shape (metres). Measured on makeStackScene: with 0, a box on a box
  /// slides off the one below (boxes end half inside each other); with 0.01 two boxes stand. Bodies rest
  /// about twice the margin apart. Ten boxes fall over with any margin from 0 to 0.04. Ignored by the Gpucol
  /// backend, whose shapes keep margin 0.
  float gimpactMargin = 0.01f;
  /// Collision margin of every MeshShape (metres; Gpucol backend): 0 is Bullet's default for concave shapes.
  /// With a margin, triangles that come within both margins give contacts and bodies rest that far apart.
  float meshMargin = 0.0f;
  /// Whether bodies may fall asleep (Bullet's default deactivation). False keeps every body simulated, so
  /// that resting contacts are tested every step.
  bool allowSleeping = true;
  /// Iterations of the sequential impulse solver (Bullet's default is 10).
  int solverIterations = 10;
};

/// A Bullet world built from a SceneDescription with one collision backend. It owns everything (shapes,
/// bodies, world, solver, broad phase, dispatcher, collision configuration) and destroys it in the order
/// Bullet needs: bodies out of the world first, then the world, then what the world used.
class WorldScene {
 public:
  /// Builds the shapes (one per mesh), the world and the bodies. Throws MeshError when a dynamic body's mesh
  /// has no mass properties (open mesh), std::invalid_argument for a body naming a mesh that does not exist
  /// or, on the Primitives backend, a mesh without convex pieces.
  WorldScene(const SceneDescription& scene, const WorldOptions& options);
  ~WorldScene();
  WorldScene(const WorldScene&) = delete;
  WorldScene& operator=(const WorldScene&) = delete;

  /// Advances the world by exactly one step of `dt` seconds (no sub-stepping, no interpolation).
  void step(float dt);

  /// The Bullet world.
  btDiscreteDynamicsWorld& world() { return *m_world; }
  /// The description the scene was built from.
  const SceneDescription& description() const { return m_scene; }
  /// The options the scene was built with.
  const WorldOptions& options() const { return m_options; }
  /// The dynamic bodies, in the order of the description.
  const std::vector<btRigidBody*>& dynamicBodies() const { return m_dynamicBodies; }
  /// gpucol's dispatcher (for its per-step statistics), or null on the backends with Bullet's own (GImpact,
  /// primitives).
  const CollisionDispatcher* gpucolDispatcher() const;

  /// Kinetic energy of the dynamic bodies (joules): linear plus rotational, in double.
  double kineticEnergy() const;
  /// Potential energy of the dynamic bodies' centres of mass above the ground's top face (joules).
  double potentialEnergy() const;
  /// Depth of the deepest contact of the last step (metres, >= 0): minus the most negative distance over
  /// every point of every manifold; 0 when nothing penetrates.
  float largestPenetration() const;
  /// Deepest overlap of two bodies that have contacts after the last step (metres, >= 0), measured on the
  /// convex pieces of their solids whatever the backend (BodyOverlap); -1 when some mesh has no pieces.
  float deepestBodyOverlap() const;
  /// Contact points in all manifolds after the last step.
  int contactCount() const;
  /// True when every dynamic body sleeps or moves slower than `linearSpeed` (m/s) and turns slower than
  /// `angularSpeed` (rad/s).
  bool allAtRest(float linearSpeed = kRestLinearSpeed, float angularSpeed = kRestAngularSpeed) const;
  /// Dynamic bodies that are neither asleep nor below the rest speeds.
  int movingBodyCount(float linearSpeed = kRestLinearSpeed, float angularSpeed = kRestAngularSpeed) const;
  /// Dynamic bodies that sleep (Bullet's ISLAND_SLEEPING).
  int sleepingBodyCount() const;
  /// Centre of mass of each dynamic body, in the order of dynamicBodies().
  std::vector<btVector3> positions() const;
  /// False when any dynamic body's position, orientation or velocity is NaN or infinite.
  bool allFinite() const;
  /// Dynamic bodies whose centre of mass is below the ground's top face (less
  /// SceneDescription::fallTolerance): they went through the ground (or fell off its edge).
  int bodiesBelowGround() const;
  /// Largest distance of a dynamic body's centre of mass from the origin (metres).
  float farthestBody() const;

  /// Default rest speed (m/s). A body whose support gives way gains g·dt = 0.16 m/s in one 1/60 s step; one
  /// held by its contacts keeps only the solver's residue, a few mm/s at most in Bullet. 5 mm/s (3 % of g·dt)
  /// separates the two. Bullet's own sleeping thresholds (0.8 m/s, 1 rad/s for 2 s) are far too lax for this.
  static constexpr float kRestLinearSpeed = 0.005f;
  /// Default rest angular speed (rad/s): the same 5 mm/s a quarter metre from the centre of mass.
  static constexpr float kRestAngularSpeed = 0.02f;

 private:
  struct Shapes;

  SceneDescription m_scene;
  WorldOptions m_options;
  std::unique_ptr<btCollisionConfiguration> m_collisionConfiguration;
  std::unique_ptr<btCollisionDispatcher> m_dispatcher;
  std::unique_ptr<btBroadphaseInterface> m_broadphase;
  std::unique_ptr<btConstraintSolver> m_solver;
  std::unique_ptr<btDiscreteDynamicsWorld> m_world;
  std::unique_ptr<Shapes> m_shapes;
  std::vector<std::unique_ptr<btRigidBody>> m_bodies;
  std::vector<btRigidBody*> m_dynamicBodies;
  std::unordered_map<const btCollisionObject*, std::size_t> m_bodyIndex;  // index in m_scene.bodies
  mutable std::unique_ptr<BodyOverlap> m_overlap;  // made by the first deepestBodyOverlap()
};

}  // namespace gpucol::scenes
