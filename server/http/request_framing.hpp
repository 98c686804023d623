// Whether a request's message can be read without doubt about where it ends (RFC 9112).
// A server and a proxy in front of it that disagree on a body's length let a client hide a
// second request inside the first one's body; so a request whose framing is unusual is
// refused and its connection closed, never guessed at.
#pragma once

#include <cstddef>
#include <optional>
#include <string_view>
#include <vector>

#include "server/http/http_types.hpp"

namespace tessera {

struct HeaderField {
  std::string_view name;
  std::string_view value;
};

// A parsed request header, as views into the parser's message.
struct RequestHead {
  std::string_view method;
  unsigned version = 11;  // 10 for HTTP/1.0, 11 for HTTP/1.1
  std::string_view target;
  std::vector<HeaderField> fields;  // in the order received, repeats kept

  // The first field of that name (case-insensitive), if any.
  std::optional<std::string_view> field(std::string_view name) const;
};

// The raw header, through its blank line, before it is parsed: a folded field line
// (obs-fold, which a parser would silently unfold) is 400, and a request line longer than
// `max_target_bytes` allows is 414. Also for a header cut off at the header limit, where it
// tells a request target too long (414) from a header too large (nullopt: the caller's 431).
std::optional<HttpResponse> raw_header_problem(std::string_view header,
                                               std::size_t max_target_bytes);

// The parsed header: its version, Host and body framing. nullopt when it may be served; an
// answer otherwise, after which the connection must close.
std::optional<HttpResponse> framing_problem(const RequestHead& head, std::size_t max_target_bytes);

}  // namespace tessera
