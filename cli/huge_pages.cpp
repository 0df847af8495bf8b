// huge_pages.cpp — the global operator new of the vdb_shell program (and of the benchmarks,
// which measure what it does): blocks of 2 MiB or more are aligned to 2 MiB and advised to the
// kernel as transparent huge pages (madvise MADV_HUGEPAGE).
//
// Why: the shell's large arrays (tet geometry, cell lists, traces: tens to hundreds of MiB) are
// freshly mapped by malloc each time and first touched page by page. With 4 KiB pages every
// 4 KiB costs a page fault, and on a virtual machine a fault costs microseconds: the full check
// of a 280,000-tet shell spent 0.45 s of its 1.5 s faulting in two copies of its tet geometry.
// With 2 MiB pages the same memory takes 512 times fewer faults. Debian's kernels give
// transparent huge pages only to advised memory ("madvise" mode) by default.
//
// Deletion stays the standard library's (free()), which takes blocks of malloc() and
// posix_memalign() alike. Not built into sanitizer builds, whose runtime replaces operator new.
// Programs that link the library get a similar effect from the environment:
// GLIBC_TUNABLES=glibc.malloc.hugetlb=1.
#include <malloc.h>
#include <sys/mman.h>

#include <cstddef>
#include <cstdlib>
#include <new>

namespace {

constexpr std::size_t kHugePage = std::size_t{2} << 20;

// A block of `size` bytes; from kHugePage up, aligned to a huge page and advised (its last,
// partial huge page stays in small pages: no memory is added).
void* allocate(std::size_t size) {
  if (size < kHugePage) return std::malloc(size);
  void* p = nullptr;
  if (posix_memalign(&p, kHugePage, size) != 0) return nullptr;
  // Advice only: a kernel without transparent huge pages refuses it, and nothing changes.
  madvise(p, size & ~(kHugePage - 1), MADV_HUGEPAGE);
  return p;
}

// malloc() maps blocks from kHugePage up afresh (and unmaps them when freed) instead of raising
// that threshold as blocks are freed (up to 32 MiB) and then cutting them from its heap: the
// advice above then only ever falls on fresh mappings, which take huge pages as they are first
// touched, never on heap pages already touched in small ones, which the kernel's khugepaged
// would copy into huge pages, taking CPU time from the program.
[[maybe_unused]] const int kMmapThreshold = mallopt(M_MMAP_THRESHOLD, kHugePage);

}  // namespace

void* operator new(std::size_t size) {
  if (size == 0) size = 1;
  for (;;) {
    if (void* p = allocate(size)) return p;
    const std::new_handler handler = std::get_new_handler();
    if (!handler) throw std::bad_alloc();
    handler();
  }
}
