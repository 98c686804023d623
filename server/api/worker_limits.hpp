// What this coordinator's worker protocol allows (common/protocol/limits.hpp), as stated
// at registration and checked by the worker and lease routes.
#pragma once

#include <optional>

#include "common/protocol/limits.hpp"
#include "server/api/api_routes.hpp"
#include "server/http/http_types.hpp"

namespace tessera {

ProtocolLimits protocol_limits(const ApiContext& context);

// A claim's or an extension's ?max_tiles= (1 when absent), or nothing when it is out of
// range; bad_max_tiles() is the answer then.
std::optional<int> max_tiles_of(const ApiContext& context, const HttpRequest& request);
HttpResponse bad_max_tiles(const ApiContext& context);

}  // namespace tessera
