// Stable least-significant-digit radix sort of (ulong key, uint value) pairs, or of keys alone, up to 4 bits
// per pass, in two shapes: chunks for a CPU device, tiles for a GPU (radix_tile_*, below).
// Chunks: each work-item owns one chunk of consecutive elements and walks it in order, so the sort needs no local
// memory and no barriers (PoCL's CPU device runs barrier-heavy tile sorts slowly, and a GPU keeps enough
// items in flight with short chunks):
//  radix_count:   digit histogram of each chunk, written digit-major (counts[digit * chunks + chunk]), so
//                 that one exclusive scan of the whole array (scan.cl) gives every chunk's first output
//                 slot for every digit with chunks of equal digit kept in order — the sort is stable.
//  radix_scatter: walks its chunk again in order and writes each element to its digit's next slot (the
//                 values too, unless they are null: keys sorted alone).

#define RADIX 16u

__kernel void radix_count(__global const ulong* keys, const uint n, const uint shift, const uint digitMask,
                          const uint chunkLength, const uint chunks, __global uint* counts) {
  const uint chunk = get_global_id(0);
  if (chunk >= chunks) {
    return;
  }
  uint histogram[RADIX];
  for (uint d = 0u; d < RADIX; ++d) {
    histogram[d] = 0u;
  }
  const uint begin = chunk * chunkLength;
  const uint end = min(n, begin + chunkLength);
  for (uint i = begin; i < end; ++i) {
    ++histogram[(uint)(keys[i] >> shift) & digitMask];
  }
  for (uint d = 0u; d <= digitMask; ++d) {
    counts[d * chunks + chunk] = histogram[d];
  }
}

__kernel void radix_scatter(__global const ulong* keysIn, __global const uint* valuesIn,
                            __global ulong* keysOut, __global uint* valuesOut, const uint n, const uint shift,
                            const uint digitMask, const uint chunkLength, const uint chunks,
                            __global const uint* offsets) {
  const uint chunk = get_global_id(0);
  if (chunk >= chunks) {
    return;
  }
  uint next[RADIX];
  for (uint d = 0u; d <= digitMask; ++d) {
    next[d] = offsets[d * chunks + chunk];
  }
  const uint begin = chunk * chunkLength;
  const uint end = min(n, begin + chunkLength);
  for (uint i = begin; i < end; ++i) {
    const ulong key = keysIn[i];
    const uint destination = next[(uint)(key >> shift) & digitMask]++;
    keysOut[destination] = key;
    if (valuesOut != 0) {
      valuesOut[destination] = valuesIn[i];
    }
  }
}

// Tiles, a GPU's shape: work-group g owns the tile of its size at g * size, one element per work-item, so that
// loads and stores are coalesced and the histograms live in local memory:
//  radix_tile_count:   the tile's digit histogram by local atomics, written digit-major (counts[digit * tiles +
//                      tile]) as radix_count's, so the same scan gives each tile's first slot per digit.
//  radix_tile_scatter: sorts the tile by digit in local memory (one stable split per bit of the digit, each a
//                      local prefix sum), then element p of the sorted tile goes to its digit's first slot plus
//                      p less the digit's first place in the tile: consecutive elements of one digit go to
//                      consecutive addresses. Elements past n take the largest digit and stay last (they come
//                      after every element of the tile), so they move no one else, and are not written.
// The work-group size is a power of two (the host's), TILE_MAX at most.
#define TILE_MAX 256u

__kernel void radix_tile_count(__global const ulong* keys, const uint n, const uint shift, const uint digitMask,
                               const uint tiles, __global uint* counts) {
  __local uint histogram[RADIX];
  const uint lid = get_local_id(0);
  if (lid < RADIX) histogram[lid] = 0u;
  barrier(CLK_LOCAL_MEM_FENCE);
  const uint i = get_global_id(0);
  if (i < n) atomic_inc(&histogram[(uint)(keys[i] >> shift) & digitMask]);
  barrier(CLK_LOCAL_MEM_FENCE);
  if (lid <= digitMask) counts[lid * tiles + get_group_id(0)] = histogram[lid];
}

// Exclusive prefix sum of flag over the work-group (Hillis-Steele in `scratch`); the total in *total.
uint radix_tile_exclusive_sum(uint flag, __local uint* scratch, __local uint* total) {
  const uint lid = get_local_id(0), size = get_local_size(0);
  scratch[lid] = flag;
  barrier(CLK_LOCAL_MEM_FENCE);
  for (uint step = 1u; step < size; step <<= 1) {
    const uint add = lid >= step ? scratch[lid - step] : 0u;
    barrier(CLK_LOCAL_MEM_FENCE);
    scratch[lid] += add;
    barrier(CLK_LOCAL_MEM_FENCE);
  }
  const uint inclusive = scratch[lid];
  if (lid == size - 1u) *total = inclusive;
  barrier(CLK_LOCAL_MEM_FENCE);
  return inclusive - flag;
}

#define PAST_N 0x80000000u

__kernel void radix_tile_scatter(__global const ulong* keysIn, __global const uint* valuesIn,
                                 __global ulong* keysOut, __global uint* valuesOut, const uint n,
                                 const uint shift, const uint digitMask, const uint bits, const uint tiles,
                                 __global const uint* offsets) {
  __local ulong tileKeys[TILE_MAX];
  __local uint tileValues[TILE_MAX];
  __local uint tileTags[TILE_MAX];  // the digit, with PAST_N for an element past n
  __local uint scratch[TILE_MAX];
  __local uint digitStart[RADIX];
  __local uint zeros;
  const uint lid = get_local_id(0);
  const uint i = get_global_id(0);
  ulong key = i < n ? keysIn[i] : 0ul;
  uint value = i < n && valuesOut != 0 ? valuesIn[i] : 0u;
  uint tag = i < n ? (uint)(key >> shift) & digitMask : digitMask | PAST_N;
  for (uint bit = 0u; bit < bits; ++bit) {
    const uint one = (tag >> bit) & 1u;
    const uint zerosBefore = radix_tile_exclusive_sum(1u - one, scratch, &zeros);
    const uint place = one ? zeros + (lid - zerosBefore) : zerosBefore;
    tileKeys[place] = key;
    tileValues[place] = value;
    tileTags[place] = tag;
    barrier(CLK_LOCAL_MEM_FENCE);
    key = tileKeys[lid];
    value = tileValues[lid];
    tag = tileTags[lid];
    barrier(CLK_LOCAL_MEM_FENCE);
  }
  const uint digit = tag & digitMask;
  if (lid == 0u || (tileTags[lid - 1u] & digitMask) != digit) digitStart[digit] = lid;
  barrier(CLK_LOCAL_MEM_FENCE);
  if ((tag & PAST_N) == 0u) {
    const uint destination = offsets[digit * tiles + get_group_id(0)] + (lid - digitStart[digit]);
    keysOut[destination] = key;
    if (valuesOut != 0) valuesOut[destination] = value;
  }
}
