#include "common/protocol/paths.hpp"

#include <cctype>
#include <cstdio>

namespace tessera::protocol {
namespace {

// RFC 3986's unreserved characters stay; every other byte is %XX.
std::string percent_encode(std::string_view text) {
  std::string encoded;
  for (const char c : text) {
    const auto u = static_cast<unsigned char>(c);
    if (std::isalnum(u) || c == '-' || c == '.' || c == '_' || c == '~') {
      encoded += c;
    } else {
      char hex[4];
      std::snprintf(hex, sizeof hex, "%%%02X", u);
      encoded += hex;
    }
  }
  return encoded;
}

// A number as the query gives it: no trailing zeros, "0.5" rather than "0.500000".
std::string decimal(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3f", value);
  std::string s = text;
  s.erase(s.find_last_not_of('0') + 1);
  if (s.back() == '.') s.pop_back();
  return s;
}

std::string with(std::string_view name, std::string_view value) {
  return std::string(name) + "=" + percent_encode(value);
}

}  // namespace

std::string_view parameter_of(std::string_view pattern) {
  const std::size_t open = pattern.find('{');
  const std::size_t close = pattern.find('}', open);
  if (open == pattern.npos || close == pattern.npos) return {};
  return pattern.substr(open + 1, close - open - 1);
}

std::string fill(std::string_view pattern, std::string_view value) {
  const std::size_t open = pattern.find('{');
  const std::size_t close = pattern.find('}', open);
  if (open == pattern.npos || close == pattern.npos) return std::string(pattern);
  return std::string(pattern.substr(0, open)) + percent_encode(value) +
         std::string(pattern.substr(close + 1));
}

std::string job_target(std::string_view id, double wait_s) {
  std::string target = fill(route::job, id);
  if (wait_s > 0) target += "?" + with(query::wait_s, decimal(wait_s));
  return target;
}

std::string jobs_target(std::optional<JobState> state, int limit) {
  std::string target = std::string(route::jobs) + "?" + with(query::limit, std::to_string(limit));
  if (state) target += "&" + with(query::state, name_in(kJobStateNames, *state));
  return target;
}

std::string jobs_with_prefix_target(std::string_view prefix, int limit) {
  return std::string(route::jobs) + "?" + with(query::limit, std::to_string(limit)) + "&" +
         with(query::id_prefix, prefix);
}

std::string jobs_named_target(std::string_view name, int limit) {
  return std::string(route::jobs) + "?" + with(query::limit, std::to_string(limit)) + "&" +
         with(query::name, name);
}

std::string image_target(std::string_view id, const ImageFormat& format, bool partial) {
  std::string target = fill(route::job_image, id) + "?" + with(query::format, format.name);
  if (partial) target += "&" + with(query::partial, "1");
  return target;
}

std::string frame_image_target(std::string_view id, int frame, const ImageFormat& format,
                               bool partial) {
  const std::string frames = fill(route::job_frames, id);
  std::string target =
      frames + "/" + std::to_string(frame) + "/image?" + with(query::format, format.name);
  if (partial) target += "&" + with(query::partial, "1");
  return target;
}

std::string claim_target(std::string_view worker, double wait_s, int max_tiles) {
  return fill(route::worker_claim, worker) + "?" + with(query::wait_s, decimal(wait_s)) + "&" +
         with(query::max_tiles, std::to_string(max_tiles));
}

std::string extend_target(std::string_view lease, int max_tiles) {
  return fill(route::lease_extend, lease) + "?" + with(query::max_tiles, std::to_string(max_tiles));
}

}  // namespace tessera::protocol
