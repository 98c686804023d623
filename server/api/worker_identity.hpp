// Which worker a request comes from. The worker token (access.hpp) says only that the
// caller may be some worker; the secret its registration gave it, sent back with each later
// call (protocol::kWorkerSecretHeader), says which one. Without it any holder of the worker
// token could upload to, or release, another worker's lease.
#pragma once

#include <optional>
#include <string>

#include "server/farm/scheduler.hpp"
#include "server/http/http_types.hpp"

namespace tessera {

// A new worker's secret: 256 random bits as hex, returned once; and the digest of one,
// which is all the coordinator keeps.
std::string new_worker_secret();
std::string worker_secret_digest(std::string_view secret);

// Each gives nothing when the request may go on, or the answer that refuses it: 401 when
// it carries no secret, 403 when the secret is not the right worker's.

// The caller is worker `worker_id`.
std::optional<HttpResponse> check_worker(const Scheduler& scheduler, const HttpRequest& request,
                                         const std::string& worker_id);
// The caller holds lease `lease_id`. Nothing also when the lease is not live: the route
// then answers that it is lost, whoever asks.
std::optional<HttpResponse> check_lease_holder(const Scheduler& scheduler,
                                               const HttpRequest& request,
                                               const std::string& lease_id);
// The caller is some registered worker that has not left.
std::optional<HttpResponse> check_any_worker(const Scheduler& scheduler,
                                             const HttpRequest& request);

}  // namespace tessera
