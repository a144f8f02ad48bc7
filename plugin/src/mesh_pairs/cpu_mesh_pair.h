#pragma once
// One mesh pair on the CPU, and the step both paths end with: the near phase's hits into the pair's result.
#include <LinearMath/btTransform.h>

#include <vector>

#include "gpucol/collide_meshes.h"
#include "gpucol/config.h"
#include "mesh_pairs/mesh_batch_device.h"
#include "mesh_pairs/pair_frame.h"

namespace gpucol {

/// Throws std::invalid_argument when either transform has a NaN or infinite component.
void requireFinite(const btTransform& transformA, const btTransform& transformB);

class CandidateCache;

/// The query's pair on the CPU: root boxes, middle phase, near phase, contacts and their reduction. With a
/// `cache`, a pair without a speculative reach takes its candidates from it (the same contacts, fewer
/// traversals while the pair rests).
MeshPairResult collidePairOnCpu(const MeshPairQuery& query, const Config& config,
                                CandidateCache* cache = nullptr);

/// Fills `result`'s intersecting pairs, contacts and reduced contacts from the device's near phase's `hits`
/// (DeviceNearHit, in candidate order, indexing result.candidatePairs), with the proximity contacts of the
/// candidates that do not cross found on the CPU: the same result, by the same code, as collidePairOnCpu's.
template <class Hit>
void collectHits(const std::vector<Hit>& hits, const MeshShape& shapeA, const MeshShape& shapeB,
                 const PairFrame& frame, const Config& config, MeshPairResult& result);

}  // namespace gpucol
