#include "server/api/memory_give_back.hpp"

#include <malloc.h>

#include <algorithm>

namespace tessera {

bool MemoryGiveBack::note(std::size_t in_use) {
  peak_ = std::max(peak_, in_use);
  if (peak_ >= threshold && in_use * 2 < peak_) {
    peak_ = in_use;
    // Connections that have just closed still free what they held (their queues, their
    // buffers) for a moment after: given back again at the next few calls.
    again_ = 3;
  } else if (again_ == 0) {
    return false;
  } else {
    --again_;
  }
  // A few milliseconds on the timer's thread, a few times per flood that has passed.
  ::malloc_trim(0);
  return true;
}

}  // namespace tessera
