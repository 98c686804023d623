// What a web page can make the server do: a page on another site may send a form or
// text/plain anywhere without asking, and a page whose DNS name is rebound to 127.0.0.1
// reaches a coordinator on the user's machine. Refused at the HTTP layer, before any route.
#include <utility>  // before Asio: Boost 1.74 with GCC 12 in C++20 needs it

#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <boost/asio/io_context.hpp>

#include "server/http/http_server.hpp"
#include "server/http/origin_policy.hpp"
#include "server/http/router.hpp"
#include "tests/unit/server/raw_connection.hpp"

namespace tessera {
namespace {

using raw_http::body_of;
using raw_http::RawConnection;
using raw_http::status_of;

class HttpOriginTest : public ::testing::Test {
 protected:
  void start(OriginPolicy origins) {
    router_.add("GET", "/v1/jobs", [](HttpRequest&&, Respond respond) {
      respond(json_response(200, {{"jobs", nlohmann::json::array()}}));
    });
    router_.add("POST", "/v1/jobs", [](HttpRequest&&, Respond respond) {
      respond(json_response(201, {{"id", "j-1"}}));
    });
    router_.add(
        "PUT", "/pixels", [](HttpRequest&&, Respond respond) { respond(json_response(200, {})); },
        RouteOptions{}.with_content_type("application/octet-stream"));
    HttpServerOptions options;
    options.address = "127.0.0.1";
    options.port = 0;
    options.origins = std::move(origins);
    server_ = std::make_unique<HttpServer>(io_, router_, options);
    thread_ = std::thread([this] { io_.run(); });
  }

  void TearDown() override {
    if (server_) server_->stop();
    if (thread_.joinable()) thread_.join();
  }

  // The status of one request; `fields` are extra header lines, each ending in CRLF.
  int status(const std::string& method, const std::string& target, const std::string& fields,
             const std::string& host = "127.0.0.1") {
    RawConnection raw(server_->port());
    raw.send(method + " " + target + " HTTP/1.1\r\nHost: " + host + "\r\n" + fields +
             "Content-Length: 2\r\nConnection: close\r\n\r\n{}");
    const std::string response = raw.read_response();
    last_ = response;
    return status_of(response);
  }

  boost::asio::io_context io_;
  Router router_;
  std::unique_ptr<HttpServer> server_;
  std::thread thread_;
  std::string last_;
};

TEST(OriginPolicyTest, TheServersOwnPagesAreOfItsSchemeToo) {
  const OriginPolicy none;
  const auto refused = [&](const char* origin, bool tls) {
    return origin_problem(none, "farm.example:8640", origin, tls).has_value();
  };
  EXPECT_FALSE(refused("http://farm.example:8640", false));
  EXPECT_FALSE(refused("https://farm.example:8640", false));  // through a TLS proxy
  EXPECT_FALSE(refused("https://farm.example:8640", true));
  // A TLS server's pages never come over plain HTTP, which anyone on the way could write.
  EXPECT_TRUE(refused("http://farm.example:8640", true));
  EXPECT_TRUE(refused("ftp://farm.example:8640", false));
  EXPECT_TRUE(refused("farm.example:8640", false));
  EXPECT_TRUE(refused("https://farm.example:8641", true));
}

TEST_F(HttpOriginTest, ChangesNeedTheRoutesContentType) {
  start({});
  const std::string json = "Content-Type: application/json\r\n";
  EXPECT_EQ(status("POST", "/v1/jobs", json), 201) << last_;
  EXPECT_EQ(status("POST", "/v1/jobs", "Content-Type: Application/JSON; charset=utf-8\r\n"), 201);
  // What a page may send anywhere without a CORS preflight: a form, text, or nothing.
  for (const std::string type :
       {"text/plain", "application/x-www-form-urlencoded", "multipart/form-data; boundary=x"}) {
    EXPECT_EQ(status("POST", "/v1/jobs", "Content-Type: " + type + "\r\n"), 415) << type;
    EXPECT_EQ(body_of(last_)["error"]["code"], "unsupported_media_type");
  }
  EXPECT_EQ(status("POST", "/v1/jobs", ""), 415) << "no Content-Type at all";
  // Uploads are pixels, and only pixels.
  EXPECT_EQ(status("PUT", "/pixels", "Content-Type: application/octet-stream\r\n"), 200);
  EXPECT_EQ(status("PUT", "/pixels", json), 415);
  // Reading needs nothing.
  EXPECT_EQ(status("GET", "/v1/jobs", ""), 200);
}

TEST_F(HttpOriginTest, OnlyTheServersOwnOriginAndThoseAllowedMayCall) {
  start({{"https://dashboard.example:8443"}, false});
  const std::string json = "Content-Type: application/json\r\n";
  EXPECT_EQ(status("POST", "/v1/jobs", json), 201) << "no Origin: a program, not a page";
  EXPECT_EQ(status("POST", "/v1/jobs", json + "Origin: http://127.0.0.1\r\n"), 201)
      << "the server's own pages";
  EXPECT_EQ(status("POST", "/v1/jobs", json + "Origin: https://dashboard.example:8443\r\n"), 201);
  for (const std::string origin :
       {"https://evil.example", "null", "https://dashboard.example", "http://127.0.0.1:9",
        "https://dashboard.example:8443.evil.example"}) {
    EXPECT_EQ(status("POST", "/v1/jobs", json + "Origin: " + origin + "\r\n"), 403) << origin;
    EXPECT_EQ(body_of(last_)["error"]["code"], "origin_refused") << origin;
    EXPECT_EQ(status("GET", "/v1/jobs", "Origin: " + origin + "\r\n"), 403) << origin;
  }
}

TEST_F(HttpOriginTest, WithoutTokensOnlyLoopbackNamesAreAnswered) {
  start({{}, true});
  for (const std::string host : {"127.0.0.1", "127.0.0.1:8640", "127.1.2.3", "localhost",
                                 "LOCALHOST:8640", "app.localhost", "[::1]", "[::1]:8640"})
    EXPECT_EQ(status("GET", "/v1/jobs", "", host), 200) << host;
  // A page at rebind.example, its name pointed at 127.0.0.1 after it loaded.
  for (const std::string host : {"rebind.example", "rebind.example:8640", "127.0.0.1.evil.example",
                                 "localhost.evil.example", "10.0.0.1", "[::2]"}) {
    EXPECT_EQ(status("GET", "/v1/jobs", "", host), 403) << host;
    EXPECT_EQ(body_of(last_)["error"]["code"], "host_refused") << host;
  }
}

}  // namespace
}  // namespace tessera
