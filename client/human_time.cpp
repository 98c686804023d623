#include "client/human_time.hpp"

#include <chrono>

#include "common/protocol/timestamp.hpp"

namespace tessera {

std::string time_ago(std::int64_t then_ms, std::int64_t now_ms) {
  const std::int64_t s = (now_ms - then_ms) / 1000;
  if (s < 10) return "just now";
  if (s < 60) return std::to_string(s) + " s ago";
  if (s < 3600) return std::to_string(s / 60) + " min ago";
  if (s < 48 * 3600) return std::to_string(s / 3600) + " h ago";
  return std::to_string(s / 86400) + " days ago";
}

std::string time_ago(std::string_view rfc3339, std::int64_t now) {
  const auto then = protocol::parse_timestamp(rfc3339);
  return then ? time_ago(*then, now) : std::string(rfc3339);
}

std::int64_t now_ms() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

}  // namespace tessera
