#include "server/http/router.hpp"

#include <algorithm>
#include <stdexcept>

namespace tessera {
namespace {

// "/a/b/" -> {"a", "b", ""}; "/" -> {""}. The caller has checked the leading '/'.
std::vector<std::string_view> split_path(std::string_view path) {
  std::vector<std::string_view> parts;
  std::size_t start = 1;
  while (true) {
    const std::size_t slash = path.find('/', start);
    parts.push_back(path.substr(start, slash == std::string_view::npos ? slash : slash - start));
    if (slash == std::string_view::npos) return parts;
    start = slash + 1;
  }
}

bool is_param_name(std::string_view name) {
  return !name.empty() && std::all_of(name.begin(), name.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
  });
}

int hex_value(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

}  // namespace

std::optional<std::string> percent_decode(std::string_view text, bool plus_is_space) {
  std::string out;
  out.reserve(text.size());
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (c == '%') {
      if (i + 2 >= text.size()) return std::nullopt;
      const int high = hex_value(text[i + 1]);
      const int low = hex_value(text[i + 2]);
      if (high < 0 || low < 0) return std::nullopt;
      out.push_back(static_cast<char>(high * 16 + low));
      i += 2;
    } else if (c == '+' && plus_is_space) {
      out.push_back(' ');
    } else {
      out.push_back(c);
    }
  }
  return out;
}

std::optional<std::map<std::string, std::string>> parse_query(std::string_view query) {
  std::map<std::string, std::string> values;
  while (!query.empty()) {
    const std::size_t amp = query.find('&');
    const std::string_view part = query.substr(0, amp);
    query = amp == std::string_view::npos ? std::string_view() : query.substr(amp + 1);
    if (part.empty()) continue;
    const std::size_t eq = part.find('=');
    auto key = percent_decode(part.substr(0, eq), true);
    auto value = percent_decode(
        eq == std::string_view::npos ? std::string_view() : part.substr(eq + 1), true);
    if (!key || !value) return std::nullopt;
    values.insert_or_assign(std::move(*key), std::move(*value));
  }
  return values;
}

void Router::add(std::string method, std::string pattern, Handler handler, RouteOptions options) {
  if (method.empty()) throw std::invalid_argument("route " + pattern + ": empty method");
  if (pattern.empty() || pattern.front() != '/')
    throw std::invalid_argument("route pattern \"" + pattern + "\" must start with '/'");
  if (!handler) throw std::invalid_argument("route " + method + " " + pattern + ": no handler");

  std::vector<Segment> segments;
  for (std::string_view part : split_path(pattern)) {
    if (part.starts_with('{') && part.ends_with('}') && part.size() >= 2) {
      const std::string_view name = part.substr(1, part.size() - 2);
      if (!is_param_name(name))
        throw std::invalid_argument("route pattern \"" + pattern + "\": bad parameter name");
      for (const Segment& s : segments)
        if (s.is_param && s.text == name)
          throw std::invalid_argument("route pattern \"" + pattern + "\": repeated parameter " +
                                      std::string(name));
      segments.push_back({std::string(name), true});
    } else if (part.find_first_of("{}") != std::string_view::npos) {
      throw std::invalid_argument("route pattern \"" + pattern +
                                  "\": a parameter must be a whole segment");
    } else {
      segments.push_back({std::string(part), false});
    }
  }

  for (const Route& route : routes_) {
    if (route.pattern == pattern) {
      if (route.method == method)
        throw std::logic_error("route " + method + " " + pattern + " added twice");
      continue;
    }
    const bool same_shape =
        std::equal(route.segments.begin(), route.segments.end(), segments.begin(), segments.end(),
                   [](const Segment& a, const Segment& b) {
                     return a.is_param == b.is_param && (a.is_param || a.text == b.text);
                   });
    if (same_shape)
      throw std::logic_error("route pattern \"" + pattern + "\" is \"" + route.pattern +
                             "\" with other parameter names");
  }
  routes_.push_back({std::move(method), std::move(pattern), std::move(segments), std::move(handler),
                     std::move(options)});
}

RouteMatch Router::match(std::string_view method, std::string_view path) const {
  RouteMatch result;
  if (path.empty() || path.front() != '/') {
    result.error = error_response(404, "not_found", "no route for " + std::string(path));
    return result;
  }
  std::vector<std::string> parts;
  for (std::string_view raw : split_path(path)) {
    auto decoded = percent_decode(raw, false);
    if (!decoded) {
      result.error = error_response(400, "bad_request", "the path is not valid percent-encoding");
      return result;
    }
    parts.push_back(std::move(*decoded));
  }

  const auto fits = [&](const Route& route) {
    if (route.segments.size() != parts.size()) return false;
    for (std::size_t i = 0; i < parts.size(); ++i) {
      const Segment& s = route.segments[i];
      if (s.is_param ? parts[i].empty() : s.text != parts[i]) return false;
    }
    return true;
  };
  // Of two fitting patterns (same length), the one whose first difference is a literal.
  const auto more_specific = [](const Route& a, const Route& b) {
    for (std::size_t i = 0; i < a.segments.size(); ++i)
      if (a.segments[i].is_param != b.segments[i].is_param) return !a.segments[i].is_param;
    return false;
  };

  const Route* best = nullptr;
  for (const Route& route : routes_)
    if (fits(route) && (!best || more_specific(route, *best))) best = &route;
  if (!best) {
    result.error = error_response(404, "not_found", "no route for " + std::string(path));
    return result;
  }

  // HEAD is GET without the body (RFC 9110 9.3.2), on every GET route not given a HEAD
  // of its own; the HTTP layer leaves the body out.
  bool has_head = false;
  for (const Route& route : routes_)
    has_head = has_head || (route.pattern == best->pattern && route.method == "HEAD");
  const std::string_view wanted = method == "HEAD" && !has_head ? "GET" : method;
  std::string allow;
  for (const Route& route : routes_) {
    if (route.pattern != best->pattern) continue;
    if (route.method == wanted) {
      result.handler = &route.handler;
      result.pattern = route.pattern;
      result.body_limit = route.options.body_limit;
      result.role = route.options.role;
      result.sink = route.options.sink ? &route.options.sink : nullptr;
      result.content_type = route.options.content_type;
      for (std::size_t i = 0; i < parts.size(); ++i)
        if (route.segments[i].is_param) result.params.emplace(route.segments[i].text, parts[i]);
      return result;
    }
    if (!allow.empty()) allow += ", ";
    allow += route.method;
    if (route.method == "GET" && !has_head) allow += ", HEAD";
  }
  result.pattern = best->pattern;
  result.error = error_response(
      405, "method_not_allowed",
      std::string(method) + " is not allowed on " + std::string(path) + "; allowed: " + allow);
  result.error.headers.emplace_back("Allow", allow);
  return result;
}

std::optional<std::string> Router::role_of(std::string_view method,
                                           std::string_view pattern) const {
  for (const Route& route : routes_)
    if (route.method == method && route.pattern == pattern) return route.options.role;
  return std::nullopt;
}

std::vector<std::pair<std::string, std::string>> Router::routes() const {
  std::vector<std::pair<std::string, std::string>> list;
  list.reserve(routes_.size());
  for (const Route& route : routes_) list.emplace_back(route.method, route.pattern);
  return list;
}

}  // namespace tessera
