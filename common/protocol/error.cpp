#include "common/protocol/error.hpp"

namespace tessera::protocol {

Error Error::read(const FieldReader& body) {
  const FieldReader error = body.object("error");
  Error e;
  e.code = error.string("code");
  e.message = error.string("message");
  e.path = error.optional_string("path");
  e.limit = error.optional_string("limit");
  if (error.has("limit_value")) e.limit_value = error.count("limit_value");
  return e;
}

nlohmann::json to_json(const Error& e) {
  nlohmann::json error = {{"code", e.code}, {"message", e.message}};
  if (e.path) error["path"] = *e.path;
  if (e.limit) error["limit"] = *e.limit;
  if (e.limit_value) error["limit_value"] = *e.limit_value;
  return {{"error", std::move(error)}};
}

std::optional<Error> error_of(std::string_view body) {
  const nlohmann::json parsed = nlohmann::json::parse(body, nullptr, false);
  if (parsed.is_discarded()) return std::nullopt;
  try {
    return Error::read(FieldReader(parsed));
  } catch (const ProtocolError&) {
    return std::nullopt;
  }
}

std::string error_message(int status, std::string_view body) {
  if (auto error = error_of(body)) return error->message;
  return "HTTP " + std::to_string(status) + ": " + std::string(body.substr(0, 200));
}

}  // namespace tessera::protocol
