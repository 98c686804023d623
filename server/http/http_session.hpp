// One HTTP/1.1 connection, from accept to close. The session itself lives in
// http_session.cpp, which with its stream_writer.hpp is all the server code that includes Beast.
#pragma once

#include <utility>  // before Asio: Boost 1.74 with GCC 12 in C++20 needs it

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <unordered_map>

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>

#include "server/http/body_budget.hpp"
#include "server/http/http_server.hpp"

namespace boost::asio::ssl {
class context;
}

namespace tessera {

// One HTTP/1.1 connection, plain or TLS (http_session.cpp).
class HttpSession : public std::enable_shared_from_this<HttpSession> {
 public:
  virtual ~HttpSession() = default;
  // Asks it to close once its current request, if any, is answered. From any thread.
  virtual void shut_down() = 0;
  // Delivers a handler's answer, from any thread.
  virtual void deliver(HttpResponse response) = 0;
  // Closes it at once if it is still only waiting for a request (or for the rest of a
  // request's header), as a full server takes the oldest such connection for a new one;
  // otherwise it stays. From any thread.
  virtual void evict() = 0;

  // Since when (steady clock, microseconds) it has waited for a request or read one whose
  // header is not complete yet; 0 while it serves one. Written on its strand, read by the
  // listener.
  std::atomic<std::int64_t> waiting_since_us{0};
};

// What every connection needs from the server that accepted it. Shared, because
// connections still finishing their last request may outlive the HttpServer object.
struct ServerShared {
  ServerShared(boost::asio::io_context& io_context, const Router& router_ref,
               HttpServerOptions server_options)
      : io(io_context),
        router(router_ref),
        options(std::move(server_options)),
        body_budget(options.body_budget_bytes) {}

  boost::asio::io_context& io;
  const Router& router;
  const HttpServerOptions options;
  BodyBudget body_budget;
  std::atomic<bool> stopping{false};
  std::atomic<std::size_t> connection_count{0};

  std::mutex mutex;
  // The open sessions, so that stop() can reach the idle ones and a full server the oldest
  // waiting one, and the connections open from each peer address. Guarded by `mutex`.
  struct OpenSession {
    std::weak_ptr<HttpSession> session;
    std::string peer;
    bool evicted = false;  // asked to close for a newer connection; no longer counted
  };
  std::unordered_map<const HttpSession*, OpenSession> sessions;
  std::unordered_map<std::string, std::size_t> open_by_peer;  // not counting evicted ones
  std::size_t open_counted = 0;                               // likewise

  // The TLS context new connections take (null: plain HTTP). A reload replaces it;
  // connections already open keep theirs.
  std::shared_ptr<boost::asio::ssl::context> tls_context() {
    std::lock_guard lock(mutex);
    return tls;
  }
  void set_tls_context(std::shared_ptr<boost::asio::ssl::context> context) {
    std::lock_guard lock(mutex);
    tls = std::move(context);
  }

 private:
  std::shared_ptr<boost::asio::ssl::context> tls;  // guarded by `mutex`
};

// Serves `socket` (whose executor must be a strand of its own) until it closes. `peer` is
// its remote address, as admit_connection() counted it.
void start_http_session(boost::asio::ip::tcp::socket socket, std::shared_ptr<ServerShared> shared,
                        const std::string& peer);

// Asks every open session to close once its current request, if any, is answered.
// Set shared.stopping first, so that sessions starting meanwhile close too.
void shut_down_sessions(ServerShared& shared);

}  // namespace tessera
