#include "server/api/worker_identity.hpp"

#include <variant>

#include "common/protocol/workers.hpp"
#include "server/farm/ids.hpp"

namespace tessera {
namespace {

constexpr const char* wrong_worker = "wrong_worker";

// The worker the request's secret proves, or the answer that refuses it.
std::variant<std::string, HttpResponse> prover(const Scheduler& scheduler,
                                               const HttpRequest& request) {
  const auto header = request.headers.find(ascii_lower(protocol::kWorkerSecretHeader));
  if (header == request.headers.end() || header->second.empty())
    return error_response(401, "missing_worker_secret",
                          "worker calls must send the secret their registration gave, in " +
                              std::string(protocol::kWorkerSecretHeader));
  if (auto worker = scheduler.worker_with_secret(worker_secret_digest(header->second)))
    return std::move(*worker);
  return error_response(403, wrong_worker,
                        "the worker secret is not that of any registered worker; register again");
}

}  // namespace

std::string new_worker_secret() { return random_hex(64); }

std::string worker_secret_digest(std::string_view secret) { return sha256_hex(secret); }

std::optional<HttpResponse> check_worker(const Scheduler& scheduler, const HttpRequest& request,
                                         const std::string& worker_id) {
  auto caller = prover(scheduler, request);
  if (auto* refused = std::get_if<HttpResponse>(&caller)) return std::move(*refused);
  if (std::get<std::string>(caller) == worker_id) return std::nullopt;
  return error_response(403, wrong_worker, "the worker secret is not worker " + worker_id + "'s");
}

std::optional<HttpResponse> check_lease_holder(const Scheduler& scheduler,
                                               const HttpRequest& request,
                                               const std::string& lease_id) {
  auto caller = prover(scheduler, request);
  if (auto* refused = std::get_if<HttpResponse>(&caller)) return std::move(*refused);
  const auto holder = scheduler.lease_holder(lease_id);
  if (!holder || *holder == std::get<std::string>(caller)) return std::nullopt;
  return error_response(403, wrong_worker, "lease " + lease_id + " is held by another worker");
}

std::optional<HttpResponse> check_any_worker(const Scheduler& scheduler,
                                             const HttpRequest& request) {
  auto caller = prover(scheduler, request);
  if (auto* refused = std::get_if<HttpResponse>(&caller)) return std::move(*refused);
  return std::nullopt;
}

}  // namespace tessera
