// Starting a program over, once, with glibc's malloc backed by transparent huge pages.
//
// Loading a big scene touches hundreds of megabytes that malloc hands out (simdjson's
// buffers, the mesh's arrays, Embree's), one page fault per 4 KiB page. On virtual machines
// such as these a fault costs ten microseconds and more: a 1M-triangle scene took 157,000
// of them, over a second of its three. glibc asks for huge pages, one fault per 2 MiB, when
// started with GLIBC_TUNABLES=glibc.malloc.hugetlb=1 (glibc 2.35 and later), and reads that
// only at start-up, so the program sets it and starts itself again (docs/performance.md).
#pragma once

namespace tessera {

// Replaces the process with a new start of the same program and arguments, with
// glibc.malloc.hugetlb=1 added to GLIBC_TUNABLES. Returns, changing nothing, where the
// variable already names that tunable (the second start, or a user's own choice), where
// TESSERA_NO_HUGE_PAGES is set, or where the program cannot be started again.
void restart_with_huge_page_malloc(char** argv);

}  // namespace tessera
