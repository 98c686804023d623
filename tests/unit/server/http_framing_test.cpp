// HTTP/1.1 message framing (RFC 9112) as a hostile client, or a proxy that reads a message
// differently from us, would test it: one table of raw requests and what each must get.
// A request whose body length is in doubt must never have that body read as a request.
#include <utility>  // before Asio: Boost 1.74 with GCC 12 in C++20 needs it

#include <chrono>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <boost/asio/io_context.hpp>
#include <nlohmann/json.hpp>

#include "server/http/http_server.hpp"
#include "server/http/router.hpp"
#include "tests/unit/server/raw_connection.hpp"

namespace tessera {
namespace {

using namespace std::chrono_literals;
using raw_http::body_of;
using raw_http::RawConnection;
using raw_http::status_of;

class HttpFramingTest : public ::testing::Test {
 protected:
  void SetUp() override {
    router_.add("GET", "/v1/jobs/{id}", [](HttpRequest&& request, Respond respond) {
      respond(json_response(200, {{"id", request.params.at("id")}}));
    });
    router_.add(
        "POST", "/upload",
        [](HttpRequest&& request, Respond respond) {
          respond(json_response(200, {{"body", request.body}}));
        },
        RouteOptions{}.with_body_limit(1024).with_content_type(
            ""));  // any content type: framing is what is tested here
    router_.add(
        "POST", "/big",
        [](HttpRequest&& request, Respond respond) {
          respond(json_response(200, {{"size", request.body.size()}}));
        },
        RouteOptions{}.with_body_limit(4 << 20).with_content_type(""));
  }

  void start(HttpServerOptions options = {}) {
    options.address = "127.0.0.1";
    options.port = 0;
    server_ = std::make_unique<HttpServer>(io_, router_, options);
    for (int i = 0; i < 2; ++i) threads_.emplace_back([this] { io_.run(); });
  }

  void TearDown() override {
    if (server_) server_->stop();
    for (std::thread& thread : threads_) thread.join();
  }

  boost::asio::io_context io_;
  Router router_;
  std::unique_ptr<HttpServer> server_;
  std::vector<std::thread> threads_;
};

struct FramingCase {
  const char* what;
  std::string request;
  int status;
  bool closes;  // the connection must end after the answer
};

// What would be served if a server took the bytes after a doubtful header as a request.
const std::string kSmuggled = "GET /v1/jobs/smuggled HTTP/1.1\r\nHost: x\r\n\r\n";

std::string post_with(const std::string& fields, const std::string& body) {
  return "POST /upload HTTP/1.1\r\nHost: x\r\n" + fields + "\r\n" + body;
}

std::vector<FramingCase> framing_cases() {
  const std::string chunked_body = "5\r\nhello\r\n0\r\n\r\n";
  const std::string long_target = "/v1/jobs/" + std::string(9 * 1024, 'a');
  const std::string longer_than_header = "/v1/jobs/" + std::string(20 * 1024, 'a');
  return {
      // Transfer-Encoding other than one final "chunked": the body's end is unknown.
      {"an unknown coding", post_with("Transfer-Encoding: gzip\r\n", kSmuggled), 400, true},
      {"identity", post_with("Transfer-Encoding: identity\r\n", kSmuggled), 400, true},
      {"an empty coding", post_with("Transfer-Encoding: \r\n", kSmuggled), 400, true},
      {"chunked then another", post_with("Transfer-Encoding: chunked, gzip\r\n", kSmuggled), 400,
       true},
      {"a coding we cannot undo", post_with("Transfer-Encoding: gzip, chunked\r\n", chunked_body),
       501, true},
      {"chunked twice in one field",
       post_with("Transfer-Encoding: chunked, chunked\r\n", chunked_body), 400, true},
      {"chunked twice in two fields",
       post_with("Transfer-Encoding: chunked\r\nTransfer-Encoding: chunked\r\n", chunked_body), 400,
       true},
      {"chunked with a Content-Length",
       post_with("Transfer-Encoding: chunked\r\nContent-Length: 3\r\n", chunked_body), 400, true},
      {"Transfer-Encoding in HTTP/1.0",
       "POST /upload HTTP/1.0\r\nHost: x\r\nTransfer-Encoding: chunked\r\n\r\n" + chunked_body, 400,
       true},
      {"chunked, any letter case", post_with("Transfer-Encoding: ChUnKeD\r\n", chunked_body), 200,
       false},
      {"chunked", post_with("Transfer-Encoding: chunked\r\n", chunked_body), 200, false},
      // Content-Length.
      {"two different lengths", post_with("Content-Length: 3\r\nContent-Length: 4\r\n", "abcd"),
       400, true},
      {"a length that is not a number", post_with("Content-Length: banana\r\n", ""), 400, true},
      {"a negative length", post_with("Content-Length: -1\r\n", ""), 400, true},
      {"a length over the route's limit", post_with("Content-Length: 4096\r\n", ""), 413, true},
      {"a chunk size that overflows",
       post_with("Transfer-Encoding: chunked\r\n", "fffffffffffffffffff\r\nx\r\n0\r\n\r\n"), 400,
       true},
      {"a chunk size that is not hex",
       post_with("Transfer-Encoding: chunked\r\n", "zz\r\nx\r\n0\r\n\r\n"), 400, true},
      // Host.
      {"HTTP/1.1 without Host", "GET /v1/jobs/1 HTTP/1.1\r\n\r\n", 400, true},
      {"two Host fields", "GET /v1/jobs/1 HTTP/1.1\r\nHost: a\r\nHost: b\r\n\r\n", 400, true},
      {"a Host with a space", "GET /v1/jobs/1 HTTP/1.1\r\nHost: a b\r\n\r\n", 400, true},
      {"a Host with user info", "GET /v1/jobs/1 HTTP/1.1\r\nHost: me@x\r\n\r\n", 400, true},
      {"HTTP/1.0 without Host", "GET /v1/jobs/1 HTTP/1.0\r\n\r\n", 200, true},
      // The header's shape.
      {"an obs-folded field", "GET /v1/jobs/1 HTTP/1.1\r\nHost: x\r\nX-Folded: a\r\n b\r\n\r\n",
       400, true},
      {"a folded first field", "GET /v1/jobs/1 HTTP/1.1\r\n Host: x\r\n\r\n", 400, true},
      {"a space before the colon", "GET /v1/jobs/1 HTTP/1.1\r\nHost : x\r\n\r\n", 400, true},
      {"a bare LF in a field", "GET /v1/jobs/1 HTTP/1.1\r\nHost: x\nX-Evil: 1\r\n\r\n", 400, true},
      {"a long request target", "GET " + long_target + " HTTP/1.1\r\nHost: x\r\n\r\n", 414, true},
      {"a target longer than a header may be",
       "GET " + longer_than_header + " HTTP/1.1\r\nHost: x\r\n\r\n", 414, true},
      {"a long header field",
       "GET /v1/jobs/1 HTTP/1.1\r\nHost: x\r\nX-Big: " + std::string(20 * 1024, 'a') + "\r\n\r\n",
       431, true},
      {"not HTTP at all", "THIS IS NOT HTTP\r\n\r\n", 400, true},
      {"an unknown HTTP version", "GET /v1/jobs/1 HTTP/2.7\r\nHost: x\r\n\r\n", 400, true},
  };
}

TEST_F(HttpFramingTest, EveryDoubtfulMessageIsRefusedAndItsBytesNeverServed) {
  start();
  for (const FramingCase& c : framing_cases()) {
    SCOPED_TRACE(c.what);
    RawConnection raw(server_->port());
    raw.send(c.request);
    const std::string response = raw.read_response();
    EXPECT_EQ(status_of(response), c.status) << response.substr(0, 400);
    if (c.status >= 400) {
      // The error says what was wrong, in the server's JSON shape.
      const auto body =
          nlohmann::json::parse(response.substr(response.find("\r\n\r\n") + 4), nullptr, false);
      EXPECT_TRUE(body.contains("error") && body["error"].value("message", "") != "") << response;
    }
    if (c.closes) {
      // Nothing after the answer: the bytes that followed the doubtful header (a second
      // request, to a server that misread the first one) are never answered.
      EXPECT_TRUE(raw.closed_within(10s));
    } else {
      raw.send(kSmuggled);  // a next request on the same connection is served
      const std::string next = raw.read_response();
      EXPECT_EQ(status_of(next), 200);
      EXPECT_EQ(body_of(next)["id"], "smuggled");
    }
  }
}

TEST_F(HttpFramingTest, AChunkedBodyArrivesWhole) {
  start();
  RawConnection raw(server_->port());
  raw.send(post_with("Transfer-Encoding: chunked\r\n", "5\r\nhello\r\n6\r\n world\r\n0\r\n\r\n"));
  const std::string response = raw.read_response();
  ASSERT_EQ(status_of(response), 200) << response;
  EXPECT_EQ(body_of(response)["body"], "hello world");
}

TEST_F(HttpFramingTest, HeadAnswersEveryGetRouteWithoutItsBody) {
  start();
  RawConnection raw(server_->port());
  raw.send("GET /v1/jobs/abc HTTP/1.1\r\nHost: x\r\n\r\n");
  const std::string get = raw.read_response();
  ASSERT_EQ(status_of(get), 200);
  const std::string get_header = get.substr(0, get.find("\r\n\r\n") + 4);

  raw.send("HEAD /v1/jobs/abc HTTP/1.1\r\nHost: x\r\n\r\n");
  EXPECT_EQ(raw.read_header(), get_header);  // byte for byte, Content-Length included
  // No body follows it: the next answer on the connection starts right after the header.
  raw.send("GET /v1/jobs/next HTTP/1.1\r\nHost: x\r\n\r\n");
  const std::string next = raw.read_response();
  ASSERT_EQ(status_of(next), 200) << next;
  EXPECT_EQ(body_of(next)["id"], "next");

  // No GET, no HEAD: 405, and Allow says which methods the path has; no body either.
  raw.send("HEAD /upload HTTP/1.1\r\nHost: x\r\n\r\n");
  const std::string refused = raw.read_header();
  EXPECT_EQ(status_of(refused), 405) << refused;
  EXPECT_NE(refused.find("Allow: POST\r\n"), std::string::npos) << refused;
  raw.send("GET /v1/jobs/last HTTP/1.1\r\nHost: x\r\n\r\n");
  const std::string last = raw.read_response();
  ASSERT_EQ(status_of(last), 200) << last;
  EXPECT_EQ(body_of(last)["id"], "last");
}

TEST_F(HttpFramingTest, AllowNamesHeadBesideGet) {
  start();
  RawConnection raw(server_->port());
  raw.send("DELETE /v1/jobs/abc HTTP/1.1\r\nHost: x\r\n\r\n");
  const std::string response = raw.read_response();
  EXPECT_EQ(status_of(response), 405);
  EXPECT_NE(response.find("Allow: GET, HEAD\r\n"), std::string::npos) << response;
}

TEST_F(HttpFramingTest, ABodyThatTricklesInIsCutOffAtItsDeadline) {
  HttpServerOptions options;
  options.body_timeout = 500ms;
  start(options);
  RawConnection raw(server_->port());
  raw.send(post_with("Content-Length: 1000\r\n", ""));
  // One byte every 50 ms would take 50 s; each read sees progress, so only a deadline for
  // the whole body ends it.
  const auto began = std::chrono::steady_clock::now();
  bool closed = false;
  for (int i = 0; i < 200 && !closed; ++i) {
    try {
      raw.send("x");
    } catch (const std::runtime_error&) {
      closed = true;  // the server hung up: sending fails
      break;
    }
    closed = raw.closed_within(50ms);
  }
  EXPECT_TRUE(closed) << "the trickling body was still being read after 10 s";
  EXPECT_LT(std::chrono::steady_clock::now() - began, 5s);
}

TEST_F(HttpFramingTest, ALargeBodyOnASlowSteadyLinkStillArrives) {
  HttpServerOptions options;
  options.body_timeout = 300ms;
  options.min_body_rate = 64 * 1024;
  start(options);
  RawConnection raw(server_->port());
  constexpr std::size_t kPiece = 64 * 1024;
  constexpr int kPieces = 16;
  raw.send("POST /big HTTP/1.1\r\nHost: x\r\nContent-Length: " + std::to_string(kPiece * kPieces) +
           "\r\n\r\n");
  // 1 MiB over about 0.8 s, well past body_timeout, but at 20 times the minimum rate.
  for (int i = 0; i < kPieces; ++i) {
    raw.send(std::string(kPiece, 'p'));
    std::this_thread::sleep_for(50ms);
  }
  const std::string response = raw.read_response();
  ASSERT_EQ(status_of(response), 200) << response.substr(0, 300);
  EXPECT_EQ(body_of(response)["size"], kPiece * kPieces);
}

}  // namespace
}  // namespace tessera
