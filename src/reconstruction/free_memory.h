// Internal: handing freed heap memory back to the system between stages (the Poisson solver's
// depths, a brick's triangulated contact points).
#pragma once

#include <malloc.h>

namespace sdfcontour::detail {

/// glibc keeps freed blocks below its mmap threshold (which earlier large frees raise to 32 MB)
/// in its arenas, one per thread: after a Poisson depth releases its splats, or a brick its
/// stages, that is hundreds of MB of resident memory that the next allocations are made on top of
/// (bunny 1024³: the second brick of 512 started 0.7 GB above its block, band and first piece).
/// Bricks of one size one after another reuse it instead (local_mesh_in_bricks.cpp).
inline void return_free_memory() {
  malloc_trim(0);
}

}  // namespace sdfcontour::detail
