#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>

namespace tessera {

// A scene that breaks a rule. `pointer` is the JSON Pointer (RFC 6901) of the offending
// value, "" for the document itself; `detail` says what was expected and what was found.
class SceneError : public std::runtime_error {
 public:
  SceneError(std::string pointer, std::string detail)
      : std::runtime_error((pointer.empty() ? std::string("/") : pointer) + ": " + detail),
        pointer_(std::move(pointer)),
        detail_(std::move(detail)) {}
  // A scene that is valid but costs more than a Limits member allows.
  SceneError(std::string pointer, std::string detail, std::string limit, std::uint64_t limit_value)
      : SceneError(std::move(pointer), std::move(detail)) {
    limit_ = std::move(limit);
    limit_value_ = limit_value;
  }

  const std::string& pointer() const { return pointer_; }
  const std::string& detail() const { return detail_; }
  // The Limits member that was exceeded ("max_samples_per_pixel"), "" for any other error.
  const std::string& limit() const { return limit_; }
  std::uint64_t limit_value() const { return limit_value_; }

 private:
  std::string pointer_;
  std::string detail_;
  std::string limit_;
  std::uint64_t limit_value_ = 0;
};

}  // namespace tessera
