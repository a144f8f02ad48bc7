/* Structs of the OpenCL mesh pipeline shared by the host (opencl/host/mesh_pipeline.cpp, which checks their
   layout with static_assert) and the kernels (opencl/kernels/mesh_middle_phase.cl, mesh_near_phase.cl).
   Plain C that compiles as C++ and as OpenCL C; 4-byte fields only, so both sides lay them out alike. */
#ifndef GPUCOL_OPENCL_SHARED_MESH_PIPELINE_TYPES_H
#define GPUCOL_OPENCL_SHARED_MESH_PIPELINE_TYPES_H

#ifdef __OPENCL_VERSION__
typedef uint gpucol_mesh_uint;
#else
#include <stdint.h>
typedef uint32_t gpucol_mesh_uint;
#endif

/* One frame's side of the traversal's box test (bvh/tree_traversal.h, BoxMap): the map that carries the other
   tree's boxes into this frame, row-major, its absolute values, and the widening. */
typedef struct GpucolBoxMap {
  float linear[9];
  float translation[3];
  float absLinear[9];
  float inflation[3];
} GpucolBoxMap;

/* One mesh pair of a batch: the device's layout of the pair's frame (PairFrame, plugin/src/mesh_pairs/
   pair_frame.h, which opencl/host/mesh_pipeline.cpp writes here) and the pair's place in the resident
   arenas. Matrices are row-major. The traversal tests boxes in both frames, as the CPU's does: B's boxes
   carried into A's unscaled mesh frame (intoA) and A's into B's (intoB); the near phase builds A's triangles
   in A's scaled frame (scaleA, flipA) and carries B's in (bLinear, bTranslation, flipB), as the CPU's does. */
typedef struct GpucolMeshPair {
  GpucolBoxMap intoA;
  GpucolBoxMap intoB;
  float bLinear[9];
  float bTranslation[3];
  float scaleA[3];
  gpucol_mesh_uint nodesA; /* first node of A's tree in the node arena */
  gpucol_mesh_uint nodesB;
  gpucol_mesh_uint entriesA; /* first leaf entry of A's tree in the entry arena */
  gpucol_mesh_uint entriesB;
  gpucol_mesh_uint trianglesA; /* first triangle of A's mesh in the triangle soup arena (9 floats each) */
  gpucol_mesh_uint trianglesB;
  gpucol_mesh_uint flipA; /* 1: A's scaling mirrors the mesh, swap vertices 1 and 2 */
  gpucol_mesh_uint flipB;
} GpucolMeshPair;

/* A tree node as bvh/aabb_tree.h stores it (AabbNode): inner when count == 0 (left child next, right child
   `first`), a leaf of one triangle `first` when count == 1, else `count` entries from `first`. */
typedef struct GpucolTreeNode {
  float min[3];
  float max[3];
  gpucol_mesh_uint first;
  gpucol_mesh_uint count;
} GpucolTreeNode;

/* A triangle of a leaf of several, with its own box (AabbLeafEntry). */
typedef struct GpucolLeafEntry {
  float min[3];
  float max[3];
  gpucol_mesh_uint triangle;
} GpucolLeafEntry;

/* A node pair of the breadth-first front whose boxes overlap: the pair of the batch it belongs to (the
   front is segmented over all pairs, thesis §7.3) and a node of each tree, relative to the tree's first. */
typedef struct GpucolFrontEntry {
  gpucol_mesh_uint pair;
  gpucol_mesh_uint a;
  gpucol_mesh_uint b;
} GpucolFrontEntry;

/* Bits of GpucolNearHit::flags. */
#define GPUCOL_HIT_CONTACT 1u      /* a contact was kept for this intersecting pair */
#define GPUCOL_HIT_ON_FACE_OF_B 2u /* TriangleContact::onFaceOfB */
#define GPUCOL_HIT_SAME_FACING 4u  /* TriangleContact::sameFacing */
#define GPUCOL_HIT_INTERSECTS                                                   \
  0x80000000u /* the triangles intersect (the records of every tested candidate \
                 come back; the host keeps these) */

/* One intersecting candidate and its contact (TriangleContact, in A's scaled frame). */
typedef struct GpucolNearHit {
  gpucol_mesh_uint candidate; /* index into the sorted candidate keys */
  gpucol_mesh_uint flags;
  float point[3];
  float normal[3];
  float depth;
  float deepest[3];
} GpucolNearHit;

#endif /* GPUCOL_OPENCL_SHARED_MESH_PIPELINE_TYPES_H */
