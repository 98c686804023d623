// Times on the wire: RFC 3339 in UTC with milliseconds, e.g. 2026-11-22T01:02:03.456Z.
#pragma once

#include <cstdint>
#include <string>

namespace tessera::protocol {

std::string format_timestamp(std::int64_t ms_since_epoch);

}  // namespace tessera::protocol
