// mimalloc's options for every program linked with it (CMake's rdmesh_link_malloc adds this file).
//
// Large OS pages: mimalloc asks the kernel for transparent huge pages (madvise) on its segments,
// so that fresh memory arrives 2 MiB per page fault instead of 4 KiB. Page faults are most of the
// cost of touching fresh memory, and on a virtual machine each costs microseconds: with them,
// `rdmesh mesh` on a 17-face KiCad part 60 -> 55 ms, voron_bowden_module at 1e-4 load 0.56 ->
// 0.43 s (docs/TUNING.md, "The allocator"). MIMALLOC_LARGE_OS_PAGES in the environment still
// decides when it is set.

#include <mimalloc.h>

#include <cstdlib>

namespace {

// Runs before the program's own static initialisers; the libraries' ran before and allocated
// little.
__attribute__((constructor(101))) void SetMallocOptions() {
  if (std::getenv("MIMALLOC_LARGE_OS_PAGES") == nullptr) mi_option_set(mi_option_large_os_pages, 1);
}

}  // namespace
