/* The grid of one pair search, shared by the host (opencl/host/opencl_pair_finder.cpp) and the kernels
   (opencl/kernels/grid_find_pairs.cl): the host fills it, uploads it as a one-element buffer, and checks
   its layout with static_assert. Plain C that compiles as C++ and as OpenCL C. */
#ifndef GPUCOL_OPENCL_SHARED_GRID_PARAMS_H
#define GPUCOL_OPENCL_SHARED_GRID_PARAMS_H

#ifdef __OPENCL_VERSION__
typedef uint gpucol_grid_uint;
typedef int gpucol_grid_int;
#else
#include <stdint.h>
typedef uint32_t gpucol_grid_uint;
typedef int32_t gpucol_grid_int;
#endif

/* Flag bits of a proxy slot; the host checks them against gpucol::kProxyActive / kProxyStatic. */
#define GPUCOL_PROXY_ACTIVE 1u
#define GPUCOL_PROXY_STATIC 2u

/* Uniform grid (paper §4.1–4.2): cell coordinate of x on an axis is
   clamp(floor((x - origin) * invCell), 0, dim - 1); cell index cx + dimX * (cy + dimY * cz) < 2^32. */
typedef struct GpucolGridParams {
  float originX;
  float originY;
  float originZ;
  float invCell;
  gpucol_grid_uint dimX;
  gpucol_grid_uint dimY;
  gpucol_grid_uint dimZ;
  gpucol_grid_uint unused;
} GpucolGridParams;

/* One proxy slot as the kernels read it: its box and its filter in 32 bytes, so that a candidate test loads
   one box from one cache line instead of a value from each of eight arrays (the flags stay in a byte
   array of their own, read only for the pairs that overlap). */
typedef struct GpucolProxyBox {
  float minX;
  float minY;
  float minZ;
  gpucol_grid_int group;
  float maxX;
  float maxY;
  float maxZ;
  gpucol_grid_int mask;
} GpucolProxyBox;

/* One proxy slot that changed since the last search (stage 11, resting proxies): while the device keeps the
   last grid, the host sends only these and grid_update_proxies writes them into the device's arrays and
   marks the slot as no longer resting. A destroyed proxy comes with flags 0. */
typedef struct GpucolProxyUpdate {
  GpucolProxyBox box;
  gpucol_grid_uint slot;
  gpucol_grid_uint flags;
} GpucolProxyUpdate;

#endif /* GPUCOL_OPENCL_SHARED_GRID_PARAMS_H */
