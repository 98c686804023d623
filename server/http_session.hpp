// One HTTP/1.1 connection, from accept to close. The session itself lives in
// http_session.cpp, the one server file that includes Beast.
#pragma once

#include <utility>  // before Asio: Boost 1.74 with GCC 12 in C++20 needs it

#include <atomic>
#include <cstddef>
#include <memory>
#include <mutex>
#include <string>
#include <unordered_map>

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>

#include "server/body_budget.hpp"
#include "server/http_server.hpp"

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
  // The open sessions, so that stop() can reach the idle ones. Guarded by `mutex`.
  std::unordered_map<const HttpSession*, std::weak_ptr<HttpSession>> sessions;

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

// Serves `socket` (whose executor must be a strand of its own) until it closes.
void start_http_session(boost::asio::ip::tcp::socket socket, std::shared_ptr<ServerShared> shared);

// Asks every open session to close once its current request, if any, is answered.
// Set shared.stopping first, so that sessions starting meanwhile close too.
void shut_down_sessions(ServerShared& shared);

}  // namespace tessera
