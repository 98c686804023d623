// Which browser pages may call the server, and under which names it answers: any web page
// a farm user visits can send requests to a coordinator on their machine, and a page whose
// DNS name is rebound to 127.0.0.1 even reads the answers.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "server/http/http_types.hpp"
#include "server/http/request_framing.hpp"

namespace tessera {

struct OriginPolicy {
  // Origins besides the server's own whose pages may call it, as browsers send them:
  // "https://dashboard.example:8443" (scheme, host and port; no path).
  std::vector<std::string> allowed_origins;
  // Answer only requests whose Host is a loopback name or address (localhost, 127.0.0.0/8,
  // [::1]): for a server without tokens, which trusts whoever reaches it.
  bool loopback_hosts_only = false;
};

// 403 for an Origin that is neither the server's own (its authority is the request's Host,
// its scheme the server's: https for a server speaking TLS (`tls`), http or https, through
// a TLS proxy, for a plain one) nor allowed, or for a Host that is not loopback where only
// those are answered. No Origin (a program, not a page) is fine. nullopt: the request may
// go on.
std::optional<HttpResponse> origin_problem(const OriginPolicy& policy, std::string_view host,
                                           std::optional<std::string_view> origin, bool tls);

// 415 when a request that changes state (POST, PUT, PATCH) does not say its body is of the
// route's `wanted` media type ("": any). A browser may send a form or text/plain to any site
// without asking; any other type makes it ask first (CORS), which this server never grants.
std::optional<HttpResponse> content_type_problem(std::string_view method, std::string_view wanted,
                                                 std::string_view content_type);

// Both, for a request to a route that takes `wanted`.
std::optional<HttpResponse> browser_problem(const OriginPolicy& policy, const RequestHead& head,
                                            std::string_view wanted, bool tls);

}  // namespace tessera
