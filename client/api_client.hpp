// The coordinator's public API (docs/openapi.yaml) from the client's side.
#pragma once

#include <stdexcept>
#include <string>

#include <nlohmann/json.hpp>

#include "client/http_client.hpp"

namespace tessera {

// An error answer of the API: status and the {"error": {...}} body.
class ApiError : public std::runtime_error {
 public:
  ApiError(int status, std::string code, const std::string& message, std::string path)
      : std::runtime_error(message), status_(status), code_(std::move(code)), path_(std::move(path)) {}
  int status() const { return status_; }
  const std::string& code() const { return code_; }
  const std::string& path() const { return path_; }

 private:
  int status_;
  std::string code_;
  std::string path_;
};

class ApiClient {
 public:
  // `token`: the API token to send, "" for none.
  explicit ApiClient(const std::string& server_url, const std::string& token = "");

  nlohmann::json submit(const std::string& name, int priority, const nlohmann::json& scene);
  // With `wait_s` > 0 the server answers once the job has finished, or after wait_s.
  nlohmann::json job(const std::string& id, double wait_s = 0);
  nlohmann::json jobs(const std::string& state, int limit);
  nlohmann::json cancel(const std::string& id);
  void remove(const std::string& id);
  std::string image(const std::string& id, const std::string& format, bool partial);
  nlohmann::json workers();

 private:
  HttpResult call(const std::string& method, const std::string& target, const std::string& body = "");
  HttpClient http_;
};

}  // namespace tessera
