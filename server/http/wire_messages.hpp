// Between Beast's messages and the plain structs that handlers and checks see: a parsed
// request as a RequestHead and an HttpRequest, and an HttpResponse as the message that
// goes on the wire.
#pragma once

#include <utility>  // before Asio: Boost 1.74 with GCC 12 in C++20 needs it

#include <string_view>
#include <variant>

#include <boost/beast/http/file_body.hpp>
#include <boost/beast/http/message.hpp>
#include <boost/beast/http/string_body.hpp>

#include "server/http/http_types.hpp"
#include "server/http/request_framing.hpp"

namespace tessera {

using BeastRequest = boost::beast::http::request<boost::beast::http::string_body>;
using StringMessage = boost::beast::http::response<boost::beast::http::string_body>;
using FileMessage = boost::beast::http::response<boost::beast::http::file_body>;
using WireMessage = std::variant<StringMessage, FileMessage>;

// Views into `request`, for the framing checks.
RequestHead head_of(const BeastRequest& request);

// The method, the header fields (names in lower case, repeats joined with ", ") and the
// body, which is moved out of `request`.
HttpRequest plain_request(BeastRequest& request);

// A file answer is opened here, so that a temporary one can leave its directory at once:
// the open descriptor keeps its bytes until they are sent. One that cannot be opened
// becomes a 500, logged with `where` (the route). The answer to a HEAD (`head_only`)
// announces the length its GET's body would have, and carries none.
// The header of a streamed response (HttpResponse::stream), as text: no length, no chunks,
// "Connection: close", since its body runs until the connection ends.
std::string stream_header(const HttpResponse& response);

WireMessage response_message(HttpResponse response, bool head_only, bool close_after,
                             std::string_view where);

}  // namespace tessera
