#include "bench/coordinator_load/http_connection.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>

#include <boost/asio/buffer.hpp>
#include <boost/asio/connect.hpp>
#include <boost/asio/read.hpp>
#include <boost/asio/read_until.hpp>
#include <boost/asio/write.hpp>

namespace tessera::load {
namespace {

namespace net = boost::asio;
using error_code = boost::system::error_code;

// The value of `name` (lower case, with its colon) in an HTTP header block; "" when absent.
std::string_view header_value(std::string_view header, std::string_view name) {
  for (std::size_t line = header.find("\r\n"); line != std::string_view::npos;
       line = header.find("\r\n", line + 2)) {
    const std::string_view rest = header.substr(line + 2);
    if (rest.size() < name.size()) break;
    const bool same = std::equal(name.begin(), name.end(), rest.begin(), [](char a, char b) {
      return a == std::tolower(static_cast<unsigned char>(b));
    });
    if (!same) continue;
    std::string_view value = rest.substr(name.size(), rest.find("\r\n") - name.size());
    while (!value.empty() && value.front() == ' ') value.remove_prefix(1);
    return value;
  }
  return {};
}

}  // namespace

HttpConnection::HttpConnection(net::io_context& io, net::ip::tcp::endpoint server,
                               std::string authorization)
    : socket_(io), server_(server), authorization_(std::move(authorization)) {}

void HttpConnection::connect(std::function<void(const error_code&)> done) {
  in_.clear();
  socket_.async_connect(server_, [this, done = std::move(done)](const error_code& ec) {
    if (!ec) {
      error_code ignored;
      socket_.set_option(net::ip::tcp::no_delay(true), ignored);
    }
    done(ec);
  });
}

void HttpConnection::request(std::string_view method, std::string_view target,
                             std::string_view extra_headers, std::span<const char> body,
                             Done done) {
  done_ = std::move(done);
  head_.clear();
  head_.append(method).append(" ").append(target).append(" HTTP/1.1\r\nHost: 127.0.0.1\r\n");
  head_.append(authorization_).append(extra_headers);
  head_.append("Content-Length: ").append(std::to_string(body.size())).append("\r\n\r\n");
  const std::array<net::const_buffer, 2> buffers{net::buffer(head_),
                                                 net::buffer(body.data(), body.size())};
  net::async_write(socket_, buffers, [this](const error_code& ec, std::size_t) {
    if (ec) return finish(ec, 0, 0, 0);
    read_header();
  });
}

void HttpConnection::read_header() {
  net::async_read_until(
      socket_, net::dynamic_buffer(in_), "\r\n\r\n",
      [this](const error_code& ec, std::size_t header_bytes) {
        if (ec) return finish(ec, 0, 0, 0);
        const std::string_view header(in_.data(), header_bytes);
        int status = 0;
        if (header.size() < 12 ||
            std::from_chars(header.data() + 9, header.data() + 12, status).ec != std::errc())
          return finish(net::error::invalid_argument, 0, 0, 0);
        std::size_t length = 0;
        if (status >= 200 && status != 204 && status != 304) {
          const std::string_view text = header_value(header, "content-length:");
          if (text.empty() ||
              std::from_chars(text.data(), text.data() + text.size(), length).ec != std::errc())
            return finish(net::error::invalid_argument, status, 0, 0);
        }
        read_body(header_bytes, status, length);
      });
}

void HttpConnection::read_body(std::size_t header_bytes, int status, std::size_t body_bytes) {
  const std::size_t total = header_bytes + body_bytes;
  if (in_.size() >= total) return finish({}, status, header_bytes, body_bytes);
  net::async_read(socket_, net::dynamic_buffer(in_), net::transfer_exactly(total - in_.size()),
                  [this, header_bytes, status, body_bytes](const error_code& ec, std::size_t) {
                    if (ec) return finish(ec, 0, 0, 0);
                    finish({}, status, header_bytes, body_bytes);
                  });
}

void HttpConnection::finish(const error_code& ec, int status, std::size_t header_bytes,
                            std::size_t body_bytes) {
  // Consumed before the call: `done_` may send the next request, whose read starts from
  // what is left in `in_`.
  body_.assign(in_, std::min(header_bytes, in_.size()), body_bytes);
  in_.erase(0, std::min(header_bytes + body_bytes, in_.size()));
  Done done = std::move(done_);
  done(ec, status, body_);
}

void HttpConnection::close() {
  error_code ignored;
  socket_.close(ignored);
}

}  // namespace tessera::load
