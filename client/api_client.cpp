#include "client/api_client.hpp"

#include <chrono>

namespace tessera {

using nlohmann::json;

ApiClient::ApiClient(const std::string& server_url, const std::string& token)
    : http_(server_url, std::chrono::seconds(60)) {
  http_.set_bearer_token(token);
}

HttpResult ApiClient::call(const std::string& method, const std::string& target,
                           const std::string& body) {
  HttpResult result = http_.request(method, target, body);
  if (result.status < 400) return result;
  const json error = json::parse(result.body, nullptr, false);
  if (error.is_object() && error.contains("error") && error["error"].is_object()) {
    const json& e = error["error"];
    throw ApiError(result.status, e.value("code", ""), e.value("message", result.body),
                   e.value("path", ""));
  }
  throw ApiError(result.status, "", "HTTP " + std::to_string(result.status) + ": " + result.body, "");
}

json ApiClient::submit(const std::string& name, int priority, const json& scene) {
  const json body = {{"name", name}, {"priority", priority}, {"scene", scene}};
  return json::parse(call("POST", "/v1/jobs", body.dump()).body);
}

json ApiClient::job(const std::string& id, double wait_s) {
  std::string target = "/v1/jobs/" + id;
  if (wait_s > 0) target += "?wait_s=" + std::to_string(wait_s);
  return json::parse(call("GET", target).body);
}

json ApiClient::jobs(const std::string& state, int limit) {
  std::string target = "/v1/jobs?limit=" + std::to_string(limit);
  if (!state.empty()) target += "&state=" + state;
  return json::parse(call("GET", target).body);
}

json ApiClient::cancel(const std::string& id) {
  return json::parse(call("POST", "/v1/jobs/" + id + "/cancel").body);
}

void ApiClient::remove(const std::string& id) { call("DELETE", "/v1/jobs/" + id); }

std::string ApiClient::image(const std::string& id, const std::string& format, bool partial) {
  return call("GET", "/v1/jobs/" + id + "/image?format=" + format + (partial ? "&partial=1" : ""))
      .body;
}

json ApiClient::workers() { return json::parse(call("GET", "/v1/workers").body); }

}  // namespace tessera
