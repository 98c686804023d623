// Maps (method, path) to a handler. Patterns are literal segments and whole-segment
// parameters: "/v1/jobs/{id}/image". The server asks the router before reading a request's
// body, so that a route's body limit applies to the bytes still on the wire.
#pragma once

#include <cstddef>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "server/http/http_types.hpp"

namespace tessera {

struct RouteMatch {
  const Handler* handler = nullptr;           // null when nothing is to be called; see `error`
  std::string pattern;                        // the matched route's pattern, for logs
  std::map<std::string, std::string> params;  // percent-decoded
  std::optional<std::size_t> body_limit;      // nullopt: the server's default
  std::string role;                           // who may call it; "" for anyone
  std::string content_type;                   // of the body a POST or PUT must send
  const SinkFactory* sink = nullptr;          // set: the body streams to a sink, not memory
  // When handler is null: 404 not_found, 405 method_not_allowed (with an Allow header)
  // or 400 bad_request (a path that is not valid percent-encoding).
  HttpResponse error;
};

// What a route asks of a request beyond its method and path, each set by name:
// RouteOptions{}.with_role(role_client).with_body_limit(1024).
struct RouteOptions {
  std::optional<std::size_t> body_limit;  // nullopt: the server's default
  // Who may call it, for HttpServerOptions::authorize; "" is anyone.
  std::string role;
  // What a POST or PUT to it must declare, bodiless or not (415 else); "" takes any.
  std::string content_type = "application/json";
  SinkFactory sink;  // set: the body streams to a sink, not memory

  RouteOptions with_body_limit(std::size_t bytes) && {
    body_limit = bytes;
    return std::move(*this);
  }
  RouteOptions with_role(std::string name) && {
    role = std::move(name);
    return std::move(*this);
  }
  RouteOptions with_content_type(std::string type) && {
    content_type = std::move(type);
    return std::move(*this);
  }
  RouteOptions with_sink(SinkFactory factory) && {
    sink = std::move(factory);
    return std::move(*this);
  }
};

// Routes are added before the server starts; match() is then safe from any thread.
class Router {
 public:
  // Throws std::invalid_argument for a malformed pattern, and std::logic_error for a
  // (method, pattern) already added or a pattern that differs from an existing one only in
  // its parameter names (the two could never be told apart).
  void add(std::string method, std::string pattern, Handler handler, RouteOptions options = {});

  // `path` is the request target without its query, still percent-encoded. Where several
  // patterns fit, the one with a literal segment earliest wins ("/v1/jobs/stats" over
  // "/v1/jobs/{id}"), and the method is then looked up among that pattern's routes only.
  RouteMatch match(std::string_view method, std::string_view path) const;

  // (method, pattern) in the order added.
  std::vector<std::pair<std::string, std::string>> routes() const;
  // The role of the route (method, pattern); nullopt when there is no such route.
  std::optional<std::string> role_of(std::string_view method, std::string_view pattern) const;

 private:
  struct Segment {
    std::string text;  // the literal, or the parameter's name
    bool is_param = false;
  };
  struct Route {
    std::string method;
    std::string pattern;
    std::vector<Segment> segments;
    Handler handler;
    RouteOptions options;
  };

  std::vector<Route> routes_;
};

// RFC 3986 percent-decoding; nullopt when a '%' is not followed by two hex digits.
// `plus_is_space` for query strings (application/x-www-form-urlencoded).
std::optional<std::string> percent_decode(std::string_view text, bool plus_is_space);

// "a=1&b=x%20y&flag" -> {a: "1", b: "x y", flag: ""}; a repeated key keeps its last value.
// nullopt when some part is not valid percent-encoding.
std::optional<std::map<std::string, std::string>> parse_query(std::string_view query);

}  // namespace tessera
