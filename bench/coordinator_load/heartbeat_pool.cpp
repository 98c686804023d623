#include "bench/coordinator_load/heartbeat_pool.hpp"
#include "common/protocol/paths.hpp"
#include "common/protocol/workers.hpp"

namespace tessera::load {

using error_code = boost::system::error_code;

HeartbeatPool::HeartbeatPool(boost::asio::io_context& io,
                             const boost::asio::ip::tcp::endpoint& server,
                             const std::string& authorization, LoadState& state, int connections)
    : state_(state) {
  for (int i = 0; i < connections; ++i)
    links_.push_back(std::make_unique<Link>(HttpConnection(io, server, authorization)));
}

void HeartbeatPool::send(const std::string& lease_id, const std::string& secret) {
  queue_.emplace_back(lease_id, secret);
  for (auto& link : links_)
    if (!link->busy) return next(*link);
}

void HeartbeatPool::next(Link& link) {
  if (state_.finished || queue_.empty()) {
    link.busy = false;
    return;
  }
  link.busy = true;
  link.target = protocol::fill(protocol::route::lease_heartbeat, queue_.front().first);
  link.headers = "Content-Type: application/json\r\n" + std::string(protocol::kWorkerSecretHeader) +
                 ": " + queue_.front().second + "\r\n";
  queue_.pop_front();
  post(link, false);
}

void HeartbeatPool::post(Link& link, bool retried) {
  if (!link.connected) {
    link.http.connect([this, &link, retried](const error_code& ec) {
      if (state_.finished) return;
      if (ec) return state_.fail("heartbeat connection: " + ec.message());
      link.connected = true;
      post(link, retried);
    });
    return;
  }
  link.http.request("POST", link.target, link.headers, {},
                    [this, &link, retried](const error_code& ec, int status, std::string_view) {
                      if (state_.finished) return;
                      if (ec) {
                        // The coordinator closes a kept-alive connection that idles too long: once
                        // more on a new one.
                        if (retried) return state_.fail("heartbeat: " + ec.message());
                        link.http.close();
                        link.connected = false;
                        return post(link, true);
                      }
                      ++state_.heartbeats;
                      // 410: the lease was lost; its upload will be refused and counted there. A
                      // lease that ended between the heartbeat being queued and sent is lost too,
                      // harmlessly.
                      if (status != 200) ++state_.heartbeats_lost;
                      next(link);
                    });
}

void HeartbeatPool::stop() {
  for (auto& link : links_) link->http.close();
}

}  // namespace tessera::load
