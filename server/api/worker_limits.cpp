#include "server/api/worker_limits.hpp"

#include "common/protocol/leases.hpp"
#include "common/protocol/paths.hpp"

namespace tessera {

ProtocolLimits protocol_limits(const ApiContext& context) {
  ProtocolLimits limits = coordinator_limits(context.limits.max_tile_size);
  limits.max_lease_tiles = context.scheduler.config().max_lease_tiles;
  return limits;
}

std::optional<int> max_tiles_of(const ApiContext& context, const HttpRequest& request) {
  const auto it = request.query.find(std::string(protocol::query::max_tiles));
  if (it == request.query.end()) return 1;
  const auto parsed = protocol::parse_number_list(it->second);
  if (!parsed || parsed->size() != 1 || parsed->front() < 1 ||
      parsed->front() > static_cast<std::uint64_t>(protocol_limits(context).max_batch_tiles))
    return std::nullopt;
  return static_cast<int>(parsed->front());
}

HttpResponse bad_max_tiles(const ApiContext& context) {
  return error_response(400, "invalid_request",
                        "max_tiles must be an integer from 1 to " +
                            std::to_string(protocol_limits(context).max_batch_tiles));
}

}  // namespace tessera
