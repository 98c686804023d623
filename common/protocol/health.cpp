#include "common/protocol/health.hpp"

namespace tessera::protocol {
namespace {

void expect_status(const FieldReader& body, const char* status) {
  if (body.string("status") != status) body.fail("status", std::string("must be ") + status);
}

}  // namespace

Health Health::read(const FieldReader& body) {
  expect_status(body, "ok");
  Health health;
  // Absent from coordinators before it was added.
  if (body.has("api_token_required"))
    health.api_token_required = body.boolean("api_token_required");
  return health;
}
nlohmann::json to_json(const Health& health) {
  return {{"status", "ok"}, {"api_token_required", health.api_token_required}};
}

Ready Ready::read(const FieldReader& body) {
  expect_status(body, "ready");
  return {};
}
nlohmann::json to_json(const Ready&) { return {{"status", "ready"}}; }

}  // namespace tessera::protocol
