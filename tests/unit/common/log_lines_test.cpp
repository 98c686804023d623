// --log-format json: one JSON object per line, the ids a line names as fields.
#include "common/text/log_lines.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

namespace tessera {
namespace {

using nlohmann::json;

const std::string job = "j-0123456789abcdef0123456789abcdef";
const std::string worker = "w-0123456789ab";
const std::string lease = "l-0123456789abcdef";

TEST(LogLinesTest, AJsonLineCarriesTheIdsItsMessageNames) {
  const json line = json::parse(json_log_line(
      "info", "lease " + lease + " of job " + job + " went to worker " + worker + " (render)",
      "2026-12-05T14:00:00.123Z"));
  EXPECT_EQ(line["time"], "2026-12-05T14:00:00.123Z");
  EXPECT_EQ(line["level"], "info");
  EXPECT_EQ(line["job"], job);
  EXPECT_EQ(line["worker"], worker);
  EXPECT_EQ(line["lease"], lease);
  EXPECT_EQ(line["message"].get<std::string>().substr(0, 6), "lease ");
}

TEST(LogLinesTest, OnlyWholeIdsAreFieldsAndAnyMessageStaysOneLineOfJson) {
  const std::string text = json_log_line(
      "warn", "my-j-0123456789abcdef0123456789abcdef j-0123 w-0123456789abcd\nforged\x1b[31m\xff",
      "t");
  EXPECT_EQ(text.find('\n'), std::string::npos);
  const json line = json::parse(text);
  EXPECT_FALSE(line.contains("job")) << "inside a longer word, or too short";
  EXPECT_FALSE(line.contains("worker")) << "too long";
  EXPECT_FALSE(line.contains("lease"));
  EXPECT_NE(line["message"].get<std::string>().find("forged"), std::string::npos);
}

}  // namespace
}  // namespace tessera
