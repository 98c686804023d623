// Times on the wire: RFC 3339 in UTC with milliseconds, e.g. 2026-11-22T01:02:03.456Z.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace tessera::protocol {

std::string format_timestamp(std::int64_t ms_since_epoch);
// The milliseconds since the epoch of a time as format_timestamp() writes it (the fraction
// optional); nothing for any other text.
std::optional<std::int64_t> parse_timestamp(std::string_view text);

}  // namespace tessera::protocol
