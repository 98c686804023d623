// What a route handler sees of HTTP: plain structs, no Beast, so that the many handler
// files compile quickly and can be unit-tested without a socket.
#pragma once

#include <chrono>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/protocol/error.hpp"
#include "common/text/ascii_case.hpp"  // header names are kept lower case: ascii_lower()

namespace tessera {

// A body that a route takes piece by piece as it arrives rather than whole (an asset
// upload, which may be gigabytes): the session reads the next piece only once `done` has
// been called, from any thread, with whether the piece was taken.
class BodySink {
 public:
  virtual ~BodySink() = default;
  virtual void write(std::string piece, std::function<void(bool taken)> done) = 0;
};

struct HttpRequest {
  std::string method;                          // as sent, e.g. "GET"
  std::string path;                            // percent-encoded, as sent, without the query
  std::map<std::string, std::string> query;    // decoded; a repeated key keeps its last value
  std::map<std::string, std::string> params;   // decoded, from the route pattern's {names}
  std::map<std::string, std::string> headers;  // lower-case names; repeats joined with ", "
  std::string body;
  std::string remote_address;  // "ip:port" of the peer
  // For a route that streams its body: where the body went; `body` is then empty.
  std::shared_ptr<BodySink> body_sink;
};

// A body sent as it comes, for as long as the peer stays (server-sent events). The session
// writes the response's header, then whatever take() has each time, and keepalive() when
// nothing came for keepalive_interval(); the connection closes at the end.
class BodyStream {
 public:
  virtual ~BodyStream() = default;
  // Calls `ready` once, from any thread, when take() has something or the stream has
  // ended (at once when it has already). A later wait() replaces an earlier `ready`.
  virtual void wait(std::function<void()> ready) = 0;
  // What to send now, "" when nothing; `ended` is set once the stream is over.
  virtual std::string take(bool& ended) = 0;
  // The peer went, or the server stops: nothing more is taken, `ready` is dropped.
  virtual void cancel() = 0;
  virtual std::string keepalive() const = 0;
  virtual std::chrono::milliseconds keepalive_interval() const = 0;
};

struct HttpResponse {
  using Headers = std::vector<std::pair<std::string, std::string>>;
  HttpResponse() = default;
  HttpResponse(int status_code, std::string type, std::string text, Headers extra_headers = {})
      : status(status_code),
        content_type(std::move(type)),
        body(std::move(text)),
        headers(std::move(extra_headers)) {}

  int status = 200;
  std::string content_type = "application/json";  // empty: no Content-Type header
  std::string body;
  Headers headers;  // added as given
  // When set, the body is this file's bytes, sent from the disk rather than held in memory
  // (a big image), and `body` is ignored. A temporary file is removed once it is opened.
  std::string file;
  bool file_is_temporary = false;
  // When set, the body is this stream's (server-sent events), and `body` is ignored.
  std::shared_ptr<BodyStream> stream;
};

// Header names and tokens (codings, media types) compare without regard to ASCII case.
inline bool iequals_ascii(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  const auto lower = [](char c) { return c >= 'A' && c <= 'Z' ? char(c - 'A' + 'a') : c; };
  for (std::size_t i = 0; i < a.size(); ++i)
    if (lower(a[i]) != lower(b[i])) return false;
  return true;
}

// A header value without the optional white space (spaces and tabs) around it.
inline std::string_view trim_ows(std::string_view text) {
  while (!text.empty() && (text.front() == ' ' || text.front() == '\t')) text.remove_prefix(1);
  while (!text.empty() && (text.back() == ' ' || text.back() == '\t')) text.remove_suffix(1);
  return text;
}

// Answers a request. May be called later and from any thread, but exactly once: a second
// call is ignored, and dropping every copy without calling it answers 500.
using Respond = std::function<void(HttpResponse)>;
using Handler = std::function<void(HttpRequest&&, Respond)>;
// Makes the sink for a request's body from its head (no body yet), once the route, its
// role and its limits have passed; throws to refuse with 500.
using SinkFactory = std::function<std::shared_ptr<BodySink>(const HttpRequest& head)>;

inline HttpResponse json_response(int status, const nlohmann::json& body) {
  // Replace rather than throw on invalid UTF-8: a response must always be producible,
  // even when it echoes bytes a client sent.
  return HttpResponse{status,
                      "application/json",
                      body.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace),
                      {}};
}

// The body every error has: {"error": {"code", "message", "path"?}}. `path` is a JSON
// Pointer into the request body, for errors about one of its values.
inline HttpResponse error_response(int status, std::string code, std::string message,
                                   std::string path = "") {
  protocol::Error error{std::move(code), std::move(message), {}, {}, {}};
  if (!path.empty()) error.path = std::move(path);
  return json_response(status, protocol::to_json(error));
}

}  // namespace tessera
