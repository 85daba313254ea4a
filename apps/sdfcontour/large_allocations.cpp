// The program's operator new and delete: large blocks are mapped on their own and asked to be
// backed by transparent huge pages.
//
// Why: the Poisson solve and the brick triangulations allocate, fill and free arrays of tens to
// hundreds of megabytes, stage after stage (freed memory is handed back between stages to keep the
// peak low). With 4 KiB pages every first touch is a page fault: at bunny 256³ they took about a
// third of the reconstruction's CPU time. Where the kernel's huge-page mode is "madvise" (Debian's
// default), only memory that asks gets 2 MiB pages; glibc's malloc asks only when started with
// GLIBC_TUNABLES=glibc.malloc.hugetlb=1. Results do not change: only where the bytes live.
//
// Only the executable replaces these functions, where the replacement is global and every
// allocation and release goes through it. The Python module does not (inside another program,
// code it did not allocate would reach its operator delete). Sanitizer builds keep their own.
#if !defined(__SANITIZE_ADDRESS__) && !defined(__SANITIZE_THREAD__)

#include <sys/mman.h>

#include <cstdint>
#include <cstdlib>
#include <new>

namespace {

constexpr std::size_t kHugePage = std::size_t(2) << 20;
constexpr std::size_t kLargeBlock = std::size_t(4) << 20;  // from here on, a mapping of its own
// Every block starts with this header just before the caller's bytes: malloc's block, or the
// mapping's start and length. 16 bytes keep malloc's 16-byte alignment.
struct alignas(16) Header {
  void* start;
  std::size_t mapped;  // 0: from malloc
};
static_assert(sizeof(Header) == 16);

void* allocate(std::size_t n) {
  if (n < kLargeBlock) {
    auto* h = static_cast<Header*>(std::malloc(sizeof(Header) + (n ? n : 1)));
    if (!h) return nullptr;
    *h = Header{h, 0};
    return h + 1;
  }
  // Bytes aligned to a huge page, the header in the page before them.
  if (n > SIZE_MAX - 2 * kHugePage) return nullptr;
  const std::size_t length = n + 2 * kHugePage;
  void* start = ::mmap(nullptr, length, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  if (start == MAP_FAILED) return nullptr;
  const auto first =
      (reinterpret_cast<std::uintptr_t>(start) + sizeof(Header) + kHugePage - 1) & ~(kHugePage - 1);
  auto* bytes = reinterpret_cast<void*>(first);
  ::madvise(bytes, (n + kHugePage - 1) & ~(kHugePage - 1), MADV_HUGEPAGE);  // a hint only
  reinterpret_cast<Header*>(bytes)[-1] = Header{start, length};
  return bytes;
}

}  // namespace

void* operator new(std::size_t n) {
  for (;;) {
    if (void* p = allocate(n)) return p;
    std::new_handler handler = std::get_new_handler();
    if (!handler) throw std::bad_alloc();
    handler();
  }
}

void operator delete(void* p) noexcept {
  if (!p) return;
  const Header& h = static_cast<Header*>(p)[-1];
  if (h.mapped)
    ::munmap(h.start, h.mapped);
  else
    std::free(h.start);
}

void operator delete(void* p, std::size_t) noexcept {
  operator delete(p);
}

#endif
