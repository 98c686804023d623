// The cost of opening the image-file module, OpenImageIO's ~260 libraries (dynamic linking
// and their static constructors), on the main thread or on a thread of its own, in a
// process that starts as `tessera render` does (again, with glibc's malloc on huge pages).
// A library loads once per process, so each run is a process: alternate the two and
// compare medians (docs/performance.md).
//
// Usage: tessera_image_load main|thread
// Prints: WHERE MILLISECONDS PAGE_FAULTS
#include <sys/resource.h>

#include <chrono>
#include <cstdio>
#include <string_view>
#include <thread>

#include "common/image/huge_page_malloc.hpp"
#include "common/image/image_file_loader.hpp"

namespace {

long page_faults() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_minflt + usage.ru_majflt;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string_view where = argc == 2 ? argv[1] : "";
  if (where != "main" && where != "thread") {
    std::fprintf(stderr, "usage: %s main|thread\n", argv[0]);
    return 2;
  }
  tessera::restart_with_huge_page_malloc(argv);
  const long faults_before = page_faults();
  const auto start = std::chrono::steady_clock::now();
  if (where == "main") {
    tessera::image_files();
  } else {
    std::thread loading([] { tessera::image_files(); });
    loading.join();
  }
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  std::printf("%s %.1f %ld\n", argv[1], ms, page_faults() - faults_before);
  return 0;
}
