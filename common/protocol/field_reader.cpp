#include "common/protocol/field_reader.hpp"

namespace tessera::protocol {
namespace {

using nlohmann::json;

const char* type_name(const json& value) {
  if (value.is_number_integer()) return "integer";
  return value.type_name();
}

}  // namespace

std::string pointer_key(std::string_view key) {
  std::string escaped;
  for (const char c : key) {
    if (c == '~')
      escaped += "~0";
    else if (c == '/')
      escaped += "~1";
    else
      escaped += c;
  }
  return escaped;
}

FieldReader::FieldReader(const json& object, std::string pointer)
    : object_(object), pointer_(std::move(pointer)) {
  if (!object_.is_object())
    throw ProtocolError(pointer_, std::string("must be an object, got ") + type_name(object_));
}

std::string FieldReader::pointer(std::string_view key) const {
  return pointer_ + "/" + pointer_key(key);
}

void FieldReader::fail(std::string_view key, const std::string& message) const {
  throw ProtocolError(pointer(key), message);
}

const json* FieldReader::find(std::string_view key) const {
  const auto it = object_.find(key);
  return it == object_.end() ? nullptr : &*it;
}

bool FieldReader::has(std::string_view key) const { return find(key) != nullptr; }

const json& FieldReader::required(std::string_view key) const {
  const json* value = find(key);
  if (!value) fail(key, "is required");
  return *value;
}

const json& FieldReader::any(std::string_view key) const { return required(key); }

std::string FieldReader::string(std::string_view key) const {
  const json& value = required(key);
  if (!value.is_string()) fail(key, std::string("must be a string, got ") + type_name(value));
  return value.get<std::string>();
}

std::int64_t FieldReader::integer(std::string_view key, std::int64_t min, std::int64_t max) const {
  const json& value = required(key);
  // A number parsed from text is unsigned when it can be; one built in memory may be either.
  const bool fits = value.is_number_integer() &&
                    (!value.is_number_unsigned() ||
                     value.get<std::uint64_t>() <=
                         static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max()));
  if (!fits || value.get<std::int64_t>() < min || value.get<std::int64_t>() > max) {
    std::string range;
    if (min != std::numeric_limits<std::int64_t>::min() &&
        max != std::numeric_limits<std::int64_t>::max())
      range = " from " + std::to_string(min) + " to " + std::to_string(max);
    else if (min != std::numeric_limits<std::int64_t>::min())
      range = " of at least " + std::to_string(min);
    fail(key, "must be an integer" + range + ", got " +
                  (value.is_number() ? value.dump() : std::string(type_name(value))));
  }
  return value.get<std::int64_t>();
}

std::uint64_t FieldReader::count(std::string_view key) const {
  const json& value = required(key);
  if (value.is_number_unsigned()) return value.get<std::uint64_t>();
  return static_cast<std::uint64_t>(integer(key, 0));
}

double FieldReader::number(std::string_view key) const {
  const json& value = required(key);
  if (!value.is_number()) fail(key, std::string("must be a number, got ") + type_name(value));
  return value.get<double>();
}

bool FieldReader::boolean(std::string_view key) const {
  const json& value = required(key);
  if (!value.is_boolean()) fail(key, std::string("must be true or false, got ") + type_name(value));
  return value.get<bool>();
}

FieldReader FieldReader::object(std::string_view key) const {
  return FieldReader(required(key), pointer(key));
}

const json& FieldReader::array(std::string_view key) const {
  const json& value = required(key);
  if (!value.is_array()) fail(key, std::string("must be an array, got ") + type_name(value));
  return value;
}

std::optional<std::string> FieldReader::nullable_string(std::string_view key) const {
  if (required(key).is_null()) return std::nullopt;
  return string(key);
}

std::optional<std::int64_t> FieldReader::nullable_integer(std::string_view key) const {
  if (required(key).is_null()) return std::nullopt;
  return integer(key);
}

std::optional<double> FieldReader::nullable_number(std::string_view key) const {
  if (required(key).is_null()) return std::nullopt;
  return number(key);
}

std::optional<std::string> FieldReader::optional_string(std::string_view key) const {
  if (!has(key)) return std::nullopt;
  return string(key);
}

std::optional<std::int64_t> FieldReader::optional_integer(std::string_view key, std::int64_t min,
                                                          std::int64_t max) const {
  if (!has(key)) return std::nullopt;
  return integer(key, min, max);
}

void FieldReader::only(std::initializer_list<std::string_view> keys) const {
  only(std::span<const std::string_view>(keys.begin(), keys.size()));
}

void FieldReader::only(std::span<const std::string_view> keys) const {
  for (const auto& [key, value] : object_.items()) {
    bool known = false;
    for (const std::string_view k : keys) known = known || k == key;
    if (known) continue;
    std::string expected;
    for (const std::string_view k : keys)
      expected += (expected.empty() ? "" : ", ") + std::string(k);
    fail(key, "unknown key \"" + key + "\" (expected " + expected + ")");
  }
}

}  // namespace tessera::protocol
