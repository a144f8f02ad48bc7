// Exclusive prefix sum of uint, any length, in place (thesis §5.4.2, Alg. 5.4; Blelloch's work-efficient
// up-sweep / down-sweep). Each work-group of L items scans a block of 2L values in local memory and writes
// the block's total; the host scans the block totals the same way (recursively) and scan_add_block_offsets
// adds them back. A carry in any addition of the up-sweep means the total exceeds 2^32 - 1: every partial
// sum is a sum of non-negative values, so the first addition past 2^32 - 1 carries; it sets *overflow.

__kernel void scan_blocks(__global uint* data, const uint n, __global uint* blockSums,
                          __global uint* overflow, __local uint* block) {
  const uint lid = get_local_id(0);
  const uint L = get_local_size(0);
  const uint base = get_group_id(0) * 2u * L;
  const uint i0 = base + 2u * lid;
  block[2u * lid] = i0 < n ? data[i0] : 0u;
  block[2u * lid + 1u] = i0 + 1u < n ? data[i0 + 1u] : 0u;

  uint offset = 1u;
  for (uint d = L; d > 0u; d >>= 1) {
    barrier(CLK_LOCAL_MEM_FENCE);
    if (lid < d) {
      const uint ai = offset * (2u * lid + 1u) - 1u;
      const uint bi = offset * (2u * lid + 2u) - 1u;
      const uint a = block[ai];
      const uint s = a + block[bi];
      if (s < a) {
        *overflow = 1u;
      }
      block[bi] = s;
    }
    offset <<= 1;
  }
  barrier(CLK_LOCAL_MEM_FENCE);
  if (lid == 0u) {
    blockSums[get_group_id(0)] = block[2u * L - 1u];
    block[2u * L - 1u] = 0u;
  }
  for (uint d = 1u; d < 2u * L; d <<= 1) {
    offset >>= 1;
    barrier(CLK_LOCAL_MEM_FENCE);
    if (lid < d) {
      const uint ai = offset * (2u * lid + 1u) - 1u;
      const uint bi = offset * (2u * lid + 2u) - 1u;
      const uint t = block[ai];
      block[ai] = block[bi];
      block[bi] += t;
    }
  }
  barrier(CLK_LOCAL_MEM_FENCE);
  if (i0 < n) {
    data[i0] = block[2u * lid];
  }
  if (i0 + 1u < n) {
    data[i0 + 1u] = block[2u * lid + 1u];
  }
}

// data[i] += scanned total of the blocks before i's block (blockLength = 2L of scan_blocks).
__kernel void scan_add_block_offsets(__global uint* data, const uint n, __global const uint* blockOffsets,
                                     const uint blockLength) {
  const uint i = get_global_id(0);
  if (i < n) {
    data[i] += blockOffsets[i / blockLength];
  }
}

// The chunked variant, for CPU devices (PoCL): a work-group barrier there costs a pass over every item of
// the group, so Blelloch's 2 log L barriers dominate. Instead each work-item owns `chunkLength`
// consecutive values: scan_chunk_totals sums its chunk, the host scans the totals (recursively), and
// scan_chunks rewrites its chunk as an exclusive scan starting at its scanned total. No barrier at all.
__kernel void scan_chunk_totals(__global const uint* data, const uint n, const uint chunkLength,
                                __global uint* totals, __global uint* overflow) {
  const uint chunk = get_global_id(0);
  const uint begin = chunk * chunkLength;
  if (begin >= n) {
    return;
  }
  const uint end = min(n, begin + chunkLength);
  uint sum = 0u;
  for (uint i = begin; i < end; ++i) {
    const uint next = sum + data[i];
    if (next < sum) {
      *overflow = 1u;
    }
    sum = next;
  }
  totals[chunk] = sum;
}

__kernel void scan_chunks(__global uint* data, const uint n, const uint chunkLength,
                          __global const uint* chunkOffsets) {
  const uint chunk = get_global_id(0);
  const uint begin = chunk * chunkLength;
  if (begin >= n) {
    return;
  }
  const uint end = min(n, begin + chunkLength);
  uint sum = chunkOffsets[chunk];
  for (uint i = begin; i < end; ++i) {
    const uint value = data[i];
    data[i] = sum;
    sum += value;
  }
}
