#pragma once
// collideMeshes and collideMeshesBatch with the pairs' candidate caches: MeshMeshAlgorithm's way in.
#include <vector>

#include "gpucol/collide_meshes.h"
#include "gpucol/config.h"

namespace gpucol {

class CandidateCache;

/// collideMeshesBatch, where each pair that runs on the CPU keeps its candidates in caches[i] (null: none;
/// candidate_cache.h). `caches` is empty or as long as `queries`. The results are collideMeshesBatch's.
std::vector<MeshPairResult> collideMeshesBatch(const std::vector<MeshPairQuery>& queries,
                                               const Config& config,
                                               const std::vector<CandidateCache*>& caches);

/// collideMeshes for one pair with its candidate cache (null: none).
MeshPairResult collideMeshes(const MeshPairQuery& query, const Config& config, CandidateCache* cache);

}  // namespace gpucol
