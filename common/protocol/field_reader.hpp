// Reading one JSON object of the protocol, field by field, with errors that say where (a
// JSON Pointer) and what. Every body of docs/openapi.yaml is read through this, on both
// sides: the coordinator reads requests, the clients read answers.
#pragma once

#include <cstdint>
#include <initializer_list>
#include <limits>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

namespace tessera::protocol {

// A body that does not have the protocol's shape: the field's JSON Pointer (empty for the
// body itself) and what is wrong with it.
class ProtocolError : public std::runtime_error {
 public:
  ProtocolError(std::string pointer, std::string message)
      : std::runtime_error(pointer.empty() ? message : pointer + ": " + message),
        pointer_(std::move(pointer)),
        message_(std::move(message)) {}
  const std::string& pointer() const { return pointer_; }
  const std::string& message() const { return message_; }

 private:
  std::string pointer_;
  std::string message_;
};

// "a/b" -> "a~1b", as RFC 6901 escapes a key in a pointer.
std::string pointer_key(std::string_view key);

class FieldReader {
 public:
  // Throws ProtocolError unless `object` is a JSON object. `pointer` is where it lies in
  // the body, for the errors.
  explicit FieldReader(const nlohmann::json& object, std::string pointer = "");

  // Required fields: missing, null or of another type is an error.
  std::string string(std::string_view key) const;
  std::int64_t integer(std::string_view key,
                       std::int64_t min = std::numeric_limits<std::int64_t>::min(),
                       std::int64_t max = std::numeric_limits<std::int64_t>::max()) const;
  std::uint64_t count(std::string_view key) const;  // a whole number from 0
  double number(std::string_view key) const;
  bool boolean(std::string_view key) const;
  FieldReader object(std::string_view key) const;
  const nlohmann::json& array(std::string_view key) const;
  const nlohmann::json& any(std::string_view key) const;

  // Required fields that may be null (`nullable: true`): null reads as nothing.
  std::optional<std::string> nullable_string(std::string_view key) const;
  std::optional<std::int64_t> nullable_integer(std::string_view key) const;
  std::optional<double> nullable_number(std::string_view key) const;

  // Optional fields: absent reads as nothing; present must be of the type.
  std::optional<std::string> optional_string(std::string_view key) const;
  std::optional<std::int64_t> optional_integer(
      std::string_view key, std::int64_t min = std::numeric_limits<std::int64_t>::min(),
      std::int64_t max = std::numeric_limits<std::int64_t>::max()) const;

  // Refuses any key but these: "unknown key "x" (expected a, b, c)".
  void only(std::initializer_list<std::string_view> keys) const;
  void only(std::span<const std::string_view> keys) const;
  bool has(std::string_view key) const;
  // The pointer of a field of this object.
  std::string pointer(std::string_view key) const;
  // An error about a field of this object.
  [[noreturn]] void fail(std::string_view key, const std::string& message) const;

 private:
  const nlohmann::json& required(std::string_view key) const;
  const nlohmann::json* find(std::string_view key) const;

  const nlohmann::json& object_;
  std::string pointer_;
};

// Reads an array of objects with `read` (FieldReader -> T), each at its own pointer.
template <typename T, typename Read>
std::vector<T> read_array(const FieldReader& parent, std::string_view key, Read read) {
  const nlohmann::json& items = parent.array(key);
  std::vector<T> values;
  values.reserve(items.size());
  for (std::size_t i = 0; i < items.size(); ++i)
    values.push_back(read(FieldReader(items[i], parent.pointer(key) + "/" + std::to_string(i))));
  return values;
}

}  // namespace tessera::protocol

namespace tessera::protocol {

// A whole body of type T (T::read), from its text. Throws ProtocolError, for text that is
// not JSON too.
template <typename T>
T read_body(std::string_view text) {
  const nlohmann::json body = nlohmann::json::parse(text, nullptr, false);
  if (body.is_discarded())
    throw ProtocolError("", "the body is not JSON: " + std::string(text.substr(0, 200)));
  return T::read(FieldReader(body));
}

}  // namespace tessera::protocol
