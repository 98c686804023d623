// GET /metrics: the farm in Prometheus's text exposition format (version 0.0.4). Counters
// are totals since the coordinator started; gauges are read at the scrape. Made on the disk
// pool, since the store's sizes are read from the disk.
#include <utility>  // before Asio: Boost 1.74 with GCC 12 in C++20 needs it

#include <filesystem>
#include <string>

#include <boost/asio/ip/address.hpp>

#include "common/protocol/paths.hpp"
#include "server/api/access.hpp"
#include "server/api/api_routes.hpp"
#include "server/metrics/http_metrics.hpp"

namespace tessera {
namespace {

namespace fs = std::filesystem;

// The peer of "ip:port" or "[ipv6]:port" is this machine.
bool loopback_peer(const std::string& remote_address) {
  std::string host = remote_address.substr(0, remote_address.rfind(':'));
  if (host.size() >= 2 && host.front() == '[') host = host.substr(1, host.size() - 2);
  boost::system::error_code ec;
  const auto address = boost::asio::ip::make_address(host, ec);
  if (ec) return false;
  if (address.is_v6() && address.to_v6().is_v4_mapped())
    return boost::asio::ip::make_address_v4(boost::asio::ip::v4_mapped, address.to_v6())
        .is_loopback();
  return address.is_loopback();
}

// The bytes of the regular files under `dir` (none when it does not exist).
std::uint64_t bytes_under(const fs::path& dir) {
  std::uint64_t total = 0;
  std::error_code ec;
  for (fs::recursive_directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    std::error_code size_ec;
    if (it->is_regular_file(size_ec)) {
      const auto size = it->file_size(size_ec);
      if (!size_ec) total += size;
    }
  }
  return total;
}

std::uint64_t file_bytes(const fs::path& file) {
  std::error_code ec;
  const auto size = fs::file_size(file, ec);
  return ec ? 0 : size;
}

void family(std::string& out, const char* name, const char* type, const char* help) {
  out += std::string("# HELP ") + name + " " + help + "\n# TYPE " + name + " " + type + "\n";
}

void sample(std::string& out, const char* name, const std::string& labels, double value) {
  out += name;
  if (!labels.empty()) out += "{" + labels + "}";
  out += " " + metric_number(value) + "\n";
}

std::string exposition(const ApiContext& context) {
  const Scheduler& scheduler = context.scheduler;
  const FarmGauges gauges = scheduler.gauges();
  const FarmCounters& counters = scheduler.counters();
  std::string out;
  family(out, "tessera_jobs", "gauge", "Jobs by state.");
  for (const auto& [state, count] : gauges.jobs)
    sample(out, "tessera_jobs", std::string("state=\"") + to_string(state) + "\"", count);
  family(out, "tessera_pending_tiles", "gauge",
         "Tiles waiting for a worker, by their job's priority (paused jobs' not counted): the "
         "queue depth.");
  for (const auto& [priority, count] : gauges.pending_by_priority)
    sample(out, "tessera_pending_tiles", "priority=\"" + std::to_string(priority) + "\"",
           static_cast<double>(count));
  family(out, "tessera_tiles_rendered_total", "counter", "Tiles whose results were accepted.");
  sample(out, "tessera_tiles_rendered_total", "", static_cast<double>(counters.tiles_rendered));
  family(out, "tessera_tile_render_seconds", "histogram",
         "Each accepted tile's render time on its worker.");
  counters.tile_render_seconds.write(out, "tessera_tile_render_seconds");
  family(out, "tessera_lease_expiries_total", "counter",
         "Leases that ran out without a heartbeat; their tiles went back to the queue.");
  sample(out, "tessera_lease_expiries_total", "", static_cast<double>(counters.lease_expiries));
  family(out, "tessera_tile_retries_total", "counter",
         "Tiles that went out to a worker again after going out before.");
  sample(out, "tessera_tile_retries_total", "", static_cast<double>(counters.tile_retries));
  family(out, "tessera_workers", "gauge",
         "Workers by state; draining ones are also counted under draining.");
  for (const auto& [state, count] : gauges.workers)
    sample(out, "tessera_workers", "state=\"" + label_value(state) + "\"", count);
  family(out, "tessera_rays_total", "counter", "Rays traced for the tiles accepted.");
  sample(out, "tessera_rays_total", "", static_cast<double>(counters.rays));
  if (context.http_metrics) context.http_metrics->write(out);
  const fs::path data = context.data_dir;
  family(out, "tessera_sqlite_bytes", "gauge",
         "The SQLite database with its write-ahead log, and the pixel files beside it.");
  sample(
      out, "tessera_sqlite_bytes", "file=\"database\"",
      static_cast<double>(file_bytes(data / "tessera.db") + file_bytes(data / "tessera.db-wal")));
  sample(out, "tessera_sqlite_bytes", "file=\"pixels\"",
         static_cast<double>(bytes_under(data / "pixels")));
  family(out, "tessera_asset_store_bytes", "gauge", "The asset store's files (meshes, textures).");
  sample(out, "tessera_asset_store_bytes", "", static_cast<double>(bytes_under(data / "assets")));
  return out;
}

}  // namespace

void add_metrics_route(Router& router, ApiContext& context) {
  router.add(
      "GET", std::string(protocol::route::metrics),
      [&context](HttpRequest&& request, Respond respond) {
        if (context.metrics_loopback_only && !loopback_peer(request.remote_address))
          return respond(error_response(
              403, "metrics_refused",
              "/metrics answers this machine only, unless the coordinator has a "
              "--metrics-token, which the scraper then sends as Authorization: Bearer TOKEN"));
        context.run_disk([&context, respond = std::move(respond)] {
          HttpResponse response{
              200, "text/plain; version=0.0.4; charset=utf-8", exposition(context), {}};
          respond(std::move(response));
        });
      },
      RouteOptions{}.with_role(role_metrics));
}

}  // namespace tessera
