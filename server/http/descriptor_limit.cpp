#include "server/http/descriptor_limit.hpp"

#include <sys/resource.h>

#include <algorithm>
#include <fstream>

namespace tessera {

DescriptorLimit raise_descriptor_limit() {
  rlimit limit{};
  if (::getrlimit(RLIMIT_NOFILE, &limit) != 0) return {};
  DescriptorLimit result{limit.rlim_cur, limit.rlim_cur};
  rlim_t wanted = limit.rlim_max;
  if (wanted == RLIM_INFINITY) {
    // Linux refuses an infinite limit of descriptors: the kernel's own ceiling instead.
    std::uint64_t ceiling = 1 << 20;
    std::ifstream("/proc/sys/fs/nr_open") >> ceiling;
    wanted = ceiling;
  }
  if (wanted > limit.rlim_cur) {
    limit.rlim_cur = wanted;
    if (::setrlimit(RLIMIT_NOFILE, &limit) == 0) result.now = wanted;
  }
  return result;
}

ConnectionCaps connection_caps(std::uint64_t descriptors) {
  const std::uint64_t reserve = std::max<std::uint64_t>(64, descriptors / 8);
  const std::uint64_t total = descriptors > reserve + 16 ? descriptors - reserve : 16;
  return {static_cast<std::size_t>(total),
          static_cast<std::size_t>(std::max<std::uint64_t>(16, total / 4))};
}

}  // namespace tessera
