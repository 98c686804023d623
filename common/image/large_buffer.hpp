// Buffers the size of a whole image (megabytes), such as its pixels and their encoded
// codes. Each is backed by transparent huge pages where the kernel offers them, so that
// touching it for the first time costs one page fault per 2 MiB instead of one per 4 KiB:
// on a virtual machine a fault can cost ten microseconds and more, and a 1920x1080 float
// image is six thousand of them (docs/performance.md).
#pragma once

#include <cstddef>
#include <new>
#include <utility>
#include <vector>

namespace tessera {

// At least `bytes` of memory aligned for any type, from operator new; from
// kLargeBufferBytes up, the whole huge pages inside it are advised MADV_HUGEPAGE. Throws
// std::bad_alloc.
void* allocate_large(std::size_t bytes);

// The size from which a buffer asks for huge pages: one huge page.
inline constexpr std::size_t kLargeBufferBytes = std::size_t{2} << 20;

// An allocator for such buffers. Elements constructed without arguments are
// default-initialised, which leaves numbers as they are: a buffer whose every element is
// about to be written is not zeroed first.
template <typename T>
struct LargeBufferAllocator {
  using value_type = T;

  LargeBufferAllocator() = default;
  template <typename U>
  LargeBufferAllocator(const LargeBufferAllocator<U>&) noexcept {}

  T* allocate(std::size_t n) {
    if (n > static_cast<std::size_t>(-1) / sizeof(T)) throw std::bad_array_new_length();
    return static_cast<T*>(allocate_large(n * sizeof(T)));
  }
  void deallocate(T* memory, std::size_t) noexcept { ::operator delete(memory); }

  template <typename U>
  void construct(U* p) noexcept {
    ::new (static_cast<void*>(p)) U;
  }
  template <typename U, typename... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }

  template <typename U>
  bool operator==(const LargeBufferAllocator<U>&) const noexcept {
    return true;
  }
};

template <typename T>
using LargeBuffer = std::vector<T, LargeBufferAllocator<T>>;

}  // namespace tessera
