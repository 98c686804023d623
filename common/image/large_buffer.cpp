#include "common/image/large_buffer.hpp"

#include <cstdint>

#include <sys/mman.h>

namespace tessera {

void* allocate_large(std::size_t bytes) {
  // From malloc, as any buffer: freed and asked for again, as images are frame after frame,
  // it comes back from malloc's heap already in memory, where memory of its own would be
  // mapped and faulted in afresh each time.
  void* memory = ::operator new(bytes);
#ifdef MADV_HUGEPAGE
  if (bytes >= kLargeBufferBytes) {
    // The whole huge pages inside the buffer. Only advice: where the kernel has none to give
    // (or they are switched off), the buffer keeps ordinary pages.
    const auto begin = reinterpret_cast<std::uintptr_t>(memory);
    const std::uintptr_t first = (begin + kLargeBufferBytes - 1) & ~(kLargeBufferBytes - 1);
    const std::uintptr_t last = (begin + bytes) & ~(kLargeBufferBytes - 1);
    if (first < last) ::madvise(reinterpret_cast<void*>(first), last - first, MADV_HUGEPAGE);
  }
#endif
  return memory;
}

}  // namespace tessera
