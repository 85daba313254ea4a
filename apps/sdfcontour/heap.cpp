#include "heap.h"

#include <malloc.h>

#include <climits>

namespace sdfcontour::cli {

void keep_freed_heap() {
  // (32 MB is the most glibc takes for the threshold. Setting either value also stops glibc
  // from adjusting both as blocks are freed.)
  mallopt(M_MMAP_THRESHOLD, 32 << 20);
  mallopt(M_TRIM_THRESHOLD, INT_MAX);
}

}  // namespace sdfcontour::cli
