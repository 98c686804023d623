// Which connections a server keeps when connections pile up: at most max_connections in
// all and max_connections_per_peer from one address (HttpServerOptions), so that a flood of
// idle connections from one stranger can neither use up the descriptors the store needs
// nor shut everyone else out. A full server makes room by closing the connection that has
// waited longest for a request (of that peer, when it is the peer that is full); with
// none waiting, the new one is refused with a 503. This host's own address (127.0.0.1,
// ::1: its local workers, a proxy in front of it) is held to the limit of all only.
#pragma once

#include <utility>  // before Asio: Boost 1.74 with GCC 12 in C++20 needs it

#include <string>

#include <boost/asio/ip/tcp.hpp>

#include "server/http/http_session.hpp"

namespace tessera {

// Whether a new connection from `peer` (an address, no port) may be served, making room
// for it as above. Counts it once start_http_session() has registered it.
bool admit_connection(ServerShared& shared, const std::string& peer);
// Answers a connection admit_connection() refused, without waiting on the peer, and closes
// it.
void refuse_connection(ServerShared& shared, boost::asio::ip::tcp::socket& socket,
                       const std::string& peer);
// A session's end: it no longer counts.
void forget_session(ServerShared& shared, const HttpSession* session);
// An evicted session that began a request before it could be closed: it counts again.
void keep_session(ServerShared& shared, const HttpSession* session);

}  // namespace tessera
