// Server-sent events under load: SUBSCRIBERS clients follow one job of TILES tiles
// (GET /v1/jobs/{id}/events) while a simulated worker delivers its tiles at a steady pace.
// Prints the coordinator's CPU time and memory, and the delay from the start of each
// upload to each subscriber's reading of the tile's "done" event (p50, p99), as one line
// of `key=value` pairs for bench/run.
//
// Usage: tessera_event_fanout SERVER_BINARY DATA_DIR [SUBSCRIBERS [TILES [TILES_PER_S]]]
#include <fcntl.h>
#include <netinet/in.h>
#include <sys/epoll.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "bench/coordinator_load/server_process.hpp"
#include "common/net/coordinator_client.hpp"

namespace {

using namespace tessera;
using Clock = std::chrono::steady_clock;

// A scene cheap to check: one sphere, one light, TILES tiles of 10x10 pixels.
nlohmann::json scene_of(int tiles) {
  const int side = static_cast<int>(std::lround(std::sqrt(tiles))) * 10;
  return {
      {"version", 1},
      {"image", {{"width", side}, {"height", side}}},
      {"camera", {{"eye", {0, 0, 5}}, {"look_at", {0, 0, 0}}, {"up", {0, 1, 0}}, {"fov_y", 40}}},
      {"render", {{"tile_size", 10}, {"samples_per_pixel", 1}}},
      {"materials", {{"red", {{"diffuse", {0.8, 0.1, 0.1}}}}}},
      {"lights", {{{"type", "point"}, {"position", {5, 5, 5}}, {"intensity", {1, 1, 1}}}}},
      {"objects",
       {{{"type", "sphere"}, {"center", {0, 0, 0}}, {"radius", 1}, {"material", "red"}}}}};
}

struct Subscriber {
  int fd = -1;
  std::string in;
  int done = 0;
  bool open = true;
  bool subscribed = false;  // its stream's opening comment arrived
};

int connect_to(std::uint16_t port) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(port);
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (fd < 0 || ::connect(fd, reinterpret_cast<sockaddr*>(&address), sizeof address) != 0)
    throw std::runtime_error(std::string("connect: ") + std::strerror(errno));
  return fd;
}

double percentile(std::vector<float>& values, double p) {
  if (values.empty()) return 0;
  const auto at = static_cast<std::size_t>(p * static_cast<double>(values.size() - 1));
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(at), values.end());
  return values[at];
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr,
                 "usage: tessera_event_fanout SERVER_BINARY DATA_DIR [SUBSCRIBERS [TILES "
                 "[TILES_PER_S]]]\n");
    return 2;
  }
  const int subscribers = argc > 3 ? std::stoi(argv[3]) : 1000;
  const int tiles = argc > 4 ? std::stoi(argv[4]) : 10000;
  const double tiles_per_s = argc > 5 ? std::stod(argv[5]) : 1000;
  // A socket per subscriber on both sides: the soft limit of 1,024 files is too few.
  rlimit files{};
  ::getrlimit(RLIMIT_NOFILE, &files);
  files.rlim_cur = files.rlim_max;
  ::setrlimit(RLIMIT_NOFILE, &files);

  load::ServerProcess server(argv[1], argv[2], {"--log-level", "warn"});
  const std::string url = "http://127.0.0.1:" + std::to_string(server.port());
  CoordinatorClient api(url, "", std::chrono::seconds(60));
  const protocol::JobStatus job = api.submit({"fanout", 50, scene_of(tiles), std::nullopt});
  const int total = job.tiles.total;
  const std::int64_t rss_before = load::process_status_kib(server.pid(), "VmRSS");

  std::vector<Subscriber> subs(static_cast<std::size_t>(subscribers));
  const int poller = ::epoll_create1(0);
  const std::string request =
      "GET /v1/jobs/" + job.id + "/events HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n";
  for (std::size_t i = 0; i < subs.size(); ++i) {
    subs[i].fd = connect_to(server.port());
    if (::send(subs[i].fd, request.data(), request.size(), MSG_NOSIGNAL) < 0)
      throw std::runtime_error("send failed");
    ::fcntl(subs[i].fd, F_SETFL, ::fcntl(subs[i].fd, F_GETFL) | O_NONBLOCK);
    epoll_event interest{};
    interest.events = EPOLLIN;
    interest.data.u64 = i;
    ::epoll_ctl(poller, EPOLL_CTL_ADD, subs[i].fd, &interest);
  }
  // Each tile's upload start, in ns since `origin`; read by the subscribers' thread.
  const Clock::time_point origin = Clock::now();
  std::vector<std::atomic<std::int64_t>> sent(static_cast<std::size_t>(total));
  for (auto& t : sent) t.store(-1);
  std::vector<float> delays_ms;
  delays_ms.reserve(static_cast<std::size_t>(subscribers) * static_cast<std::size_t>(total));
  std::atomic<bool> reading{true};
  int resyncs = 0;
  int complete = 0;
  std::atomic<int> subscribed{0};

  std::thread reader([&] {
    std::vector<epoll_event> ready(256);
    char chunk[65536];
    while (reading.load() && complete < subscribers) {
      const int n = ::epoll_wait(poller, ready.data(), static_cast<int>(ready.size()), 200);
      const std::int64_t now_ns =
          std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now() - origin).count();
      for (int k = 0; k < n; ++k) {
        Subscriber& sub = subs[ready[static_cast<std::size_t>(k)].data.u64];
        while (true) {
          const ssize_t got = ::recv(sub.fd, chunk, sizeof chunk, 0);
          if (got <= 0) {
            if (got == 0) sub.open = false;
            break;
          }
          sub.in.append(chunk, static_cast<std::size_t>(got));
        }
        std::size_t at = 0;
        for (std::size_t end; (end = sub.in.find("\n\n", at)) != std::string::npos; at = end + 2) {
          const std::string_view block(sub.in.data() + at, end - at);
          if (!sub.subscribed && block.find(": open") != std::string_view::npos) {
            sub.subscribed = true;
            ++subscribed;
          }
          if (block.find("event: resync") != std::string_view::npos) ++resyncs;
          if (block.find("event: tile") == std::string_view::npos ||
              block.find("\"state\":\"done\"") == std::string_view::npos)
            continue;
          const std::size_t index_at = block.find("\"index\":");
          const int index = std::atoi(block.data() + index_at + 8);
          const std::int64_t start = sent[static_cast<std::size_t>(index)].load();
          if (start >= 0) delays_ms.push_back(static_cast<float>((now_ns - start) / 1e6));
          if (++sub.done == total) ++complete;
        }
        sub.in.erase(0, at);
      }
    }
  });

  // Every stream open before the first tile goes.
  const Clock::time_point open_by = Clock::now() + std::chrono::seconds(60);
  while (subscribed.load() < subscribers && Clock::now() < open_by)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  // The worker: claims batches and uploads them at TILES_PER_S.
  const protocol::Registration registration = api.register_worker({"fanout", "bench", 1});
  api.prove_as(registration.secret);
  const double cpu_before = load::process_cpu_seconds(server.pid());
  const Clock::time_point started = Clock::now();
  int delivered = 0;
  while (delivered < total) {
    const auto lease = api.claim(registration.id, 0, 10);
    if (!lease) continue;
    std::vector<std::uint64_t> indexes, rays;
    std::string pixels;
    for (const protocol::LeaseTile& tile : lease->tiles) {
      indexes.push_back(static_cast<std::uint64_t>(tile.index));
      rays.push_back(100);
      pixels.append(static_cast<std::size_t>(tile.width * tile.height * 3 * 4), '\0');
    }
    const Clock::time_point due =
        started +
        std::chrono::nanoseconds(static_cast<std::int64_t>(delivered / tiles_per_s * 1e9));
    std::this_thread::sleep_until(due);
    const std::int64_t now_ns =
        std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now() - origin).count();
    for (const std::uint64_t index : indexes) sent[index].store(now_ns);
    api.upload(lease->id, indexes, rays, std::move(pixels));
    delivered += static_cast<int>(indexes.size());
  }
  const double upload_s = std::chrono::duration<double>(Clock::now() - started).count();
  // Every subscriber has every tile, or 30 s more have passed.
  const Clock::time_point give_up = Clock::now() + std::chrono::seconds(30);
  while (complete < subscribers && Clock::now() < give_up)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  reading = false;
  reader.join();
  const double cpu = load::process_cpu_seconds(server.pid()) - cpu_before;
  const std::int64_t rss_peak = load::process_status_kib(server.pid(), "VmHWM");
  const std::int64_t rss_after = load::process_status_kib(server.pid(), "VmRSS");
  for (Subscriber& sub : subs) ::close(sub.fd);
  ::close(poller);
  const std::size_t received = delays_ms.size();
  std::printf(
      "subscribers=%d tiles=%d tiles_per_s=%.0f upload_s=%.2f events=%zu complete=%d "
      "resyncs=%d p50_ms=%.2f p99_ms=%.2f server_cpu_s=%.2f server_cpu_pct=%.1f "
      "rss_before_mib=%.1f rss_peak_mib=%.1f rss_after_mib=%.1f\n",
      subscribers, total, tiles_per_s, upload_s, received, complete, resyncs,
      percentile(delays_ms, 0.5), percentile(delays_ms, 0.99), cpu, 100 * cpu / upload_s,
      rss_before / 1024.0, rss_peak / 1024.0, rss_after / 1024.0);
  return complete == subscribers ? 0 : 1;
}
