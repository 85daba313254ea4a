// Internal to the CLI: the process's heap on transparent huge pages, and kept between stages.
#pragma once

namespace sdfcontour::cli {

/// Runs the program again with glibc's malloc asking for transparent huge pages
/// (GLIBC_TUNABLES=glibc.malloc.hugetlb=1), unless the environment already says what it wants
/// there. Returns only if it does not re-run (already set, or the exec failed): then the program
/// goes on with ordinary pages. Call first thing in main, before any output.
///
/// Why: Debian's kernels give huge pages only to memory that asks (THP mode "madvise"), and glibc
/// asks only with that tunable, which it reads at start-up. The triangulations chase pointers
/// through hundreds of MB (TLB misses) and the Poisson stages fill and free arrays as large (page
/// faults): bunny 256³ 18.1-18.4 s -> 16.5-16.8 s, bunny 512³ ~40% less. Results do not change.
void rerun_with_huge_pages(char** argv);

/// Keeps freed heap memory in the process for the next stage or brick: blocks up to 32 MB come
/// from the heap rather than from their own mappings, and the heap's top is not handed back.
/// glibc's defaults unmap or trim what a brick frees, and the kernel zeroes those pages again for
/// the next brick (bunny 1024³: 8.2 s of system time; 512³ 1.5 s of 17 s of CPU time). The peak
/// stays about where it was (1024³: 0.98 -> 1.09 GB). The library leaves the process's malloc
/// alone; a program that runs many bricks can do the same.
void keep_freed_heap();

}  // namespace sdfcontour::cli
