#include "common/protocol/health.hpp"

namespace tessera::protocol {
namespace {

void expect_status(const FieldReader& body, const char* status) {
  if (body.string("status") != status) body.fail("status", std::string("must be ") + status);
}

}  // namespace

Health Health::read(const FieldReader& body) {
  expect_status(body, "ok");
  return {};
}
nlohmann::json to_json(const Health&) { return {{"status", "ok"}}; }

Ready Ready::read(const FieldReader& body) {
  expect_status(body, "ready");
  return {};
}
nlohmann::json to_json(const Ready&) { return {{"status", "ready"}}; }

}  // namespace tessera::protocol
