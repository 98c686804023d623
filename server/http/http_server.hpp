// The coordinator's HTTP/1.1 server: accepts connections and serves each on its own strand,
// handing requests to the Router's handlers. No Asio or Beast in this header, so that
// main and the tests include it cheaply.
//
// Typical use (the io_context may be run by several threads):
//
//   boost::asio::io_context io;
//   HttpServer server(io, router, options);  // bound and accepting from here on
//   boost::asio::signal_set signals(io, SIGINT, SIGTERM);
//   signals.async_wait([&](const boost::system::error_code& ec, int) {
//     if (ec) return;
//     long_polls.close();  // long-polls must answer for the drain to end
//     server.stop();
//   });
//   io.run();  // returns once stopped and every in-flight request has been answered
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include "server/http/http_types.hpp"
#include "server/http/origin_policy.hpp"

namespace boost::asio {
class io_context;
}

namespace tessera {

class HttpMetrics;
class Listener;
class Router;
struct ServerShared;

struct HttpServerOptions {
  std::string address = "127.0.0.1";  // an IP address; "0.0.0.0" or "::" for every interface
  std::uint16_t port = 8640;          // 0: any free port; see HttpServer::port()
  // From a request's first byte until its header is complete. A new connection must also
  // send its first byte within this.
  std::chrono::milliseconds header_timeout{10'000};
  // For the whole body, so that a client dribbling bytes cannot hold a connection forever;
  // extended by the time what arrives would take at min_body_rate, so that a large body on
  // a slow but steady link still gets through.
  std::chrono::milliseconds body_timeout{30'000};
  std::uint64_t min_body_rate = 64 * 1024;  // bytes per second
  // For writing a whole response to a slow reader.
  std::chrono::milliseconds write_timeout{30'000};
  // How long a kept-alive connection may wait for its next request.
  std::chrono::milliseconds idle_timeout{60'000};
  std::uint32_t max_header_bytes = 16 * 1024;  // larger: 431
  std::size_t max_target_bytes = 8 * 1024;     // a longer request target: 414
  std::size_t default_body_limit = 1 << 20;    // for routes added without a limit; larger: 413
  // Bodies announced larger than this are read only while all of them together stay within
  // body_budget_bytes (see BodyBudget); smaller ones, and chunked ones, are read at once.
  std::size_t budgeted_body_bytes = 64 * 1024;
  std::size_t body_budget_bytes = 64 << 20;
  // Open connections, in all and from one peer address; 0: no limit. Past either, the
  // connection that has waited longest for a request makes room for the new one, or the
  // new one is answered 503 (connection_admission.hpp).
  std::size_t max_connections = 0;
  std::size_t max_connections_per_peer = 0;
  // Asked once a request's header is read and its route known, before any body is read:
  // the route's role and the Authorization header ("" when absent). An answer refuses the
  // request with it. Unset: everyone may call everything.
  std::function<std::optional<HttpResponse>(std::string_view role, std::string_view authorization)>
      authorize;
  OriginPolicy origins;  // which pages may call, under which Host names
  // Counts every answer, by route, method and status (GET /metrics); none when null. Must
  // outlive the server.
  HttpMetrics* metrics = nullptr;
  // PEM files: with both set the server speaks TLS only (HTTPS), without, plain HTTP.
  std::string tls_cert_file;
  std::string tls_key_file;
};

class HttpServer {
 public:
  // Binds and listens (throws boost::system::system_error when it cannot,
  // std::invalid_argument for a bad address, std::runtime_error for TLS files it cannot
  // use) and starts accepting on `io`. `router` must
  // not change from here on, and must outlive every connection: keep it until io.run()
  // has returned.
  HttpServer(boost::asio::io_context& io, const Router& router, HttpServerOptions options);
  // Stops accepting; connections still open finish as after stop().
  ~HttpServer();
  HttpServer(const HttpServer&) = delete;
  HttpServer& operator=(const HttpServer&) = delete;

  // The port actually bound (the chosen one when options.port was 0).
  std::uint16_t port() const { return port_; }

  // Graceful: stops accepting, closes connections waiting for a request, and lets every
  // request already begun finish; those connections then close. Safe from any thread,
  // idempotent. io.run() returns once all that is done (and nothing else keeps it busy).
  void stop();

  // Open connections, idle ones included.
  std::size_t connection_count() const;

  // Reads the TLS certificate and key files again (after they were replaced, say) for the
  // connections that come from now on. Throws std::runtime_error, keeping the ones in use,
  // when they cannot be used; does nothing for a plain HTTP server.
  void reload_tls();

 private:
  std::shared_ptr<ServerShared> shared_;
  // Shared with its own pending accept, as Asio's completion handlers require.
  std::shared_ptr<Listener> listener_;
  std::uint16_t port_ = 0;
};

}  // namespace tessera
