#pragma once

#include <CLI/CLI.hpp>

namespace gpucol::bench {

/// `gpucol-bench meshpair`: the thesis scene per mesh, gpucol beside btGImpactCollisionAlgorithm.
void addMeshPairCommand(CLI::App& app);
/// `gpucol-bench broadphase`: moving boxes per step, gpucol beside Bullet's broad phases.
void addBroadphaseCommand(CLI::App& app);

}  // namespace gpucol::bench
