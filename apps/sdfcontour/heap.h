// Internal to the CLI: the process's heap kept between stages and bricks.
#pragma once

namespace sdfcontour::cli {

/// Keeps freed heap memory in the process for the next stage or brick: blocks up to 32 MB come
/// from the heap rather than from their own mappings, and the heap's top is not handed back.
/// glibc's defaults unmap or trim what a brick or stage frees, and the kernel zeroes those pages
/// again for the next one. Call first thing in main. The library leaves the process's malloc
/// alone; a program that runs many bricks can do the same.
///
/// Measured with the CLI's earlier transparent huge pages (glibc.malloc.hugetlb=1, which it set
/// by running itself again) against small pages, both with this heap, bunny on 2 cores:
/// 1024³ 44.8 -> 37.4 s, 512³ 9.7-11.5 -> 9.3-9.7 s, 256³ 9.4-9.7 -> 9.1-9.3 s, 64³ 0.9x, the
/// regular triangulation and the Poisson path at 256³ 0.95-0.99x. Whole 2 MB pages were zeroed
/// for arrays touched in part; the pages had paid for the triangulations' pointer chasing when
/// those were the default.
void keep_freed_heap();

}  // namespace sdfcontour::cli
