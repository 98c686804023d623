// Times as people read them in a listing: "just now", "42 s ago", "3 min ago".
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

namespace tessera {

// How long before `now_ms` the moment `then_ms` was; a moment after now (clocks that
// disagree) is "just now".
std::string time_ago(std::int64_t then_ms, std::int64_t now_ms);
// The same for an RFC 3339 time of the API; the text itself when it is not one.
std::string time_ago(std::string_view rfc3339, std::int64_t now_ms);
// The milliseconds since the epoch now, by the system clock.
std::int64_t now_ms();

}  // namespace tessera
