// One kept-alive HTTP/1.1 connection to the coordinator, asynchronous, for a program that
// runs a thousand of them on one thread. It speaks only what the coordinator answers
// (Content-Length bodies, or none for 204): a full client would cost the load program CPU
// that belongs to the coordinator under test.
#pragma once

#include <utility>  // before Asio: Boost 1.74 with GCC 12 in C++20 needs it

#include <functional>
#include <span>
#include <string>
#include <string_view>

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>

namespace tessera::load {

class HttpConnection {
 public:
  // The answer's body is valid during the call only.
  using Done =
      std::function<void(const boost::system::error_code&, int status, std::string_view body)>;

  // `authorization` is a whole "Authorization: ...\r\n" line, or "".
  HttpConnection(boost::asio::io_context& io, boost::asio::ip::tcp::endpoint server,
                 std::string authorization);

  void connect(std::function<void(const boost::system::error_code&)> done);
  // `extra_headers` are whole lines, each ending in "\r\n"; `body` must stay valid until
  // `done` is called. One request at a time.
  void request(std::string_view method, std::string_view target, std::string_view extra_headers,
               std::span<const char> body, Done done);
  void close();

 private:
  void read_header();
  void read_body(std::size_t header_bytes, int status, std::size_t body_bytes);
  void finish(const boost::system::error_code& ec, int status, std::size_t header_bytes,
              std::size_t body_bytes);

  boost::asio::ip::tcp::socket socket_;
  boost::asio::ip::tcp::endpoint server_;
  std::string authorization_;
  std::string head_;  // the request line and header being sent
  std::string in_;    // bytes read and not yet consumed
  std::string body_;  // the last answer's body, handed to `done_`
  Done done_;
};

}  // namespace tessera::load
