// Text from users is data, never control: names that would steer a terminal or a log are
// refused, and whatever text the server logs or the CLI prints that they did not compose
// themselves (a worker's error, an id from a URL) is escaped.
#include <algorithm>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "common/net/coordinator_client.hpp"
#include "common/protocol/limits.hpp"
#include "tests/farm/farm_fixture.hpp"

namespace tessera {
namespace {

using namespace std::chrono_literals;
using nlohmann::json;
using test::eventually;
using test::Farm;

// Each would end a line, start a new one or send an escape sequence: C0, DEL, C1 and NUL.
const std::vector<std::pair<const char*, std::string>> kControlNames = {
    {"a line feed", "render\n[2026-12-05 00:00:00.000] [info] forged"},
    {"a carriage return", "render\rforged"},
    {"an escape sequence", "render\x1b[31mred"},
    {"a terminal title", "render\x1b]0;pwned\x07"},
    {"DEL", "render\x7f"},
    {"C1 CSI (U+009B)",
     "render\xc2\x9b"
     "31m"},
    {"NUL", std::string("render\0x", 8)},
    // Or reorder what is shown around them: "evil\u202Egnp.exe" reads as "evilexe.png".
    {"RIGHT-TO-LEFT OVERRIDE (U+202E)", "evil\xe2\x80\xaegnp.exe"},
    {"RIGHT-TO-LEFT ISOLATE (U+2067)",
     "a\xe2\x81\xa7"
     "b"},
    {"ARABIC LETTER MARK (U+061C)",
     "a\xd8\x9c"
     "b"},
};

TEST(FarmTextTest, NamesWithControlCharactersAreRefusedWithTheirPointer) {
  Farm farm("text-names", 0);
  HttpClient http = farm.http(10s);
  const json scene = test::showcase(16, 16, 1, 16);
  for (const auto& [what, name] : kControlNames) {
    SCOPED_TRACE(what);
    const HttpResult job =
        http.request("POST", "/v1/jobs", json{{"name", name}, {"scene", scene}}.dump());
    EXPECT_EQ(job.status, 400) << job.body;
    EXPECT_EQ(json::parse(job.body)["error"]["path"], "/name") << job.body;

    const HttpResult worker =
        http.request("POST", "/v1/workers", json{{"name", name}, {"protocol", 2}}.dump());
    EXPECT_EQ(worker.status, 400) << worker.body;
    EXPECT_EQ(json::parse(worker.body)["error"]["path"], "/name") << worker.body;

    const HttpResult host = http.request(
        "POST", "/v1/workers", json{{"name", "w"}, {"host", name}, {"protocol", 2}}.dump());
    EXPECT_EQ(host.status, 400) << host.body;
    EXPECT_EQ(json::parse(host.body)["error"]["path"], "/host") << host.body;
  }
  // Other scripts are names like any other.
  const json accepted = farm.api().submit("rendu été 日本 ✓", 50, scene);
  EXPECT_EQ(accepted["name"], "rendu été 日本 ✓");
  EXPECT_EQ(farm.api().jobs("", 10)["jobs"].size(), 1u) << "a refused name was stored";
}

TEST(FarmTextTest, TheServerLogAndTheCliEscapeWhatOthersWrote) {
  Farm farm("text-escaped", 0);
  const json job = farm.api().submit("escaped", 50, test::showcase(16, 16, 1, 16));

  // A worker's error text is free text, kept on the job and shown to people.
  CoordinatorClient worker(farm.url(), "", 10s);
  protocol::WorkerRegistration joining;
  joining.name = "w";
  const protocol::Registration registration = worker.register_worker(joining);
  const auto lease = worker.claim(registration.id, 5, 1);
  ASSERT_TRUE(lease);
  const std::string forged = "boom\n[2026-12-05 00:00:00.000] [info] forged\x1b]0;pwned\x07";
  worker.fail(lease->id, {.tile = lease->tiles.front().index, .error = forged});

  // The CLI shows it on one line, its escape sequence spelled out.
  const test::CliRun status =
      test::run_cli(farm.dir(), {"--server", farm.url(), "status", job["id"]});
  EXPECT_EQ(status.exit_code, 0) << status.output;
  EXPECT_NE(
      status.output.find("boom\\x0a[2026-12-05 00:00:00.000] [info] forged\\x1b]0;pwned\\x07"),
      std::string::npos)
      << status.output;
  EXPECT_EQ(status.output.find('\x1b'), std::string::npos) << "a raw escape reached the terminal";
  EXPECT_EQ(status.output.find("\n[2026-12-05"), std::string::npos) << status.output;

  // An id taken from a URL reaches the log (a refused result is logged with its lease).
  HttpClient http = farm.http(10s);
  const HttpResult registered = http.request(
      "POST", "/v1/workers", json{{"name", "w"}, {"protocol", kWorkerProtocolVersion}}.dump());
  ASSERT_EQ(registered.status, 201) << registered.body;
  const HttpResult refused =
      http.request("PUT", "/v1/leases/l%0A%5B2026-12-05%5D%20forged%1B%5B31m/result",
                   std::string(13, '\0'), "application/octet-stream",
                   {{"X-Tessera-Worker-Secret", json::parse(registered.body)["secret"]}});
  EXPECT_EQ(refused.status, 400);
  const auto log = [&] { return test::read_text(farm.dir() / "server.log"); };
  EXPECT_TRUE(eventually([&] { return log().find("forged") != std::string::npos; }, 10s)) << log();
  EXPECT_NE(log().find("l\\x0a[2026-12-05] forged\\x1b[31m"), std::string::npos) << log();
  EXPECT_EQ(log().find('\x1b'), std::string::npos) << "a raw escape in the server's log";
  EXPECT_EQ(log().find("\n[2026-12-05] forged"), std::string::npos) << "a forged log line";
}

}  // namespace
}  // namespace tessera
