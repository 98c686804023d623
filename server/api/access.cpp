#include "server/api/access.hpp"

#include <cctype>

#include <openssl/crypto.h>

#include "server/farm/ids.hpp"

namespace tessera {
namespace {

// Digests of equal length, compared without an early exit: the time taken says nothing
// about how much of a guess was right.
bool same_digest(const std::string& a, const std::string& b) {
  return a.size() == b.size() && CRYPTO_memcmp(a.data(), b.data(), a.size()) == 0;
}

HttpResponse unauthorized(std::string code, std::string message) {
  HttpResponse response = error_response(401, std::move(code), std::move(message));
  response.headers.emplace_back("WWW-Authenticate", "Bearer realm=\"tessera\"");
  return response;
}

}  // namespace

std::optional<std::string_view> bearer_token(std::string_view authorization) {
  constexpr std::string_view scheme = "bearer ";
  if (authorization.size() <= scheme.size()) return std::nullopt;
  for (std::size_t i = 0; i < scheme.size(); ++i)
    if (std::tolower(static_cast<unsigned char>(authorization[i])) != scheme[i])
      return std::nullopt;
  std::string_view token = authorization.substr(scheme.size());
  while (!token.empty() && token.front() == ' ') token.remove_prefix(1);
  while (!token.empty() && token.back() == ' ') token.remove_suffix(1);
  if (token.empty()) return std::nullopt;
  return token;
}

AccessPolicy::AccessPolicy(const AccessTokens& tokens)
    : client_digest_(tokens.client.empty() ? "" : sha256_hex(tokens.client)),
      worker_digest_(tokens.worker.empty() ? "" : sha256_hex(tokens.worker)),
      metrics_digest_(tokens.metrics.empty() ? "" : sha256_hex(tokens.metrics)) {}

bool AccessPolicy::protects(std::string_view role) const {
  if (role == role_client) return !client_digest_.empty();
  if (role == role_worker) return !worker_digest_.empty();
  if (role == role_metrics) return !metrics_digest_.empty();
  return false;
}

namespace {

// How a role's token is named to people: the client role's is the API token.
std::string token_name(std::string_view role) {
  return role == role_client ? "API token" : std::string(role) + " token";
}

}  // namespace

std::optional<HttpResponse> AccessPolicy::check(std::string_view role,
                                                std::string_view authorization) const {
  if (!protects(role)) return std::nullopt;
  const auto token = bearer_token(authorization);
  if (!token)
    return unauthorized("missing_token", "this route needs the " + token_name(role) +
                                             ": send Authorization: Bearer TOKEN");
  const std::string digest = sha256_hex(*token);
  if (role == role_metrics) {
    if (same_digest(digest, metrics_digest_)) return std::nullopt;
    return unauthorized("invalid_token", "the token is not this server's metrics token");
  }
  const std::string& wanted = role == role_client ? client_digest_ : worker_digest_;
  const std::string& other = role == role_client ? worker_digest_ : client_digest_;
  if (same_digest(digest, wanted)) return std::nullopt;
  if (!other.empty() && same_digest(digest, other))
    return error_response(403, "wrong_role",
                          "the " + token_name(role == role_client ? role_worker : role_client) +
                              " cannot be used here; this route needs the " + token_name(role));
  return unauthorized("invalid_token", "the token is not valid for this server");
}

}  // namespace tessera
