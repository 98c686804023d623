// Lease heartbeats for every simulated worker, over a few shared connections. A real
// worker keeps its lease alive from a connection of its own every heartbeat_interval_s
// while it renders; here a lease may wait as long for its upload to be served, since a
// thousand workers queue at one coordinator, so it needs heartbeats just the same.
#pragma once

#include <cstdint>
#include <deque>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "bench/coordinator_load/http_connection.hpp"
#include "bench/coordinator_load/simulated_worker.hpp"

namespace tessera::load {

class HeartbeatPool {
 public:
  HeartbeatPool(boost::asio::io_context& io, const boost::asio::ip::tcp::endpoint& server,
                const std::string& authorization, LoadState& state, int connections);
  // Queues POST /v1/leases/{lease_id}/heartbeat, proven by the holder's `secret`.
  void send(const std::string& lease_id, const std::string& secret);
  void stop();

 private:
  struct Link {
    explicit Link(HttpConnection connection) : http(std::move(connection)) {}
    HttpConnection http;
    bool busy = false;
    bool connected = false;  // lazily: the coordinator closes a connection idle from its start
    std::string target;
    std::string headers;  // the request's, kept until it is answered
  };
  void next(Link& link);
  void post(Link& link, bool retried);

  LoadState& state_;
  std::vector<std::unique_ptr<Link>> links_;
  std::deque<std::pair<std::string, std::string>> queue_;  // lease ids and secrets
};

}  // namespace tessera::load
