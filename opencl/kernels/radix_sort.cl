// Stable least-significant-digit radix sort of (ulong key, uint value) pairs, or of keys alone, up to 4 bits
// per pass.
// Each work-item owns one chunk of consecutive elements and walks it in order, so the sort needs no local
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
