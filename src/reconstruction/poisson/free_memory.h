// Internal: handing freed heap memory back to the system between the solver's stages.
#pragma once

#include <malloc.h>

namespace sdfcontour::poisson {

/// glibc keeps freed blocks below its mmap threshold (which earlier large frees raise to 32 MB)
/// in its arenas; after a depth releases its splats and builds its rows, that is a few hundred MB
/// of resident memory the solve's vectors would be allocated on top of.
inline void return_free_memory() {
  malloc_trim(0);
}

}  // namespace sdfcontour::poisson
