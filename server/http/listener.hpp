// Accepts connections and starts a session for each, until stopped.
#pragma once

#include <utility>  // before Asio: Boost 1.74 with GCC 12 in C++20 needs it

#include <cstdint>
#include <memory>
#include <string>

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/steady_timer.hpp>

#include "server/http/http_session.hpp"

namespace tessera {

class Listener : public std::enable_shared_from_this<Listener> {
 public:
  // Opens, binds and listens; throws boost::system::system_error when it cannot.
  Listener(boost::asio::io_context& io, const boost::asio::ip::tcp::endpoint& endpoint,
           std::shared_ptr<ServerShared> shared);

  std::uint16_t port() const { return port_; }

  void start();
  // From any thread: closes the acceptor, so no new connection is taken.
  void stop();

 private:
  void do_accept();
  void on_accept(const boost::system::error_code& ec, boost::asio::ip::tcp::socket socket);

  boost::asio::io_context& io_;
  boost::asio::ip::tcp::acceptor acceptor_;  // on a strand of its own
  boost::asio::steady_timer retry_timer_;    // same strand
  std::shared_ptr<ServerShared> shared_;
  std::uint16_t port_ = 0;
};

// "10.0.0.7:51234", "[::1]:51234": how a peer is named in logs and requests.
std::string format_endpoint(const boost::asio::ip::tcp::endpoint& endpoint);

}  // namespace tessera
