// A moment as RFC 3339 in UTC with milliseconds, e.g. 2026-11-22T01:02:03.456Z: how the
// API writes times (protocol/timestamp.hpp) and how JSON log lines do (log_lines.hpp).
#pragma once

#include <cstdint>
#include <string>

namespace tessera {

std::string rfc3339_utc(std::int64_t ms_since_epoch);

}  // namespace tessera
