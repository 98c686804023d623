#include "server/http/connection_admission.hpp"

#include <memory>

#include <spdlog/spdlog.h>

namespace tessera {
namespace {

// The session that has waited longest for a request, of `peer` when given; null when none
// waits. Under shared.mutex.
std::shared_ptr<HttpSession> oldest_waiting(ServerShared& shared, const std::string* peer) {
  ServerShared::OpenSession* oldest = nullptr;
  std::int64_t oldest_since = 0;
  for (auto& [raw, entry] : shared.sessions) {
    if (entry.evicted || (peer && entry.peer != *peer)) continue;
    const std::int64_t since = raw->waiting_since_us.load();
    if (since == 0 || (oldest && since >= oldest_since)) continue;
    oldest = &entry;
    oldest_since = since;
  }
  if (!oldest) return nullptr;
  std::shared_ptr<HttpSession> session = oldest->session.lock();
  if (!session) return nullptr;  // closing already
  oldest->evicted = true;
  --shared.open_by_peer[oldest->peer];
  --shared.open_counted;
  return session;
}

// This host's own programs, which reach it on the loopback address: its local workers, and
// a proxy in front of it, behind which every client has this address. Only the limit of
// all connections holds for them (a proxy caps its own clients).
bool is_this_host(const std::string& peer) { return peer == "127.0.0.1" || peer == "::1"; }

}  // namespace

bool admit_connection(ServerShared& shared, const std::string& peer) {
  const HttpServerOptions& options = shared.options;
  std::shared_ptr<HttpSession> room;
  {
    std::lock_guard lock(shared.mutex);
    const auto found = shared.open_by_peer.find(peer);
    const std::size_t from_peer = found == shared.open_by_peer.end() ? 0 : found->second;
    const bool peer_full = options.max_connections_per_peer > 0 && !is_this_host(peer) &&
                           from_peer >= options.max_connections_per_peer;
    const bool server_full =
        options.max_connections > 0 && shared.open_counted >= options.max_connections;
    if (!peer_full && !server_full) return true;
    // A peer at its own limit makes room among its own connections only.
    room = oldest_waiting(shared, peer_full ? &peer : nullptr);
    if (!room) return false;
  }
  // Outside the lock: dropping the last reference runs the session's destructor, which
  // takes it.
  room->evict();
  return true;
}

void refuse_connection(ServerShared& shared, boost::asio::ip::tcp::socket& socket,
                       const std::string& peer) {
  static const std::string answer = [] {
    const std::string body =
        R"({"error":{"code":"too_many_connections","message":"the coordinator has as many )"
        R"(connections as it takes, from this address or in all; try again shortly"}})";
    return "HTTP/1.1 503 Service Unavailable\r\nContent-Type: application/json\r\n"
           "Retry-After: 1\r\nConnection: close\r\nContent-Length: " +
           std::to_string(body.size()) + "\r\n\r\n" + body;
  }();
  boost::system::error_code ec;
  // Best effort, never waiting: a fresh connection's send buffer takes a few hundred bytes.
  // A TLS client could not read it; it only sees the connection close.
  if (!shared.tls_context()) {
    socket.non_blocking(true, ec);
    if (!ec) socket.write_some(boost::asio::buffer(answer), ec);
  }
  socket.shutdown(boost::asio::ip::tcp::socket::shutdown_both, ec);
  socket.close(ec);
  spdlog::debug("http: refused a connection from {}: too many connections", peer);
}

void forget_session(ServerShared& shared, const HttpSession* session) {
  std::lock_guard lock(shared.mutex);
  const auto it = shared.sessions.find(session);
  if (it == shared.sessions.end()) return;
  if (!it->second.evicted) {
    const auto peer = shared.open_by_peer.find(it->second.peer);
    if (peer != shared.open_by_peer.end() && --peer->second == 0) shared.open_by_peer.erase(peer);
    --shared.open_counted;
  }
  shared.sessions.erase(it);
}

void keep_session(ServerShared& shared, const HttpSession* session) {
  std::lock_guard lock(shared.mutex);
  const auto it = shared.sessions.find(session);
  if (it == shared.sessions.end() || !it->second.evicted) return;
  it->second.evicted = false;
  ++shared.open_by_peer[it->second.peer];
  ++shared.open_counted;
}

}  // namespace tessera
