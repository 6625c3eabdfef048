// Large tensors without page faults. glibc serves every allocation above 32 MB with a fresh mmap
// and unmaps it on free, so each network forward over a batch of 11k-vertex meshes touches
// hundreds of MB of new pages; in a VM those page faults cost more than the arithmetic (measured
// on the 2-core test machine: the human encoder at 185 ms per frame, 50 ms with blocks reused).
// Keeping glibc from unmapping (mallopt) is no cure: its heap then fragments and grows with every
// batch (7.6 GB after 300 frames). Instead LibTorch gets a CPU allocator that keeps freed large
// blocks and hands them to the next tensor of (nearly) the same size; a run's batches repeat
// their shapes, so after the first batch the network allocates nothing new.
#pragma once

#include <cstddef>
#include <cstdint>

namespace retarget {

// Installs the caching allocator as LibTorch's CPU allocator for the rest of the process (once;
// later calls only change the cap). Blocks of at least 1 MB are cached when freed, up to
// max_cached_bytes of idle blocks (beyond that they go back to the system); smaller tensors use
// LibTorch's default allocator. Tensors that exist already keep their own deleters.
void reuse_tensor_memory(size_t max_cached_bytes = size_t{4} << 30);

// Idle bytes the caching allocator holds (0 before reuse_tensor_memory), for tests and logs.
size_t cached_tensor_bytes();

}  // namespace retarget
