#include "server/http/origin_policy.hpp"

#include <utility>  // before Asio: Boost 1.74 with GCC 12 in C++20 needs it

#include <boost/asio/ip/address.hpp>

namespace tessera {

namespace {

// "name:port", "1.2.3.4:port" or "[v6]:port" without the port and brackets.
std::string_view host_name(std::string_view host) {
  if (!host.empty() && host.front() == '[') {
    const std::size_t end = host.find(']');
    return end == std::string_view::npos ? host : host.substr(1, end - 1);
  }
  return host.substr(0, host.find(':'));
}

bool is_loopback_name(std::string_view host) {
  const std::string name = ascii_lower(host_name(host));
  if (name == "localhost" || (name.size() > 10 && name.ends_with(".localhost"))) return true;
  boost::system::error_code ec;
  const auto address = boost::asio::ip::make_address(name, ec);
  return !ec && address.is_loopback();
}

}  // namespace

std::optional<HttpResponse> origin_problem(const OriginPolicy& policy, std::string_view host,
                                           std::optional<std::string_view> origin, bool tls) {
  if (policy.loopback_hosts_only && !is_loopback_name(host))
    return error_response(
        403, "host_refused",
        "this server has no tokens, so it answers only requests addressed to this machine "
        "(localhost, 127.0.0.1 or [::1]), not to '" +
            std::string(host) +
            "'; give it --api-token and --worker-token to be reached by other names");
  if (!origin) return std::nullopt;
  const std::string seen = ascii_lower(trim_ows(*origin));
  const std::size_t scheme_end = seen.find("://");
  // The server's own pages: of its own host and port, and of its own scheme. A plain
  // server's pages may come as https:// too, through a TLS proxy in front of it; a TLS
  // server's never come over plain http://, where a network attacker could write them.
  const std::string_view scheme = std::string_view(seen).substr(0, scheme_end);
  const bool own_scheme = scheme == "https" || (!tls && scheme == "http");
  if (scheme_end != std::string::npos && own_scheme &&
      seen.substr(scheme_end + 3) == ascii_lower(host))
    return std::nullopt;
  for (const std::string& allowed : policy.allowed_origins)
    if (iequals_ascii(allowed, seen)) return std::nullopt;
  return error_response(403, "origin_refused",
                        "requests from the web page of origin '" + std::string(*origin) +
                            "' are refused; start the server with --allowed-origin " +
                            std::string(*origin) + " to let that page call it");
}

std::optional<HttpResponse> content_type_problem(std::string_view method, std::string_view wanted,
                                                 std::string_view content_type) {
  if (wanted.empty() || (method != "POST" && method != "PUT" && method != "PATCH"))
    return std::nullopt;
  const std::string_view media = trim_ows(content_type.substr(0, content_type.find(';')));
  if (iequals_ascii(media, wanted)) return std::nullopt;
  return error_response(
      415, "unsupported_media_type",
      "this route takes Content-Type: " + std::string(wanted) +
          (media.empty() ? ", and the request has none" : "; got '" + std::string(media) + "'"));
}

std::optional<HttpResponse> browser_problem(const OriginPolicy& policy, const RequestHead& head,
                                            std::string_view wanted, bool tls) {
  if (auto refused =
          origin_problem(policy, head.field("host").value_or(""), head.field("origin"), tls))
    return refused;
  return content_type_problem(head.method, wanted, head.field("content-type").value_or(""));
}

}  // namespace tessera
