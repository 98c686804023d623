// A small synchronous HTTP/1.1 client for talking to the coordinator: the CLI, the worker
// daemon and the tests. Safe to share between threads: each request takes a kept-alive
// connection that no other request is using, or opens one, so threads that send at once
// each have their own (a worker's two upload senders share one client). Speaks https:// too,
// verifying the server's certificate. No Asio, Beast or OpenSSL in this header; they stay in
// http_client.cpp.
#pragma once

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace tessera {

struct HttpResult {
  int status = 0;
  std::map<std::string, std::string> headers;  // lower-case names; repeats joined with ", "
  std::string body;
};

// A request that got no HTTP answer. An answer with an error status is not an HttpError:
// it is an HttpResult whose status says so.
class HttpError : public std::runtime_error {
 public:
  enum class Kind {
    connect_failed,  // no connection could be made (refused, unreachable, unknown host)
    timeout,         // no complete answer within the client's timeout
    protocol,        // the connection failed or the answer was not valid HTTP
    interrupted,     // interrupt() was called
    tls,             // TLS failed: an untrusted or mismatched certificate, or no TLS there
  };
  HttpError(Kind kind, const std::string& message) : std::runtime_error(message), kind_(kind) {}
  Kind kind() const noexcept { return kind_; }

 private:
  Kind kind_;
};

struct BaseUrl {
  std::string host;  // without brackets for an IPv6 literal
  std::uint16_t port = 80;
  bool tls = false;  // https://
};

// A server URL this client cannot use, with what is wrong with it.
class BadServerUrl : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

// "http://host[:port][/]" (port 80 by default), "https://host[:port][/]" (443), or
// "host[:port]" for http. Throws BadServerUrl for anything else.
BaseUrl parse_base_url(std::string_view url);

// How an https:// server is checked: its certificate must chain to a CA trusted here and
// name the URL's host (a DNS name or an IP address).
struct TlsSettings {
  std::string ca_file;  // PEM file of the CAs to trust; "": the system's CA store
};
// `option` when given, else $TESSERA_CA_FILE, else "" (the system's store).
std::string ca_file_or_env(const std::string& option);

class HttpClient {
 public:
  using Headers = std::vector<std::pair<std::string, std::string>>;

  // Throws std::invalid_argument for a bad URL, and std::runtime_error for a CA file that
  // cannot be read; connects on the first request. `timeout` bounds connecting (the TLS
  // handshake included), and separately each whole request: sending it and reading the answer.
  HttpClient(std::string base_url, std::chrono::milliseconds timeout, const TlsSettings& tls = {});
  ~HttpClient();
  HttpClient(HttpClient&&) noexcept;
  HttpClient& operator=(HttpClient&&) noexcept;

  // `target` is the path and query, e.g. "/v1/jobs?state=running". Content-Type is sent
  // with a body, and with every POST, PUT and PATCH. Throws HttpError when no answer arrives. When
  // the kept-alive connection turns out to have been closed by the server before it answered, the
  // request is sent once more on a new connection.
  HttpResult request(std::string_view method, std::string_view target, std::string body = {},
                     std::string_view content_type = "application/json",
                     const Headers& headers = {});

  // How much of a body has gone out, and its size.
  using UploadProgress = std::function<void(std::uint64_t sent, std::uint64_t total)>;
  // request() with the file at `path` as the body, read from disk a piece at a time and
  // never held whole; `progress`, if set, is called after each piece. The timeout bounds
  // each piece and the answer, not the whole upload. Throws std::runtime_error for a file
  // that cannot be opened.
  HttpResult send_file(std::string_view method, std::string_view target,
                       const std::filesystem::path& path, std::string_view content_type,
                       const UploadProgress& progress = {}, const Headers& headers = {});
  // A bodiless request whose answer's body goes to the file `into` as it arrives, never
  // held whole; the result's body is empty. An answer that is not 2xx leaves no file: its
  // body (an error, up to 64 KiB of it) is the result's, as request() gives it.
  HttpResult receive_file(std::string_view method, std::string_view target,
                          const std::filesystem::path& into, const Headers& headers = {});

  // A GET whose answer's body is handed to `on_data` a piece at a time as it arrives (a
  // stream of server-sent events), until it ends, `on_data` returns false, or nothing
  // arrives within the timeout (a stream that sends keep-alives never waits that long).
  // An answer that is not 2xx is returned whole, as request() gives it; a 2xx one with an
  // empty body. The connection is not reused.
  using OnData = std::function<bool(std::string_view piece)>;
  HttpResult stream(std::string_view target, const OnData& on_data, const Headers& headers = {});

  // For requests that may legitimately take long, such as a long-polled claim; from the
  // next request on.
  void set_timeout(std::chrono::milliseconds timeout);
  // Sent as "Authorization: Bearer TOKEN" with every request; "" for none. Set it before
  // the client is shared.
  void set_bearer_token(std::string token);
  // Ends the requests in progress, if any, and every later one, with an HttpError of kind
  // `interrupted`, until clear_interrupt(). For a process that must not sit out a long
  // poll when it is asked to stop.
  void interrupt();
  // Makes the client usable again after interrupt(), on new connections.
  void clear_interrupt();
  // Called with every answer that arrives, before request() returns it: for a program that
  // logs its traffic, or tests that check each answer against docs/openapi.yaml. Set it
  // before the client is shared.
  using Observer = std::function<void(std::string_view method, std::string_view target,
                                      const HttpResult& result)>;
  void set_observer(Observer observer) { observer_ = std::move(observer); }
  const std::string& base_url() const { return base_url_; }

 private:
  struct Connection;
  struct Pool;
  // Sends `message` (whose body type is a string's or a file's) and reads the answer, on a
  // kept-alive connection or a new one; `rewind` makes the body ready to be sent again.
  // `into`: the file the answer's body goes to, where it goes to one.
  template <typename Message>
  HttpResult send(Message& message, std::string_view method, std::string_view target,
                  const UploadProgress* progress, const std::function<void()>& rewind,
                  const std::filesystem::path* into = nullptr);
  template <typename Message>
  void prepare(Message& message, std::string_view method, std::string_view target, bool has_body,
               std::string_view content_type, const Headers& headers) const;
  std::string base_url_;
  std::string authorization_;  // the whole header value; "" for none
  Observer observer_;
  std::unique_ptr<Pool> pool_;
};

}  // namespace tessera
