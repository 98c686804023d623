#include "server/http/http_server.hpp"

#include <utility>  // before Asio: Boost 1.74 with GCC 12 in C++20 needs it

#include <stdexcept>

#include <boost/asio/ip/address.hpp>

#include "server/http/http_session.hpp"
#include "server/http/listener.hpp"
#include "server/http/tls_context.hpp"

namespace tessera {

namespace net = boost::asio;

namespace {

net::ip::address parse_address(const std::string& text) {
  boost::system::error_code ec;
  const auto address = net::ip::make_address(text, ec);
  if (ec) throw std::invalid_argument("listen address \"" + text + "\" is not an IP address");
  return address;
}

// Unset hooks become ones that allow everything, so that sessions need not ask.
HttpServerOptions with_defaults(HttpServerOptions options) {
  if (!options.authorize)
    options.authorize = [](std::string_view, std::string_view) -> std::optional<HttpResponse> {
      return std::nullopt;
    };
  return options;
}

}  // namespace

HttpServer::HttpServer(net::io_context& io, const Router& router, HttpServerOptions options)
    : shared_(std::make_shared<ServerShared>(io, router, with_defaults(std::move(options)))) {
  if (shared_->options.min_body_rate == 0)
    throw std::invalid_argument("min_body_rate must be at least one byte per second");
  if (shared_->options.tls_cert_file.empty() != shared_->options.tls_key_file.empty())
    throw std::invalid_argument("TLS needs both a certificate and a key");
  reload_tls();
  const net::ip::tcp::endpoint endpoint(parse_address(shared_->options.address),
                                        shared_->options.port);
  listener_ = std::make_shared<Listener>(io, endpoint, shared_);
  port_ = listener_->port();
  listener_->start();
}

HttpServer::~HttpServer() { stop(); }

void HttpServer::stop() {
  // Once is enough; the flag also tells sessions that start from now on to close.
  if (shared_->stopping.exchange(true)) return;
  listener_->stop();
  shut_down_sessions(*shared_);
}

void HttpServer::reload_tls() {
  const HttpServerOptions& options = shared_->options;
  if (options.tls_cert_file.empty()) return;
  shared_->set_tls_context(make_server_tls_context(options.tls_cert_file, options.tls_key_file));
}

std::size_t HttpServer::connection_count() const { return shared_->connection_count.load(); }

}  // namespace tessera
