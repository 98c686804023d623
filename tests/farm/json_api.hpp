// The farm tests' view of the API: every call goes through the typed client of common/net
// (its URLs, bodies and errors), and the answer comes back as the JSON the protocol type
// writes, which the tests inspect like a user reading `tessera status --json`.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "common/net/coordinator_client.hpp"
#include "common/protocol/image_format.hpp"
#include "tests/farm/contract_check.hpp"

namespace tessera::test {

class JsonApi {
 public:
  explicit JsonApi(const std::string& url, const std::string& token = "") : client_(url, token) {
    client_.observe(contract_observer());
  }

  nlohmann::json submit(const std::string& name, int priority, const nlohmann::json& scene) {
    return protocol::to_json(client_.submit({name, priority, scene, std::nullopt}));
  }
  nlohmann::json job(const std::string& id, double wait_s = 0) {
    return protocol::to_json(client_.job(id, wait_s));
  }
  // `state` "" for every state.
  nlohmann::json jobs(const std::string& state, int limit) {
    return protocol::to_json(
        client_.jobs(state.empty() ? std::nullopt : job_state_from_string(state), limit));
  }
  nlohmann::json cancel(const std::string& id) { return protocol::to_json(client_.cancel(id)); }
  void remove(const std::string& id) { client_.remove(id); }
  std::string image(const std::string& id, const std::string& format, bool partial) {
    const ImageFormat* named = image_format_named(format);
    if (!named) throw std::invalid_argument("no image format " + format);
    return client_.image(id, *named, partial);
  }
  nlohmann::json workers() { return protocol::to_json(client_.workers()); }
  nlohmann::json pause(const std::string& id) { return protocol::to_json(client_.pause(id)); }
  nlohmann::json resume(const std::string& id) { return protocol::to_json(client_.resume(id)); }
  nlohmann::json retry(const std::string& id) { return protocol::to_json(client_.retry(id)); }
  nlohmann::json set_priority(const std::string& id, int priority) {
    return protocol::to_json(client_.change(id, {priority}));
  }
  nlohmann::json drain(const std::string& worker, bool draining) {
    return protocol::to_json(client_.drain(worker, draining));
  }
  void remove_worker(const std::string& worker) { client_.remove_worker(worker); }
  CoordinatorClient& client() { return client_; }

 private:
  CoordinatorClient client_;
};

}  // namespace tessera::test
