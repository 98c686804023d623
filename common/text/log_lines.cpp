#include "common/text/log_lines.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <memory>
#include <string_view>

#include <nlohmann/json.hpp>

#include <spdlog/pattern_formatter.h>
#include <spdlog/spdlog.h>

#include "common/text/printable.hpp"
#include "common/text/rfc3339.hpp"

namespace tessera {

namespace {

// %* in the pattern: the message, escaped.
class EscapedMessage final : public spdlog::custom_flag_formatter {
 public:
  void format(const spdlog::details::log_msg& message, const std::tm&,
              spdlog::memory_buf_t& out) override {
    const std::string text =
        printable(std::string_view(message.payload.data(), message.payload.size()));
    out.append(text.data(), text.data() + text.size());
  }
  std::unique_ptr<custom_flag_formatter> clone() const override {
    return std::make_unique<EscapedMessage>();
  }
};

// The id of `kind` ("j-", "w-", "l-") followed by `digits` lowercase hex digits that
// `text` names first, not inside a longer word; "" when none.
std::string first_id(std::string_view text, std::string_view kind, std::size_t digits) {
  const auto hex = [](char c) { return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'); };
  const auto word = [&](char c) {
    return hex(c) || (c >= 'g' && c <= 'z') || c == '-' || c == '_';
  };
  for (std::size_t at = text.find(kind); at != std::string_view::npos;
       at = text.find(kind, at + 1)) {
    const std::size_t end = at + kind.size() + digits;
    if (end > text.size() || (at > 0 && word(text[at - 1]))) continue;
    if (!std::all_of(text.begin() + static_cast<std::ptrdiff_t>(at + kind.size()),
                     text.begin() + static_cast<std::ptrdiff_t>(end), hex))
      continue;
    if (end < text.size() && word(text[end])) continue;
    return std::string(text.substr(at, end - at));
  }
  return {};
}

class JsonLine final : public spdlog::formatter {
 public:
  void format(const spdlog::details::log_msg& message, spdlog::memory_buf_t& out) override {
    const auto ms =
        std::chrono::duration_cast<std::chrono::milliseconds>(message.time.time_since_epoch())
            .count();
    const spdlog::string_view_t level = spdlog::level::to_string_view(message.level);
    const std::string line =
        json_log_line(std::string_view(level.data(), level.size()),
                      std::string_view(message.payload.data(), message.payload.size()),
                      rfc3339_utc(ms)) +
        "\n";
    out.append(line.data(), line.data() + line.size());
  }
  std::unique_ptr<spdlog::formatter> clone() const override { return std::make_unique<JsonLine>(); }
};

}  // namespace

std::string json_log_line(std::string_view level, std::string_view message, std::string_view time) {
  nlohmann::ordered_json line{{"time", time}, {"level", level}, {"message", message}};
  if (auto id = first_id(message, "j-", 32); !id.empty()) line["job"] = id;
  if (auto id = first_id(message, "w-", 12); !id.empty()) line["worker"] = id;
  if (auto id = first_id(message, "l-", 16); !id.empty()) line["lease"] = id;
  // ASCII only, invalid UTF-8 replaced: a line is always one line of valid JSON.
  return line.dump(-1, ' ', true, nlohmann::json::error_handler_t::replace);
}

void use_json_log_lines() { spdlog::set_formatter(std::make_unique<JsonLine>()); }

void use_escaped_log_lines() {
  auto formatter = std::make_unique<spdlog::pattern_formatter>();
  // spdlog's default pattern, with the message escaped.
  formatter->add_flag<EscapedMessage>('*').set_pattern("[%Y-%m-%d %H:%M:%S.%e] [%^%l%$] %*");
  spdlog::set_formatter(std::move(formatter));
}

}  // namespace tessera
