/* Carrying a box or a point of one mesh's frame into another's by an affine map (M, t), in float: the CPU's
   middle phase (plugin/src/bvh/tree_traversal.cpp, BoxCarrier) and near phase (plugin/src/mesh_pairs/
   cpu_mesh_pair.cpp, transformRows) and the device's (opencl/kernels/mesh_middle_phase.cl,
   mesh_near_phase.cl) use these, so that both find the same candidates and test the same triangles.
   A box is carried with the |M| trick (thesis §3.3.3 sets the map up once per pair): centre' = M c + t,
   extent' = |M| e + inflation, which contains every point of the box mapped by M, t; the inflation covers the
   rounding (tree_traversal.h, kCarryRelativeEpsilon). */
#ifndef GPUCOL_SHARED_MATH_BOX_CARRY_H
#define GPUCOL_SHARED_MATH_BOX_CARRY_H

#include "plugin/src/shared_math/shared_c.h"

/* One row of a carried centre, ((M_i0 c_0 + M_i1 c_1) + M_i2 c_2) + t_i, or of a carried extent (|M| and e,
   plus the inflation): the order every form sums it in. A macro, so that the vector forms use it too: with
   m0..m2 a column of M per lane and x0..x2 the box's coordinates splatted, it carries a whole box at once
   (SSE and GCC vectors on the CPU, float4 and float8 on the device); a macro also reads any OpenCL address
   space. The box's centre and half extent are (lo + hi) * 0.5 and (hi - lo) * 0.5. */
#define GPUCOL_CARRY_ROW(m0, m1, m2, x0, x1, x2, add) ((((m0) * (x0) + (m1) * (x1)) + (m2) * (x2)) + (add))

/* Whether box [lo, hi] and the box [otherMin, otherMax] overlap on all three axes; touching counts (the
   comparisons are exact, all rounding went into the inflation). `&` rather than `&&`: the result feeds
   branch-free code. A macro, so that it reads boxes in any OpenCL address space. */
#define GPUCOL_BOXES_OVERLAP(lo, hi, otherMin, otherMax)                                  \
  (((lo)[0] <= (otherMax)[0]) & ((otherMin)[0] <= (hi)[0]) & ((lo)[1] <= (otherMax)[1]) & \
   ((otherMin)[1] <= (hi)[1]) & ((lo)[2] <= (otherMax)[2]) & ((otherMin)[2] <= (hi)[2]))

/* Coordinate i of point (x, y, z) carried by the row (m0, m1, m2) and translation t: m0 x + (m1 y + m2 z) +
   t, the order Eigen's 3x3 matrix times vector sums it in (the near phase's triangles of B in A's frame). */
GPUCOL_SHARED_INLINE float gpucol_carry_point(float m0, float m1, float m2, float x, float y, float z,
                                              float t) {
  return (m0 * x + (m1 * y + m2 * z)) + t;
}

#endif /* GPUCOL_SHARED_MATH_BOX_CARRY_H */
