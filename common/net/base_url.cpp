// A coordinator's base URL, as --server and $TESSERA_SERVER give it (common/net/http_client.hpp).
#include <charconv>
#include <string>

#include "common/net/http_client.hpp"
#include "common/text/ascii_case.hpp"

namespace tessera {
namespace {

[[noreturn]] void bad_url(std::string_view url, std::string_view why) {
  throw BadServerUrl("invalid server URL \"" + std::string(url) + "\": " + std::string(why));
}

}  // namespace

BaseUrl parse_base_url(std::string_view url) {
  BaseUrl result;
  // A bare "host:port" means http://, as for curl.
  const std::size_t scheme_end = url.find("://");
  if (scheme_end != std::string_view::npos) {
    const std::string scheme = ascii_lower(url.substr(0, scheme_end));
    if (scheme != "http" && scheme != "https")
      bad_url(url, "expected http://host[:port] or https://host[:port]");
    result.tls = scheme == "https";
    if (result.tls) result.port = 443;
  }
  std::string_view authority =
      scheme_end == std::string_view::npos ? url : url.substr(scheme_end + 3);
  const std::size_t slash = authority.find('/');
  if (slash != std::string_view::npos) {
    if (authority.substr(slash) != "/")
      bad_url(url, "a path is not allowed; expected http://host[:port]");
    authority = authority.substr(0, slash);
  }

  std::string_view port_text;
  if (authority.starts_with('[')) {  // IPv6 literal
    const std::size_t close = authority.find(']');
    if (close == std::string_view::npos) bad_url(url, "unterminated [IPv6 address]");
    result.host = std::string(authority.substr(1, close - 1));
    const std::string_view after = authority.substr(close + 1);
    if (!after.empty()) {
      if (after.front() != ':') bad_url(url, "expected :port after ]");
      port_text = after.substr(1);
      if (port_text.empty()) bad_url(url, "empty port");
    }
  } else {
    const std::size_t colon = authority.find(':');
    result.host = std::string(authority.substr(0, colon));
    if (colon != std::string_view::npos) {
      port_text = authority.substr(colon + 1);
      if (port_text.empty()) bad_url(url, "empty port");
    }
  }
  if (result.host.empty()) bad_url(url, "no host");
  if (result.host.find('@') != std::string::npos) bad_url(url, "user information is not supported");
  if (!port_text.empty()) {
    unsigned value = 0;
    const auto [end, ec] =
        std::from_chars(port_text.data(), port_text.data() + port_text.size(), value);
    if (ec != std::errc() || end != port_text.data() + port_text.size() || value == 0 ||
        value > 65535)
      bad_url(url, "the port must be a number from 1 to 65535");
    result.port = static_cast<std::uint16_t>(value);
  }
  return result;
}

}  // namespace tessera
