// Load, bounded: hundreds of clients poll job statuses over kept-alive connections while a
// few submit jobs, for a fixed time against a real coordinator on loopback. No request may
// fail, the coordinator's memory must stay flat after a warm-up, and the p99 latency of
// GET /v1/jobs/{id} is printed. It runs alone (RUN_SERIAL): it takes the whole machine.
#include <algorithm>
#include <atomic>
#include <cstdio>
#include <fstream>
#include <mutex>
#include <thread>

#include <gtest/gtest.h>

#include "tests/farm/farm_fixture.hpp"

namespace tessera {
namespace {

using namespace std::chrono_literals;
using nlohmann::json;
using test::Farm;
using Clock = std::chrono::steady_clock;

// Resident memory of a process in KiB, from /proc.
long resident_kib(pid_t pid) {
  std::ifstream status("/proc/" + std::to_string(pid) + "/status");
  std::string line;
  while (std::getline(status, line))
    if (line.rfind("VmRSS:", 0) == 0) return std::stol(line.substr(6));
  return -1;
}

TEST(FarmLoadTest, HundredsOfPollersAndSubmittersWithoutAnErrorAndWithFlatMemory) {
  Farm farm("load", 0);
  const json scene = test::showcase(16, 16, 1, 16);
  std::vector<std::string> ids;
  for (int i = 0; i < 20; ++i)
    ids.push_back(farm.api().submit("seed-" + std::to_string(i), 50, scene)["id"]);

  constexpr int pollers = 300;
  constexpr int submitters = 4;
  std::atomic<bool> measuring{false};
  std::atomic<bool> stop{false};
  std::atomic<long> errors{0};
  std::atomic<long> polls{0};
  std::atomic<long> submissions{0};
  std::mutex samples_mutex;
  std::vector<double> latencies_ms;  // measured polls only
  std::vector<std::thread> clients;
  for (int c = 0; c < pollers; ++c) {
    clients.emplace_back([&, c] {
      HttpClient http = farm.http(30s);
      std::vector<double> mine;
      for (std::size_t i = static_cast<std::size_t>(c); !stop; ++i) {
        const auto start = Clock::now();
        try {
          if (http.request("GET", "/v1/jobs/" + ids[i % ids.size()]).status != 200) ++errors;
        } catch (const HttpError&) {
          ++errors;
          http = farm.http(30s);
        }
        if (measuring) {
          mine.push_back(std::chrono::duration<double, std::milli>(Clock::now() - start).count());
          ++polls;
        }
      }
      std::lock_guard lock(samples_mutex);
      latencies_ms.insert(latencies_ms.end(), mine.begin(), mine.end());
    });
  }
  for (int c = 0; c < submitters; ++c) {
    clients.emplace_back([&, c] {
      test::JsonApi api(farm.url());
      for (int i = 0; !stop; ++i) {
        try {
          api.submit("load-" + std::to_string(c) + "-" + std::to_string(i), 50, scene);
          if (measuring) ++submissions;
        } catch (const std::exception&) {
          ++errors;
        }
      }
    });
  }

  std::this_thread::sleep_for(3s);  // warm-up: connections, allocator pools, SQLite cache
  const long warm_kib = resident_kib(farm.server().pid());
  measuring = true;
  const auto measured_from = Clock::now();
  long peak_kib = warm_kib;
  while (Clock::now() - measured_from < 10s) {
    std::this_thread::sleep_for(500ms);
    peak_kib = std::max(peak_kib, resident_kib(farm.server().pid()));
  }
  measuring = false;
  const double seconds = std::chrono::duration<double>(Clock::now() - measured_from).count();
  stop = true;
  for (std::thread& client : clients) client.join();

  ASSERT_FALSE(latencies_ms.empty());
  std::sort(latencies_ms.begin(), latencies_ms.end());
  const auto percentile = [&](double p) {
    return latencies_ms[std::min(latencies_ms.size() - 1,
                                 static_cast<std::size_t>(p * latencies_ms.size()))];
  };
  std::printf(
      "load: %d pollers and %d submitters for %.1f s: %ld status polls (%.0f/s), %ld jobs "
      "submitted "
      "(%.0f/s), %ld errors; GET /v1/jobs/{id} latency p50 %.2f ms, p99 %.2f ms, max %.2f ms; "
      "coordinator memory %ld KiB after warm-up, peak %ld KiB\n",
      pollers, submitters, seconds, polls.load(), polls / seconds, submissions.load(),
      submissions / seconds, errors.load(), percentile(0.50), percentile(0.99), latencies_ms.back(),
      warm_kib, peak_kib);
  RecordProperty("p99_ms", std::to_string(percentile(0.99)));
  EXPECT_EQ(errors.load(), 0);
  EXPECT_GT(submissions.load(), 0);
  // Flat: the jobs submitted meanwhile are kept in memory, a few KiB each; nothing else grows.
#if defined(__SANITIZE_ADDRESS__)
  // AddressSanitizer holds freed memory in quarantine (up to 256 MiB), so resident memory
  // says nothing here; LeakSanitizer checks for leaks when the coordinator exits instead.
  std::printf("load: memory growth not checked under AddressSanitizer\n");
#else
  EXPECT_LT(peak_kib - warm_kib, 32 * 1024 + submissions.load() * 8)
      << "the coordinator grew from " << warm_kib << " KiB to " << peak_kib << " KiB";
#endif
  // And it still answers at once.
  HttpClient http = farm.http(10s);
  EXPECT_EQ(http.request("GET", "/healthz").status, 200);
}

}  // namespace
}  // namespace tessera
