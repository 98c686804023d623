// What went wrong in the store, as much as its callers must tell apart: a full disk fails
// the change it was for and says so; a shortage that passes (no descriptor left, a lock
// another process holds) is waited out and the write tried again, failing nothing.
#pragma once

#include <stdexcept>
#include <string>

namespace tessera {

enum class StoreFault {
  other,      // refused: the change's jobs fail, saying why
  disk_full,  // refused, and named "the disk is full"
  transient,  // tried again once it passes: nothing fails for it
};

class StoreError : public std::runtime_error {
 public:
  StoreError(StoreFault fault, const std::string& what) : std::runtime_error(what), fault_(fault) {}
  StoreFault fault() const { return fault_; }

 private:
  StoreFault fault_;
};

// The fault an errno of a failed file operation means.
StoreFault fault_of_errno(int error);
// How an errno reads in the store's errors: "the disk is full (No space left on device)"
// for ENOSPC and EDQUOT, strerror's words otherwise.
std::string errno_words(int error);
// The fault of an exception that reached the store thread: a StoreError's own, `other`
// for anything else.
StoreFault fault_of(const std::exception& error);

}  // namespace tessera
