#include "server/http/http_errors.hpp"

#include "common/protocol/limits.hpp"

namespace tessera {

HttpResponse header_too_large(std::size_t max_header_bytes) {
  return error_response(
      431, "header_too_large",
      "the request header exceeds " + std::to_string(max_header_bytes) + " bytes");
}

HttpResponse malformed_request(const std::string& why) {
  return error_response(400, "bad_request", "malformed HTTP request: " + why);
}

HttpResponse body_too_large(std::optional<std::uint64_t> announced, std::size_t limit) {
  return error_response(
      413, "body_too_large",
      "the request body " +
          (announced ? "of " + with_thousands(*announced) + " bytes " : std::string()) +
          "exceeds this route's limit of " + with_thousands(limit) + " bytes");
}

}  // namespace tessera
