#include "common/protocol/timestamp.hpp"

#include <algorithm>
#include <ctime>

#include "common/text/rfc3339.hpp"

namespace tessera::protocol {

std::string format_timestamp(std::int64_t ms) { return rfc3339_utc(ms); }

}  // namespace tessera::protocol

namespace tessera::protocol {

std::optional<std::int64_t> parse_timestamp(std::string_view text) {
  // YYYY-MM-DDTHH:MM:SS[.fff]Z, digits where digits are due and nothing else.
  const auto digits = [&](std::size_t at, std::size_t count) -> std::optional<int> {
    if (at + count > text.size()) return std::nullopt;
    int value = 0;
    for (std::size_t i = at; i < at + count; ++i) {
      if (text[i] < '0' || text[i] > '9') return std::nullopt;
      value = value * 10 + (text[i] - '0');
    }
    return value;
  };
  if (text.size() < 20 || text[4] != '-' || text[7] != '-' || text[10] != 'T' || text[13] != ':' ||
      text[16] != ':' || text.back() != 'Z')
    return std::nullopt;
  const auto year = digits(0, 4), month = digits(5, 2), day = digits(8, 2), hour = digits(11, 2),
             minute = digits(14, 2), second = digits(17, 2);
  if (!year || !month || !day || !hour || !minute || !second || *month < 1 || *month > 12 ||
      *day < 1 || *day > 31 || *hour > 23 || *minute > 59 || *second > 60)
    return std::nullopt;
  int ms = 0;
  if (text.size() != 20) {
    if (text[19] != '.' || text.size() < 22) return std::nullopt;
    const std::size_t count = text.size() - 21;
    if (count > 9) return std::nullopt;
    const auto fraction = digits(20, std::min<std::size_t>(count, 3));
    if (!fraction || !digits(20, count)) return std::nullopt;
    ms = *fraction;
    for (std::size_t i = count; i < 3; ++i) ms *= 10;
  }
  std::tm utc{};
  utc.tm_year = *year - 1900;
  utc.tm_mon = *month - 1;
  utc.tm_mday = *day;
  utc.tm_hour = *hour;
  utc.tm_min = *minute;
  utc.tm_sec = *second;
  return static_cast<std::int64_t>(timegm(&utc)) * 1000 + ms;
}

}  // namespace tessera::protocol
