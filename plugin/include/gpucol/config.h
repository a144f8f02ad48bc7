#pragma once

#include <string>

namespace gpucol {

/// Where a stage runs: Cpu and OpenCL force one. Auto chooses per batch (broad phase: per step) from its
/// size, with a crossover measured on the device in use: while the chosen OpenCL device is a GPU, the first
/// calls of each size class run on both paths in turn and the faster keeps the class; with a CPU OpenCL
/// device or none, Auto runs on the CPU and never starts OpenCL (docs/options.md, "Backend::Auto").
enum class Backend { Auto, Cpu, OpenCL };

/// The knobs of the plugin, each with a measured default (docs/options.md).
struct Config {
  /// Backend of the mesh pipeline (middle phase, near phase, reduction).
  Backend meshBackend = Backend::Auto;
  /// Backend of the grid broad phase.
  Backend broadphaseBackend = Backend::Auto;
  /// Bins per dimension of the 6-D contact binning (thesis §5.3.5); 0 turns reduction off.
  int reductionResolution = 4;
  /// Triangles per leaf of the non-updated AABB tree (thesis §5.3.2 uses 1).
  int trianglesPerLeaf = 1;
  /// Proxy count under which the broad phase tests all pairs without a grid. The paper found ~1000 on a GPU
  /// (Table 7); on the CPU path the grid catches up at about 128 (`gpucol-bench broadphase
  /// --brute-force-below`; docs/options.md).
  int bruteForceBelow = 128;
  /// Substring of the OpenCL device name to use; the environment variable GPUCOL_OPENCL_DEVICE overrides it.
  std::string openclDevice;
  /// Under gpucol::CollisionDispatcher, pairs of btGImpactMeshShapes, and a GImpact mesh against a plane or
  /// another concave shape, go through gpucol's mesh pipeline (a MeshShape stands in for each GImpact mesh);
  /// false leaves them to the algorithm Bullet's configuration gives (GImpact's where registered). A
  /// MeshShape against a GImpact mesh is gpucol's either way.
  bool collideGImpactShapes = true;
};

}  // namespace gpucol
