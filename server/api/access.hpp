// Who may call which route. Clients and workers hold separate secrets (--api-token,
// --worker-token), sent as "Authorization: Bearer ..."; a role whose token is not set is
// open to anyone. Tokens are compared by their SHA-256 digests in constant time, and never
// logged.
#pragma once

#include <optional>
#include <string>
#include <string_view>

#include "server/http/http_types.hpp"

namespace tessera {

inline constexpr const char* role_client = "client";  // jobs, images, the worker list
inline constexpr const char* role_worker = "worker";  // registration, claims, leases, scenes
// GET /metrics: its own token (--metrics-token), so that a scraper holds no power over jobs;
// without one the route itself answers loopback peers only.
inline constexpr const char* role_metrics = "metrics";

struct AccessTokens {
  std::string client;   // "" : client routes are open
  std::string worker;   // "" : worker routes are open
  std::string metrics;  // "" : /metrics is open to loopback peers only
};

class AccessPolicy {
 public:
  explicit AccessPolicy(const AccessTokens& tokens);

  // Whether `role` ("" : public) needs a token.
  bool protects(std::string_view role) const;
  // Nothing when the request may go on; otherwise the answer: 401 with no token or a
  // wrong one, 403 with the other role's token.
  std::optional<HttpResponse> check(std::string_view role, std::string_view authorization) const;

 private:
  std::string client_digest_;  // "" when not set
  std::string worker_digest_;
  std::string metrics_digest_;
};

// The token of "Bearer TOKEN" (the scheme in any case); nothing for any other form.
std::optional<std::string_view> bearer_token(std::string_view authorization);

}  // namespace tessera
