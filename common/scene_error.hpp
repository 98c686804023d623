#pragma once

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

  const std::string& pointer() const { return pointer_; }
  const std::string& detail() const { return detail_; }

 private:
  std::string pointer_;
  std::string detail_;
};

}  // namespace tessera
