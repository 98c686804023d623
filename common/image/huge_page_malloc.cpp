#include "common/image/huge_page_malloc.hpp"

#include <cstdlib>
#include <string>
#include <string_view>

#include <unistd.h>

namespace tessera {

void restart_with_huge_page_malloc(char** argv) {
  constexpr std::string_view kName = "glibc.malloc.hugetlb";
  const char* previous = std::getenv("GLIBC_TUNABLES");
  const std::string tunables = previous != nullptr ? previous : "";
  if (tunables.find(kName) != std::string::npos || std::getenv("TESSERA_NO_HUGE_PAGES") != nullptr)
    return;
  const std::string value = (tunables.empty() ? "" : tunables + ":") + std::string(kName) + "=1";
  if (::setenv("GLIBC_TUNABLES", value.c_str(), 1) != 0) return;
  // The very same file, wherever argv[0] points.
  ::execv("/proc/self/exe", argv);
  // Not started again (no /proc, say): go on as before, leaving the environment as it was.
  if (previous != nullptr)
    ::setenv("GLIBC_TUNABLES", tunables.c_str(), 1);
  else
    ::unsetenv("GLIBC_TUNABLES");
}

}  // namespace tessera
