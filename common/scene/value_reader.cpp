#include "common/scene/value_reader.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>

#include "common/text/suggest.hpp"

namespace tessera {

using nlohmann::json;

bool Range::contains(double value) const {
  if (min && (min_open ? !(value > *min) : !(value >= *min))) return false;
  if (max && (max_open ? !(value < *max) : !(value <= *max))) return false;
  return true;
}

std::string Range::describe() const {
  if (min && max) {
    return std::string("in ") + (min_open ? "(" : "[") + format_number(*min) + ", " +
           format_number(*max) + (max_open ? ")" : "]");
  }
  if (min) return std::string(min_open ? "> " : ">= ") + format_number(*min);
  if (max) return std::string(max_open ? "< " : "<= ") + format_number(*max);
  return "any number";
}

std::string pointer_token(std::string_view key) {
  std::string token;
  token.reserve(key.size());
  for (char c : key) {
    if (c == '~')
      token += "~0";
    else if (c == '/')
      token += "~1";
    else
      token += c;
  }
  return token;
}

std::string quote(std::string_view text) {
  // Replacing invalid UTF-8 keeps a message about a bad name from throwing itself.
  return json(std::string(text)).dump(-1, ' ', false, json::error_handler_t::replace);
}

std::string quoted_list(std::span<const std::string_view> words) {
  std::string list;
  for (std::string_view word : words) {
    if (!list.empty()) list += ", ";
    list += quote(word);
  }
  return list;
}

std::string format_number(double value) {
  if (std::isnan(value)) return "nan";
  if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
  char buffer[64];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  return std::string(buffer, result.ptr);
}

std::string describe(const json& value) {
  constexpr std::size_t max_string = 40;
  switch (value.type()) {
    case json::value_t::number_integer:
      return std::to_string(value.get<std::int64_t>());
    case json::value_t::number_unsigned:
      return std::to_string(value.get<std::uint64_t>());
    case json::value_t::number_float:
      return format_number(value.get<double>());
    case json::value_t::string: {
      const auto& text = value.get_ref<const std::string&>();
      if (text.size() <= max_string) return quote(text);
      return quote(text.substr(0, max_string)) + "...";
    }
    case json::value_t::boolean:
      return value.get<bool>() ? "true" : "false";
    case json::value_t::array:
      return "an array of " + std::to_string(value.size()) +
             (value.size() == 1 ? " element" : " elements");
    case json::value_t::object:
      return "an object";
    default:
      return value.type_name();
  }
}

std::optional<Vec3> try_normalize(const Vec3& v) {
  const double scale = std::max({std::abs(v.x), std::abs(v.y), std::abs(v.z)});
  if (!(scale > 0.0) || !std::isfinite(scale)) return std::nullopt;
  return glm::normalize(v / scale);
}

std::optional<Vec3> plain_vec3(const json& value) {
  if (!value.is_array() || value.size() != 3) return std::nullopt;
  double xyz[3];
  for (std::size_t i = 0; i < 3; ++i) {
    const json& element = value[i];
    if (!element.is_number()) return std::nullopt;
    xyz[i] = element.get<double>();
    if (!std::isfinite(xyz[i])) return std::nullopt;
  }
  return Vec3{xyz[0], xyz[1], xyz[2]};
}

void ValueReader::fail_type(std::string_view expected) const {
  fail("must be " + std::string(expected) + ", got " + value_->type_name());
}

ValueReader ValueReader::element(std::size_t index) const {
  return ValueReader((*value_)[index], pointer_ + "/" + std::to_string(index), lifted_, frames_);
}

ValueReader ValueReader::member(std::string_view key) const {
  return ValueReader(*value_->find(key), pointer_ + "/" + pointer_token(key), lifted_, frames_);
}

const LiftedTriples* ValueReader::lifted() const {
  if (lifted_ == nullptr) return nullptr;
  const auto found = lifted_->find(pointer_);
  return found == lifted_->end() ? nullptr : &found->second;
}

std::size_t ValueReader::array_size(std::string_view expected) const {
  if (!value_->is_array()) fail_type(expected);
  return value_->size();
}

void ValueReader::expect_array_of(std::size_t size, std::string_view expected) const {
  if (array_size(expected) != size)
    fail("must be " + std::string(expected) + ", got " + describe(*value_));
}

double ValueReader::number(const Range& range) const {
  if (!value_->is_number()) fail_type("a number");
  const double v = value_->get<double>();
  if (!std::isfinite(v)) fail("must be a finite number, got " + format_number(v));
  if (!range.contains(v)) fail("must be " + range.describe() + ", got " + describe(*value_));
  return v;
}

std::int64_t ValueReader::integer(const IntRange& range) const {
  if (!value_->is_number()) fail_type("an integer");
  // Work in double for the checks: every in-range value is far below 2^53.
  double v = 0.0;
  if (value_->is_number_unsigned())
    v = static_cast<double>(value_->get<std::uint64_t>());
  else if (value_->is_number_integer())
    v = static_cast<double>(value_->get<std::int64_t>());
  else
    v = value_->get<double>();
  if (!std::isfinite(v) || std::trunc(v) != v) fail("must be an integer, got " + describe(*value_));
  if (v < static_cast<double>(range.min))
    fail("must be >= " + std::to_string(range.min) + ", got " + describe(*value_));
  if (v > static_cast<double>(range.max)) {
    std::string detail = "must be <= " + std::to_string(range.max);
    if (!range.max_reason.empty()) detail += " (" + range.max_reason + ")";
    detail += ", got " + describe(*value_);
    if (range.max_reason.starts_with("limit "))
      fail_limit(detail, range.max_reason.substr(6), static_cast<std::uint64_t>(range.max));
    fail(detail);
  }
  if (value_->is_number_integer()) return value_->get<std::int64_t>();
  return static_cast<std::int64_t>(v);
}

bool ValueReader::boolean() const {
  if (!value_->is_boolean()) fail_type("a boolean");
  return value_->get<bool>();
}

const std::string& ValueReader::string() const {
  if (!value_->is_string()) fail_type("a string");
  return value_->get_ref<const std::string&>();
}

std::string_view ValueReader::choice(std::span<const std::string_view> allowed) const {
  if (!value_->is_string()) fail_type("a string, one of " + quoted_list(allowed));
  const std::string& text = value_->get_ref<const std::string&>();
  const auto found = std::find(allowed.begin(), allowed.end(), text);
  if (found != allowed.end()) return *found;
  std::string detail = "must be one of " + quoted_list(allowed) + ", got " + describe(*value_);
  if (const auto match = closest_match(text, allowed))
    detail += "; did you mean " + quote(*match) + "?";
  fail(detail);
}

Vec3 ValueReader::vec3() const {
  expect_array_of(3, "an array of 3 numbers");
  return {element(0).number(), element(1).number(), element(2).number()};
}

Vec3 ValueReader::direction() const {
  const auto unit = try_normalize(vec3());
  if (!unit) fail("must be a non-zero vector, got [0, 0, 0]");
  return *unit;
}

Color ValueReader::color() const {
  const Range non_negative = Range::at_least(0.0);
  if (value_->is_number()) return Color(number(non_negative));
  expect_array_of(3, "a color ([r, g, b] or one number for gray)");
  return {element(0).number(non_negative), element(1).number(non_negative),
          element(2).number(non_negative)};
}

ObjectReader::ObjectReader(ValueReader value, std::string_view expected)
    : value_(std::move(value)) {
  if (!value_.json().is_object()) value_.fail_type(expected);
}

const json::object_t& ObjectReader::members() const {
  return value_.json().get_ref<const json::object_t&>();
}

void ObjectReader::allow_only(std::span<const std::string_view> keys) const {
  for (const auto& [key, unused] : members()) {
    if (std::find(keys.begin(), keys.end(), key) != keys.end()) continue;
    std::string detail = "unknown key " + quote(key);
    if (const auto match = closest_match(key, keys))
      detail += "; did you mean " + quote(*match) + "?";
    else
      detail += "; known keys here: " + quoted_list(keys);
    throw SceneError(pointer() + "/" + pointer_token(key), detail);
  }
}

std::optional<ValueReader> ObjectReader::find(std::string_view key) const {
  if (!value_.json().contains(key)) return std::nullopt;
  return value_.member(key);
}

ValueReader ObjectReader::require(std::string_view key) const {
  if (auto found = find(key)) return *found;
  throw SceneError(pointer() + "/" + pointer_token(key), "required");
}

double ObjectReader::number_or(std::string_view key, double fallback, const Range& range) const {
  const auto found = find(key);
  return found ? found->number(range) : fallback;
}

std::int64_t ObjectReader::integer_or(std::string_view key, std::int64_t fallback,
                                      const IntRange& range) const {
  const auto found = find(key);
  return found ? found->integer(range) : fallback;
}

bool ObjectReader::boolean_or(std::string_view key, bool fallback) const {
  const auto found = find(key);
  return found ? found->boolean() : fallback;
}

Color ObjectReader::color_or(std::string_view key, const Color& fallback) const {
  const auto found = find(key);
  return found ? found->color() : fallback;
}

Vec3 ObjectReader::vec3_or(std::string_view key, const Vec3& fallback) const {
  const auto found = find(key);
  return found ? found->vec3() : fallback;
}

double ObjectReader::animated_number_or(std::string_view key, double fallback,
                                        const Range& range) const {
  const auto found = find(key);
  if (!found) return fallback;
  const bool bounded = range.min.has_value() || range.max.has_value();
  return found->animated([&](const ValueReader& v) { return v.number(range); }, bounded);
}

Color ObjectReader::animated_color_or(std::string_view key, const Color& fallback) const {
  const auto found = find(key);
  return found ? found->animated([](const ValueReader& v) { return v.color(); }, true) : fallback;
}

Vec3 ObjectReader::animated_vec3_or(std::string_view key, const Vec3& fallback) const {
  const auto found = find(key);
  return found ? found->animated([](const ValueReader& v) { return v.vec3(); }) : fallback;
}

}  // namespace tessera
