// A client that can do what HttpClient never would, for the HTTP layer's tests: send half a
// request, garbage, or nothing at all, and see exactly when the server hangs up.
#pragma once

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <chrono>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>

#include <nlohmann/json.hpp>

namespace tessera::raw_http {

using Clock = std::chrono::steady_clock;

// One connection of such a client.
class RawConnection {
 public:
  // `receive_buffer`: the socket's receive buffer in bytes (0: the system's), small for a
  // client that is to fall behind.
  explicit RawConnection(std::uint16_t port, int receive_buffer = 0)
      : fd_(::socket(AF_INET, SOCK_STREAM, 0)) {
    if (fd_ < 0) throw std::runtime_error("socket failed");
    if (receive_buffer > 0)
      ::setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &receive_buffer, sizeof receive_buffer);
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_port = htons(port);
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (::connect(fd_, reinterpret_cast<sockaddr*>(&address), sizeof address) != 0)
      throw std::runtime_error("connect failed");
  }
  ~RawConnection() { ::close(fd_); }
  RawConnection(const RawConnection&) = delete;
  RawConnection& operator=(const RawConnection&) = delete;

  void send(std::string_view data) {
    while (!data.empty()) {
      const ssize_t sent = ::send(fd_, data.data(), data.size(), MSG_NOSIGNAL);
      if (sent <= 0) throw std::runtime_error("send failed");
      data.remove_prefix(static_cast<std::size_t>(sent));
    }
  }

  // One response: the header, then as many body bytes as its Content-Length says.
  std::string read_response(std::chrono::milliseconds limit = std::chrono::seconds(10)) {
    const auto deadline = Clock::now() + limit;
    while (true) {
      const std::size_t header_end = received_.find("\r\n\r\n");
      if (header_end != std::string::npos) {
        std::size_t length = 0;
        const std::size_t at = lower(received_.substr(0, header_end)).find("content-length:");
        if (at != std::string::npos) length = std::stoul(received_.substr(at + 15));
        const std::size_t total = header_end + 4 + length;
        if (received_.size() >= total) {
          std::string response = received_.substr(0, total);
          received_.erase(0, total);
          return response;
        }
      }
      if (!receive_some(deadline)) return std::exchange(received_, {});
    }
  }

  // One response's header alone, through its blank line: the answer to a HEAD, whose
  // Content-Length announces a body that is not sent.
  std::string read_header(std::chrono::milliseconds limit = std::chrono::seconds(10)) {
    const auto deadline = Clock::now() + limit;
    while (true) {
      const std::size_t header_end = received_.find("\r\n\r\n");
      if (header_end != std::string::npos) {
        std::string header = received_.substr(0, header_end + 4);
        received_.erase(0, header_end + 4);
        return header;
      }
      if (!receive_some(deadline)) return std::exchange(received_, {});
    }
  }

  // The next block of a server-sent event stream, through its blank line; "" when none
  // came by the deadline or the connection closed.
  std::string read_event(std::chrono::milliseconds limit = std::chrono::seconds(10)) {
    const auto deadline = Clock::now() + limit;
    while (true) {
      const std::size_t end = received_.find("\n\n");
      if (end != std::string::npos) {
        std::string block = received_.substr(0, end + 2);
        received_.erase(0, end + 2);
        return block;
      }
      if (!receive_some(deadline)) return {};
    }
  }

  // True when the server closes the connection within `limit`; what it sent is dropped.
  bool closed_within(std::chrono::milliseconds limit) {
    const auto deadline = Clock::now() + limit;
    while (receive_some(deadline)) received_.clear();
    return closed_;
  }

 private:
  static std::string lower(std::string text) {
    for (char& c : text) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return text;
  }

  // False once the connection is closed or the deadline has passed.
  bool receive_some(Clock::time_point deadline) {
    if (closed_) return false;
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now());
    if (left.count() <= 0) return false;
    pollfd entry{fd_, POLLIN, 0};
    if (::poll(&entry, 1, static_cast<int>(left.count())) <= 0) return false;
    char chunk[4096];
    const ssize_t got = ::recv(fd_, chunk, sizeof chunk, 0);
    if (got <= 0) {
      closed_ = got == 0 || errno == ECONNRESET;
      return false;
    }
    received_.append(chunk, static_cast<std::size_t>(got));
    return true;
  }

  int fd_;
  std::string received_;
  bool closed_ = false;
};

inline int status_of(const std::string& raw_response) {
  return raw_response.size() > 12 ? std::stoi(raw_response.substr(9, 3)) : 0;
}

inline nlohmann::json body_of(const std::string& raw_response) {
  const std::size_t at = raw_response.find("\r\n\r\n");
  return nlohmann::json::parse(raw_response.substr(at + 4));
}

}  // namespace tessera::raw_http
