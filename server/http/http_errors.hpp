// The answers the HTTP layer gives itself, before any route sees a request.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>

#include "server/http/http_types.hpp"

namespace tessera {

// A status whose answer never has a body (RFC 9110): 1xx, 204 and 304.
inline bool has_no_body(int status) { return status < 200 || status == 204 || status == 304; }

// 431: the request's header is over `max_header_bytes`.
HttpResponse header_too_large(std::size_t max_header_bytes);
// 400: the request does not parse as HTTP; `why` is the parser's word.
HttpResponse malformed_request(const std::string& why);
// 413, naming the limit and, when the request announced it, the body's size: a worker over
// a limit must be told by how much, not only that it is.
HttpResponse body_too_large(std::optional<std::uint64_t> announced, std::size_t limit);

}  // namespace tessera
