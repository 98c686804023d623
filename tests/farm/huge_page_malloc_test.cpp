// The worker and `tessera render` start themselves over with glibc's malloc on transparent
// huge pages (common/image/huge_page_malloc.hpp): checked on the real programs' environments.
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <optional>
#include <string>

#include <gtest/gtest.h>

#include "tests/farm/process.hpp"

namespace tessera {
namespace {

using namespace std::chrono_literals;

// GLIBC_TUNABLES in the environment the process runs with now, if it has one.
std::optional<std::string> tunables_of(pid_t pid) {
  std::ifstream environ("/proc/" + std::to_string(pid) + "/environ", std::ios::binary);
  const std::string all{std::istreambuf_iterator<char>(environ), {}};
  const std::string name = "GLIBC_TUNABLES=";
  for (std::size_t at = 0; at < all.size(); at = all.find('\0', at) + 1) {
    if (all.compare(at, name.size(), name) == 0)
      return all.substr(at + name.size(), all.find('\0', at) - at - name.size());
    if (all.find('\0', at) == std::string::npos) break;
  }
  return std::nullopt;
}

// A worker that keeps trying an address where nothing listens, until it is killed.
std::optional<std::string> tunables_of_a_worker() {
  const auto log = std::filesystem::temp_directory_path() /
                   ("tessera-huge-pages-" + std::to_string(::getpid()) + ".log");
  test::Process worker(TESSERA_WORKER_BIN, {"--server", "http://127.0.0.1:1", "--threads", "1"},
                       log);
  // Its first start sets the variable and replaces itself: wait for the second to log.
  EXPECT_TRUE(test::eventually(
      [&] {
        std::error_code missing;
        const auto size = std::filesystem::file_size(log, missing);
        return !missing && size > 0;
      },
      10s));
  auto tunables = tunables_of(worker.pid());
  std::filesystem::remove(log);
  return tunables;
}

TEST(HugePageMallocTest, TheWorkerRunsWithMallocOnHugePages) {
  // (A user's other tunables are kept before it, but glibc cuts the variable short in place
  // as it parses it, so /proc shows only the first of several.)
  ::unsetenv("GLIBC_TUNABLES");
  EXPECT_EQ(tunables_of_a_worker(), "glibc.malloc.hugetlb=1");
}

TEST(HugePageMallocTest, AUsersOwnChoiceOrTesseraNoHugePagesIsLeftAlone) {
  ::setenv("GLIBC_TUNABLES", "glibc.malloc.hugetlb=0", 1);
  EXPECT_EQ(tunables_of_a_worker(), "glibc.malloc.hugetlb=0");
  ::unsetenv("GLIBC_TUNABLES");
  ::setenv("TESSERA_NO_HUGE_PAGES", "1", 1);
  EXPECT_EQ(tunables_of_a_worker(), std::nullopt);
  ::unsetenv("TESSERA_NO_HUGE_PAGES");
}

}  // namespace
}  // namespace tessera
