#include "common/large_buffer.hpp"

#include <cstdlib>

#include <sys/mman.h>

namespace tessera {
namespace {

std::size_t whole_huge_pages(std::size_t bytes) {
  return (bytes + kLargeBufferBytes - 1) / kLargeBufferBytes * kLargeBufferBytes;
}

}  // namespace

void* allocate_large(std::size_t bytes) {
  if (bytes < kLargeBufferBytes) return ::operator new(bytes);
  // Aligned to a huge page and a whole number of them, so that every page of the buffer
  // can be a huge one.
  const std::size_t size = whole_huge_pages(bytes);
  void* memory = std::aligned_alloc(kLargeBufferBytes, size);
  if (memory == nullptr) throw std::bad_alloc();
#ifdef MADV_HUGEPAGE
  // Only advice: where the kernel has no huge pages to give (or they are switched off),
  // the buffer gets ordinary pages.
  ::madvise(memory, size, MADV_HUGEPAGE);
#endif
  return memory;
}

void free_large(void* memory, std::size_t bytes) noexcept {
  if (bytes < kLargeBufferBytes)
    ::operator delete(memory);
  else
    std::free(memory);
}

}  // namespace tessera
