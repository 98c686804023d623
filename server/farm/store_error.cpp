#include "server/farm/store_error.hpp"

#include <cerrno>
#include <cstring>

namespace tessera {

StoreFault fault_of_errno(int error) {
  switch (error) {
    case ENOSPC:
    case EDQUOT:
      return StoreFault::disk_full;
    // Descriptors run out while connections pile up, and come back as they close; memory
    // and interrupted calls likewise pass. None of them says anything about the data.
    case EMFILE:
    case ENFILE:
    case ENOMEM:
    case EAGAIN:
    case EINTR:
      return StoreFault::transient;
    default:
      return StoreFault::other;
  }
}

std::string errno_words(int error) {
  const std::string words = std::strerror(error);
  if (fault_of_errno(error) == StoreFault::disk_full) return "the disk is full (" + words + ")";
  return words;
}

StoreFault fault_of(const std::exception& error) {
  const auto* store_error = dynamic_cast<const StoreError*>(&error);
  return store_error ? store_error->fault() : StoreFault::other;
}

}  // namespace tessera
