// The HTTP layer against real sockets: the server on 127.0.0.1 with an ephemeral port,
// driven by HttpClient and, where a well-behaved client cannot misbehave enough, by raw
// POSIX sockets.
#include <utility>  // before Asio: Boost 1.74 with GCC 12 in C++20 needs it

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <future>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <boost/asio/io_context.hpp>
#include <nlohmann/json.hpp>

#include "common/net/http_client.hpp"
#include "server/http/http_server.hpp"
#include "server/http/router.hpp"
#include "tests/unit/server/raw_connection.hpp"
#include "tests/unused_port.hpp"

namespace tessera {
namespace {

using namespace std::chrono_literals;
using nlohmann::json;
using Clock = std::chrono::steady_clock;
using raw_http::body_of;
using raw_http::RawConnection;
using raw_http::status_of;

// Polls `condition` until it holds or `limit` passes; the limit is generous, the test
// normally moves on as soon as the condition holds.
template <typename Condition>
bool eventually(Condition condition, std::chrono::milliseconds limit = 10s) {
  const auto deadline = Clock::now() + limit;
  while (!condition()) {
    if (Clock::now() > deadline) return false;
    std::this_thread::sleep_for(2ms);
  }
  return true;
}

// Handlers that do not answer at once: they park their Respond for the test to call.
class Parking {
 public:
  void park(Respond respond) {
    std::lock_guard lock(mutex_);
    parked_.push_back(std::move(respond));
    ++total_;
    changed_.notify_all();
  }

  // Waits until `count` requests have been parked in all.
  bool wait_for_total(std::size_t count, std::chrono::milliseconds limit = 10s) {
    std::unique_lock lock(mutex_);
    return changed_.wait_for(lock, limit, [&] { return total_ >= count; });
  }

  Respond take() {
    std::lock_guard lock(mutex_);
    if (parked_.empty()) throw std::logic_error("nothing parked");
    Respond respond = std::move(parked_.front());
    parked_.pop_front();
    return respond;
  }

  void answer_all() {
    std::deque<Respond> all;
    {
      std::lock_guard lock(mutex_);
      all.swap(parked_);
    }
    for (Respond& respond : all) respond(json_response(200, {{"late", true}}));
  }

 private:
  std::mutex mutex_;
  std::condition_variable changed_;
  std::deque<Respond> parked_;
  std::size_t total_ = 0;
};

using test::unused_port;

class HttpTest : public ::testing::Test {
 protected:
  void SetUp() override {
    router_.add("GET", "/v1/jobs/{id}", [](HttpRequest&& request, Respond respond) {
      respond(json_response(200, {{"route", "job"},
                                  {"id", request.params.at("id")},
                                  {"query", request.query},
                                  {"path", request.path}}));
    });
    router_.add("DELETE", "/v1/jobs/{id}", [](HttpRequest&&, Respond respond) {
      respond(HttpResponse{204, "", "", {}});
    });
    router_.add("GET", "/v1/jobs/stats", [](HttpRequest&&, Respond respond) {
      respond(json_response(200, {{"route", "stats"}}));
    });
    router_.add(
        "POST", "/upload",
        [](HttpRequest&& request, Respond respond) {
          respond(json_response(200, {{"size", request.body.size()},
                                      {"content_type", request.headers["content-type"]},
                                      {"x_test", request.headers["x-test"]}}));
        },
        RouteOptions{}.with_body_limit(16).with_content_type(
            ""));  // any content type: http_origin_test.cpp checks them
    router_.add("GET", "/whoami", [](HttpRequest&& request, Respond respond) {
      respond(json_response(200, {{"remote", request.remote_address}}));
    });
    router_.add("GET", "/wait",
                [this](HttpRequest&&, Respond respond) { parking_.park(std::move(respond)); });
    router_.add("GET", "/throw", [](HttpRequest&&, Respond) -> void {
      throw std::runtime_error("handler failure");
    });
    router_.add("GET", "/forget", [](HttpRequest&&, Respond) {});
  }

  void start(HttpServerOptions options = {}) {
    options.address = "127.0.0.1";
    options.port = 0;
    server_ = std::make_unique<HttpServer>(io_, router_, options);
    // Two threads, so that the per-connection strands matter.
    for (int i = 0; i < 2; ++i) threads_.emplace_back([this] { io_.run(); });
  }

  void TearDown() override {
    if (!server_) return;
    parking_.answer_all();
    if (server_) server_->stop();
    // io.run() returns once every connection has finished; bounded, so a bug fails the
    // test instead of hanging it.
    if (!eventually([&] { return io_.stopped(); }, 20s)) {
      ADD_FAILURE() << "the server did not drain after stop()";
      io_.stop();
    }
    for (std::thread& thread : threads_) thread.join();
  }

  std::string url() const { return "http://127.0.0.1:" + std::to_string(server_->port()); }

  boost::asio::io_context io_;
  Router router_;
  Parking parking_;
  std::unique_ptr<HttpServer> server_;
  std::vector<std::thread> threads_;
};

// ---------------------------------------------------------------------------------------
// The router alone.

TEST(RouterTest, MatchesLiteralsAndParameters) {
  Router router;
  const Handler noop = [](HttpRequest&&, Respond) {};
  router.add("GET", "/v1/jobs/{id}", noop);
  router.add("GET", "/v1/jobs/{id}/image", noop, RouteOptions{}.with_body_limit(123));
  router.add("GET", "/v1/jobs/stats", noop);
  router.add("DELETE", "/v1/jobs/{id}", noop);
  router.add("GET", "/", noop);

  auto m = router.match("GET", "/v1/jobs/j-1/image");
  ASSERT_TRUE(m.handler);
  EXPECT_EQ(m.pattern, "/v1/jobs/{id}/image");
  EXPECT_EQ(m.params.at("id"), "j-1");
  EXPECT_EQ(m.body_limit, 123u);

  m = router.match("GET", "/v1/jobs/a%2Fb%20c");
  ASSERT_TRUE(m.handler);
  EXPECT_EQ(m.params.at("id"), "a/b c");  // decoded after splitting: %2F stays in the segment
  EXPECT_FALSE(m.body_limit);

  m = router.match("GET", "/v1/jobs/stats");  // the literal beats the parameter
  ASSERT_TRUE(m.handler);
  EXPECT_EQ(m.pattern, "/v1/jobs/stats");
  EXPECT_TRUE(m.params.empty());

  EXPECT_TRUE(router.match("GET", "/").handler);
  EXPECT_EQ(router.match("GET", "/v1/jobs/").error.status, 404);  // empty parameter
  EXPECT_EQ(router.match("GET", "/v1/jobs/x/y").error.status, 404);
  EXPECT_EQ(router.match("GET", "/v1/jobs/%zz").error.status, 400);

  m = router.match("POST", "/v1/jobs/42");
  EXPECT_FALSE(m.handler);
  EXPECT_EQ(m.error.status, 405);
  ASSERT_EQ(m.error.headers.size(), 1u);
  EXPECT_EQ(m.error.headers[0].first, "Allow");
  EXPECT_EQ(m.error.headers[0].second, "GET, HEAD, DELETE");
  EXPECT_EQ(json::parse(m.error.body)["error"]["code"], "method_not_allowed");
  // The resource is the most specific pattern: its methods only.
  EXPECT_EQ(router.match("DELETE", "/v1/jobs/stats").error.status, 405);

  const std::vector<std::pair<std::string, std::string>> expected = {{"GET", "/v1/jobs/{id}"},
                                                                     {"GET", "/v1/jobs/{id}/image"},
                                                                     {"GET", "/v1/jobs/stats"},
                                                                     {"DELETE", "/v1/jobs/{id}"},
                                                                     {"GET", "/"}};
  EXPECT_EQ(router.routes(), expected);
}

TEST(RouterTest, RejectsBadAndConflictingPatterns) {
  Router router;
  const Handler noop = [](HttpRequest&&, Respond) {};
  router.add("GET", "/a/{id}", noop);
  EXPECT_THROW(router.add("GET", "/a/{id}", noop), std::logic_error);
  EXPECT_THROW(router.add("PUT", "/a/{other}", noop), std::logic_error);
  EXPECT_THROW(router.add("GET", "no-slash", noop), std::invalid_argument);
  EXPECT_THROW(router.add("GET", "/a/x{id}", noop), std::invalid_argument);
  EXPECT_THROW(router.add("GET", "/a/{}", noop), std::invalid_argument);
  EXPECT_THROW(router.add("GET", "/b/{id}/{id}", noop), std::invalid_argument);
  EXPECT_NO_THROW(router.add("PUT", "/a/{id}", noop));
}

TEST(RouterTest, ParsesQueryStrings) {
  const auto query = parse_query("a=1&b=x%20y+z&flag&&c=%26%3D&a=2");
  ASSERT_TRUE(query);
  const std::map<std::string, std::string> expected = {
      {"a", "2"}, {"b", "x y z"}, {"flag", ""}, {"c", "&="}};
  EXPECT_EQ(*query, expected);
  EXPECT_FALSE(parse_query("a=%4"));
  EXPECT_FALSE(parse_query("a=%G0"));
  EXPECT_EQ(percent_decode("a+b%2b", false), "a+b+");
  EXPECT_EQ(percent_decode("a+b", true), "a b");
}

TEST(HttpTypesTest, ErrorBodies) {
  const HttpResponse with_path =
      error_response(422, "invalid_scene", "bad radius", "/objects/0/radius");
  EXPECT_EQ(with_path.status, 422);
  EXPECT_EQ(with_path.content_type, "application/json");
  EXPECT_EQ(json::parse(with_path.body), json({{"error",
                                                {{"code", "invalid_scene"},
                                                 {"message", "bad radius"},
                                                 {"path", "/objects/0/radius"}}}}));
  EXPECT_FALSE(json::parse(error_response(404, "not_found", "no").body)["error"].contains("path"));
  // Invalid UTF-8 is replaced, not thrown on.
  EXPECT_NO_THROW(json_response(200, {{"x", std::string("\xff\xfe")}}));
}

// ---------------------------------------------------------------------------------------
// The server.

TEST_F(HttpTest, RoutesWithParametersAndQuery) {
  start();
  HttpClient client(url(), 10s);
  const HttpResult result = client.request("GET", "/v1/jobs/abc%20d?limit=5&state=a+b%26c&flag");
  ASSERT_EQ(result.status, 200);
  EXPECT_EQ(result.headers.at("content-type"), "application/json");
  EXPECT_EQ(result.headers.at("content-length"), std::to_string(result.body.size()));
  const json body = json::parse(result.body);
  EXPECT_EQ(body["route"], "job");
  EXPECT_EQ(body["id"], "abc d");
  EXPECT_EQ(body["path"], "/v1/jobs/abc%20d");
  EXPECT_EQ(body["query"], json({{"limit", "5"}, {"state", "a b&c"}, {"flag", ""}}));

  EXPECT_EQ(json::parse(client.request("GET", "/v1/jobs/stats").body)["route"], "stats");

  const HttpResult deleted = client.request("DELETE", "/v1/jobs/7");
  EXPECT_EQ(deleted.status, 204);
  EXPECT_TRUE(deleted.body.empty());
  EXPECT_FALSE(deleted.headers.contains("content-type"));

  const HttpResult upload =
      client.request("POST", "/upload", "0123456789", "text/plain", {{"X-Test", "yes"}});
  ASSERT_EQ(upload.status, 200);
  EXPECT_EQ(json::parse(upload.body),
            json({{"size", 10}, {"content_type", "text/plain"}, {"x_test", "yes"}}));
}

TEST_F(HttpTest, NotFoundAndMethodNotAllowedHaveJsonErrors) {
  start();
  HttpClient client(url(), 10s);
  const HttpResult missing = client.request("GET", "/nowhere");
  EXPECT_EQ(missing.status, 404);
  EXPECT_EQ(json::parse(missing.body)["error"]["code"], "not_found");

  const HttpResult wrong_method = client.request("PUT", "/v1/jobs/1", "{}");
  EXPECT_EQ(wrong_method.status, 405);
  EXPECT_EQ(wrong_method.headers.at("allow"), "GET, HEAD, DELETE");
  const json error = json::parse(wrong_method.body)["error"];
  EXPECT_EQ(error["code"], "method_not_allowed");
  EXPECT_TRUE(error["message"].is_string());

  const HttpResult bad_query = client.request("GET", "/v1/jobs/1?x=%zz");
  EXPECT_EQ(bad_query.status, 400);
  EXPECT_EQ(json::parse(bad_query.body)["error"]["code"], "bad_request");

  // The connection is still good after errors without a body.
  EXPECT_EQ(client.request("GET", "/v1/jobs/2").status, 200);
}

TEST_F(HttpTest, OversizedBodyIsRefusedBeforeItIsSent) {
  start();
  RawConnection raw(server_->port());
  // Only the header: the 413 must come without the server waiting for 10 GB.
  raw.send(
      "POST /upload HTTP/1.1\r\nHost: x\r\nContent-Type: application/octet-stream\r\n"
      "Content-Length: 10000000000\r\n\r\n");
  const std::string response = raw.read_response();
  ASSERT_EQ(status_of(response), 413) << response;
  EXPECT_EQ(body_of(response)["error"]["code"], "body_too_large");
  EXPECT_NE(response.find("Connection: close"), std::string::npos);
  EXPECT_TRUE(raw.closed_within(10s));

  // A chunked body announces no size: it is cut off at the limit as it arrives.
  RawConnection chunked(server_->port());
  chunked.send(
      "POST /upload HTTP/1.1\r\nHost: x\r\nTransfer-Encoding: chunked\r\n\r\n"
      "10\r\n0123456789abcdef\r\n10\r\n0123456789abcdef\r\n0\r\n\r\n");
  EXPECT_EQ(status_of(chunked.read_response()), 413);

  // The limit is the route's: 16 bytes pass, 17 do not; the default limit is untouched.
  HttpClient client(url(), 10s);
  EXPECT_EQ(client.request("POST", "/upload", std::string(16, 'x')).status, 200);
  EXPECT_EQ(client.request("POST", "/upload", std::string(17, 'x')).status, 413);
  EXPECT_EQ(client.request("GET", "/v1/jobs/after").status, 200);  // reconnected
}

TEST_F(HttpTest, ExpectContinueGetsAnInterimAnswer) {
  start();
  RawConnection raw(server_->port());
  raw.send("POST /upload HTTP/1.1\r\nHost: x\r\nContent-Length: 4\r\nExpect: 100-continue\r\n\r\n");
  EXPECT_EQ(status_of(raw.read_response()), 100);
  raw.send("abcd");
  const std::string response = raw.read_response();
  ASSERT_EQ(status_of(response), 200) << response;
  EXPECT_EQ(body_of(response)["size"], 4);
}

TEST_F(HttpTest, LargeBodiesAreReadOnlyWithinTheBodyBudget) {
  // A handler that keeps its request and answers later, from another thread, as the
  // coordinator answers an upload once its pixels are stored: the body's share of the
  // budget is held until the answer.
  std::mutex mutex;
  Respond later;
  std::atomic<bool> holding{false};
  router_.add(
      "POST", "/hold",
      [&](HttpRequest&&, Respond respond) {
        std::lock_guard lock(mutex);
        later = std::move(respond);
        holding = true;
      },
      RouteOptions{}.with_body_limit(1 << 20));
  router_.add(
      "POST", "/big",
      [](HttpRequest&& request, Respond respond) {
        respond(json_response(200, {{"size", request.body.size()}}));
      },
      RouteOptions{}.with_body_limit(1 << 20));
  HttpServerOptions options;
  options.budgeted_body_bytes = 100;
  options.body_budget_bytes = 1000;
  start(options);

  auto held = std::async(std::launch::async, [&] {
    return HttpClient(url(), 20s).request("POST", "/hold", std::string(800, 'h'));
  });
  ASSERT_TRUE(eventually([&] { return holding.load(); }));
  // 800 of 1000 bytes are held: another 800 wait, unread, in their socket...
  auto waiting = std::async(std::launch::async, [&] {
    return HttpClient(url(), 20s).request("POST", "/big", std::string(800, 'b'));
  });
  // ...while a body under the budgeted size goes at once.
  EXPECT_EQ(json::parse(
                HttpClient(url(), 10s).request("POST", "/big", std::string(50, 's')).body)["size"],
            50);
  EXPECT_EQ(waiting.wait_for(300ms), std::future_status::timeout);

  std::thread([&] {
    std::lock_guard lock(mutex);
    later(HttpResponse{204, "", "", {}});
  }).join();
  EXPECT_EQ(held.get().status, 204);
  const HttpResult result = waiting.get();
  EXPECT_EQ(result.status, 200);
  EXPECT_EQ(json::parse(result.body)["size"], 800);
  // A body larger than the whole budget goes when nothing else is held.
  EXPECT_EQ(
      json::parse(
          HttpClient(url(), 10s).request("POST", "/big", std::string(5000, 'x')).body)["size"],
      5000);
}

TEST_F(HttpTest, LateAnswerFromAnotherThreadWhileOthersAreServed) {
  start();
  auto waiting = std::async(std::launch::async, [&] {
    HttpClient client(url(), 20s);
    return client.request("GET", "/wait");
  });
  ASSERT_TRUE(parking_.wait_for_total(1));

  // Other connections are served while the long-poll is parked.
  HttpClient other(url(), 10s);
  for (int i = 0; i < 5; ++i)
    EXPECT_EQ(other.request("GET", "/v1/jobs/" + std::to_string(i)).status, 200);
  EXPECT_EQ(waiting.wait_for(0s), std::future_status::timeout);

  std::thread answerer([respond = parking_.take()] {
    respond(json_response(200, {{"late", true}}));
    respond(json_response(500, {{"twice", true}}));  // ignored
  });
  answerer.join();
  const HttpResult result = waiting.get();
  EXPECT_EQ(result.status, 200);
  EXPECT_EQ(json::parse(result.body), json({{"late", true}}));
}

TEST_F(HttpTest, HandlerFailuresBecome500) {
  start();
  HttpClient client(url(), 10s);
  const HttpResult thrown = client.request("GET", "/throw");
  EXPECT_EQ(thrown.status, 500);
  EXPECT_EQ(json::parse(thrown.body)["error"]["code"], "internal_error");
  EXPECT_EQ(client.request("GET", "/forget").status, 500);  // Respond dropped unanswered
  EXPECT_EQ(client.request("GET", "/v1/jobs/1").status, 200);
}

TEST_F(HttpTest, KeepAliveServesTwoRequestsOnOneConnection) {
  start();
  HttpClient client(url(), 10s);
  const HttpResult first = client.request("GET", "/whoami");
  const HttpResult second = client.request("GET", "/whoami");
  ASSERT_EQ(first.status, 200);
  ASSERT_EQ(second.status, 200);
  // Same client port: the same connection.
  EXPECT_EQ(json::parse(first.body)["remote"], json::parse(second.body)["remote"]);
  EXPECT_EQ(server_->connection_count(), 1u);

  // Pipelined on a raw connection: both answered, in order.
  RawConnection raw(server_->port());
  raw.send(
      "GET /v1/jobs/p1 HTTP/1.1\r\nHost: x\r\n\r\nGET /v1/jobs/p2 HTTP/1.1\r\nHost: x\r\n\r\n");
  EXPECT_EQ(body_of(raw.read_response())["id"], "p1");
  EXPECT_EQ(body_of(raw.read_response())["id"], "p2");
}

TEST_F(HttpTest, MalformedRequestGets400AndClose) {
  start();
  RawConnection garbage(server_->port());
  garbage.send("THIS IS NOT HTTP\r\n\r\n");
  const std::string response = garbage.read_response();
  ASSERT_EQ(status_of(response), 400) << response;
  EXPECT_EQ(body_of(response)["error"]["code"], "bad_request");
  EXPECT_TRUE(garbage.closed_within(10s));

  RawConnection bad_length(server_->port());
  bad_length.send("POST /upload HTTP/1.1\r\nHost: x\r\nContent-Length: banana\r\n\r\n");
  EXPECT_EQ(status_of(bad_length.read_response()), 400);

  RawConnection huge_header(server_->port());
  huge_header.send("GET /v1/jobs/1 HTTP/1.1\r\nHost: x\r\nX-Big: " + std::string(64 * 1024, 'a') +
                   "\r\n\r\n");
  EXPECT_EQ(status_of(huge_header.read_response()), 431);

  HttpClient client(url(), 10s);
  EXPECT_EQ(client.request("GET", "/v1/jobs/1").status, 200);
}

TEST_F(HttpTest, SlowAndIdleClientsAreDisconnected) {
  HttpServerOptions options;
  options.header_timeout = 300ms;
  options.body_timeout = 300ms;
  options.idle_timeout = 300ms;
  start(options);

  RawConnection silent(server_->port());
  RawConnection half_header(server_->port());
  half_header.send("GET /v1/jobs/1 HTTP/1.1\r\nHost: x\r\n");
  RawConnection dribbling(server_->port());
  dribbling.send("POST /upload HTTP/1.1\r\nHost: x\r\nContent-Length: 10\r\n\r\nabc");

  // While those hang, others are served, over and over.
  HttpClient client(url(), 10s);
  std::atomic<bool> done{false};
  std::atomic<int> served{0};
  std::thread busy([&] {
    while (!done) {
      if (client.request("GET", "/v1/jobs/busy").status == 200) ++served;
    }
  });
  EXPECT_TRUE(silent.closed_within(10s));
  EXPECT_TRUE(half_header.closed_within(10s));
  EXPECT_TRUE(dribbling.closed_within(10s));
  done = true;
  busy.join();
  EXPECT_GT(served.load(), 0);
}

TEST_F(HttpTest, ClientReconnectsWhenTheServerClosedAnIdleConnection) {
  HttpServerOptions options;
  options.idle_timeout = 100ms;
  start(options);
  HttpClient client(url(), 10s);
  EXPECT_EQ(client.request("GET", "/v1/jobs/1").status, 200);
  ASSERT_TRUE(eventually([&] { return server_->connection_count() == 0; }));
  EXPECT_EQ(client.request("GET", "/v1/jobs/2").status, 200);
}

TEST_F(HttpTest, GracefulStopFinishesInFlightRequests) {
  start();
  auto in_flight = std::async(std::launch::async, [&] {
    HttpClient client(url(), 20s);
    return client.request("GET", "/wait");
  });
  ASSERT_TRUE(parking_.wait_for_total(1));
  HttpClient idle(url(), 10s);
  ASSERT_EQ(idle.request("GET", "/v1/jobs/1").status, 200);
  ASSERT_TRUE(eventually([&] { return server_->connection_count() == 2; }));

  server_->stop();
  // The idle connection goes; the one with a request in flight stays.
  EXPECT_TRUE(eventually([&] { return server_->connection_count() == 1; }));
  // No new connections once the acceptor has closed.
  EXPECT_TRUE(eventually([&] {
    try {
      HttpClient(url(), 2s).request("GET", "/v1/jobs/1");
      return false;
    } catch (const HttpError& e) {
      return e.kind() == HttpError::Kind::connect_failed;
    }
  }));
  EXPECT_EQ(in_flight.wait_for(0s), std::future_status::timeout);
  EXPECT_FALSE(io_.stopped());

  parking_.take()(json_response(200, {{"finished", true}}));
  const HttpResult result = in_flight.get();
  EXPECT_EQ(result.status, 200);
  EXPECT_EQ(json::parse(result.body)["finished"], true);
  EXPECT_EQ(result.headers.at("connection"), "close");
  // With the last request answered, the io_context runs out of work by itself.
  EXPECT_TRUE(eventually([&] { return io_.stopped(); }));
  EXPECT_EQ(server_->connection_count(), 0u);
}

TEST_F(HttpTest, ClientTimesOutOnASlowAnswer) {
  start();
  HttpClient client(url(), 200ms);
  try {
    client.request("GET", "/wait");
    FAIL() << "expected a timeout";
  } catch (const HttpError& e) {
    EXPECT_EQ(e.kind(), HttpError::Kind::timeout) << e.what();
  }
  parking_.answer_all();
  client.set_timeout(10s);
  EXPECT_EQ(client.request("GET", "/v1/jobs/1").status, 200);  // a fresh connection
}

// One client shared by threads (a worker's upload senders share one): a request that waits
// for its answer does not hold up another, which takes a connection of its own; kept-alive
// connections are then reused; and interrupt() ends every request in flight.
TEST_F(HttpTest, ASharedClientGivesEachConcurrentRequestItsOwnConnection) {
  start();
  HttpClient shared(url(), 20s);
  auto parked = std::async(std::launch::async, [&] { return shared.request("GET", "/wait"); });
  ASSERT_TRUE(parking_.wait_for_total(1));
  // Answered while the first request still waits on its connection.
  EXPECT_EQ(shared.request("GET", "/v1/jobs/1").status, 200);
  EXPECT_EQ(parked.wait_for(0s), std::future_status::timeout);
  EXPECT_EQ(server_->connection_count(), 2u);
  parking_.answer_all();
  EXPECT_EQ(parked.get().status, 200);
  // Both connections are kept and reused: no third one is opened.
  auto again = std::async(std::launch::async, [&] { return shared.request("GET", "/wait"); });
  ASSERT_TRUE(parking_.wait_for_total(2));
  EXPECT_EQ(shared.request("GET", "/v1/jobs/2").status, 200);
  EXPECT_EQ(server_->connection_count(), 2u);
  parking_.answer_all();
  EXPECT_EQ(again.get().status, 200);

  // Two requests in flight, both ended by one interrupt.
  auto first = std::async(std::launch::async, [&] { return shared.request("GET", "/wait"); });
  auto second = std::async(std::launch::async, [&] { return shared.request("GET", "/wait"); });
  ASSERT_TRUE(parking_.wait_for_total(4));
  shared.interrupt();
  for (auto* pending : {&first, &second}) {
    try {
      pending->get();
      FAIL() << "a request in flight was not interrupted";
    } catch (const HttpError& e) {
      EXPECT_EQ(e.kind(), HttpError::Kind::interrupted) << e.what();
    }
  }
  parking_.answer_all();
  shared.clear_interrupt();
  EXPECT_EQ(shared.request("GET", "/v1/jobs/3").status, 200);
}

TEST(HttpClientTest, ConnectionRefusedIsConnectFailed) {
  HttpClient client("http://127.0.0.1:" + std::to_string(unused_port()), 5s);
  try {
    client.request("GET", "/healthz");
    FAIL() << "expected HttpError";
  } catch (const HttpError& e) {
    EXPECT_EQ(e.kind(), HttpError::Kind::connect_failed) << e.what();
    EXPECT_NE(std::string(e.what()).find("127.0.0.1"), std::string::npos);
  }
}

TEST(HttpClientTest, ParsesBaseUrls) {
  EXPECT_EQ(parse_base_url("http://example.org").port, 80);
  const BaseUrl local = parse_base_url("http://127.0.0.1:8640/");
  EXPECT_EQ(local.host, "127.0.0.1");
  EXPECT_EQ(local.port, 8640);
  const BaseUrl v6 = parse_base_url("HTTP://[::1]:9000");
  EXPECT_EQ(v6.host, "::1");
  EXPECT_EQ(v6.port, 9000);
  EXPECT_FALSE(local.tls);
  const BaseUrl secure = parse_base_url("HTTPS://farm.example");
  EXPECT_TRUE(secure.tls);
  EXPECT_EQ(secure.host, "farm.example");
  EXPECT_EQ(secure.port, 443);
  EXPECT_EQ(parse_base_url("https://farm.example:8443/").port, 8443);
  // A CA file that cannot be read is refused when the client is made, naming it.
  try {
    HttpClient("https://x", 1s, TlsSettings{"/nonexistent/ca.pem"});
    FAIL() << "an unreadable CA file was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/ca.pem"), std::string::npos) << e.what();
  }
  // A bare host:port is http://, as for curl.
  const BaseUrl bare = parse_base_url("127.0.0.1:8641");
  EXPECT_EQ(bare.host, "127.0.0.1");
  EXPECT_EQ(bare.port, 8641);
  EXPECT_THROW(parse_base_url("ftp://host"), BadServerUrl);
  EXPECT_THROW(parse_base_url("http://:80"), std::invalid_argument);
  EXPECT_THROW(parse_base_url("http://host:0"), std::invalid_argument);
  EXPECT_THROW(parse_base_url("http://host:99999"), std::invalid_argument);
  EXPECT_THROW(parse_base_url("http://host:80/v1"), std::invalid_argument);
}

}  // namespace
}  // namespace tessera
