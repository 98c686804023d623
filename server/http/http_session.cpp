#include "server/http/http_session.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdint>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include <spdlog/spdlog.h>
#include <boost/asio/dispatch.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/ssl.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/ssl.hpp>

#include "server/http/connection_admission.hpp"
#include "server/http/http_errors.hpp"
#include "server/http/listener.hpp"
#include "server/http/pending_response.hpp"
#include "server/http/request_framing.hpp"
#include "server/http/router.hpp"
#include "server/http/stream_writer.hpp"
#include "server/http/wire_messages.hpp"
#include "server/metrics/http_metrics.hpp"

namespace tessera {

namespace net = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
using tcp = net::ip::tcp;
using error_code = beast::error_code;

namespace {

// After a response that ends the connection, how long unread request bytes are drained
// so that closing does not reset the connection before the client has read the answer.
constexpr std::chrono::seconds kLingerTime{2};

using PlainStream = beast::tcp_stream;
using TlsStream = beast::ssl_stream<beast::tcp_stream>;

// A TLS connection starts with a handshake record, whose first byte is 22; an HTTP request
// never does.
constexpr unsigned char kTlsHandshakeRecord = 22;

// What a port answers a client speaking the other protocol, in plain HTTP, before closing:
// the client can then say what is wrong rather than that the connection failed. (A TLS
// client shows the plain answer as OpenSSL's "wrong version number".)
std::string wrong_protocol_answer(bool port_speaks_tls) {
  const std::string body =
      port_speaks_tls ? R"({"error":{"code":"tls_required","message":"this port speaks TLS: )"
                        R"(use https:// to reach this server"}})"
                      : R"({"error":{"code":"tls_not_served","message":"this port speaks plain )"
                        R"(HTTP: use http:// to reach this server"}})";
  return "HTTP/1.1 400 Bad Request\r\nContent-Type: application/json\r\nConnection: close\r\n"
         "Content-Length: " +
         std::to_string(body.size()) + "\r\n\r\n" + body;
}

}  // namespace

// One connection over Stream: PlainStream, or TlsStream once its handshake is done.
template <typename Stream>
class BasicHttpSession : public HttpSession {
 public:
  static constexpr bool kTls = std::is_same_v<Stream, TlsStream>;

  BasicHttpSession(tcp::socket&& socket, std::shared_ptr<ServerShared> shared) requires(!kTls)
      : stream_(std::move(socket)), shared_(std::move(shared)) {
    ++shared_->connection_count;
  }
  // The context is the one in use when the connection came: a reload changes later ones.
  BasicHttpSession(tcp::socket&& socket, std::shared_ptr<ServerShared> shared,
                   std::shared_ptr<net::ssl::context> tls) requires kTls
      : tls_(std::move(tls)),
        stream_(std::move(socket), *tls_),
        shared_(std::move(shared)) {
    ++shared_->connection_count;
  }

  ~BasicHttpSession() override {
    release_body_budget();
    forget_session(*shared_, this);
    --shared_->connection_count;
  }

  void start(const std::string& peer) {
    error_code ec;
    const auto endpoint = lowest().socket().remote_endpoint(ec);
    if (!ec) remote_address_ = format_endpoint(endpoint);
    // Small requests and answers: do not let Nagle hold back the last segment.
    lowest().socket().set_option(tcp::no_delay(true), ec);
    note_waiting();
    {
      std::lock_guard lock(shared_->mutex);
      shared_->sessions.emplace(this, ServerShared::OpenSession{weak_from_this(), peer});
      ++shared_->open_by_peer[peer];
      ++shared_->open_counted;
    }
    net::dispatch(stream_.get_executor(), [self = self()] {
      if constexpr (kTls)
        self->do_tls_start();
      else
        self->do_wait_for_request();
    });
  }

  void evict() override {
    net::post(stream_.get_executor(), [self = self()] {
      if (self->phase_ == Phase::idle || self->phase_ == Phase::header) return self->close();
      // It began a request meanwhile: it stays, and counts again.
      keep_session(*self->shared_, self.get());
    });
  }

  // From any thread.
  void shut_down() override {
    net::post(stream_.get_executor(), [self = self()] { self->on_shut_down(); });
  }

  // Delivers a handler's answer, from any thread. A handler may hold the body until it
  // answers: its share of the body budget goes with the answer.
  void deliver(HttpResponse response) override {
    net::post(stream_.get_executor(), [self = self(), response = std::move(response)]() mutable {
      self->release_body_budget();
      self->send(std::move(response), !self->keep_alive_);
    });
  }

 private:
  enum class Phase { idle, header, body, handler, writing, streaming, closing, closed };

  bool stopping() const { return shared_->stopping.load(); }
  std::shared_ptr<BasicHttpSession> self() {
    return std::static_pointer_cast<BasicHttpSession>(shared_from_this());
  }
  // The TCP stream under TLS, if any: timeouts, the socket, close.
  beast::tcp_stream& lowest() { return beast::get_lowest_layer(stream_); }

  // The first bytes say whether the client speaks TLS; they are then handed to the
  // handshake, which would otherwise wait to read them itself. All within header_timeout.
  void do_tls_start() {
    phase_ = Phase::header;
    lowest().expires_after(shared_->options.header_timeout);
    lowest().async_read_some(buffer_.prepare(4096),
                             [self = self()](error_code ec, std::size_t bytes) {
                               if (ec) return self->close();
                               self->buffer_.commit(bytes);
                               if (!self->starts_tls_handshake())
                                 return self->refuse_other_protocol();
                               self->do_handshake();
                             });
  }

  void do_handshake() {
    if constexpr (kTls) {
      stream_.async_handshake(net::ssl::stream_base::server, buffer_.data(),
                              [self = self()](error_code ec, std::size_t used) {
                                if (ec) {
                                  spdlog::debug("https {}: TLS handshake failed: {}",
                                                self->remote_address_, ec.message());
                                  return self->close();
                                }
                                self->buffer_.consume(used);
                                self->do_wait_for_request();
                              });
    }
  }

  bool starts_tls_handshake() const {
    return buffer_.size() > 0 &&
           static_cast<unsigned char>(*static_cast<const char*>(buffer_.data().data())) ==
               kTlsHandshakeRecord;
  }

  // Plain HTTP to a TLS port, or a TLS handshake to a plain one.
  void refuse_other_protocol() {
    phase_ = Phase::writing;
    refusal_ = std::make_unique<std::string>(wrong_protocol_answer(kTls));
    lowest().expires_after(shared_->options.write_timeout);
    net::async_write(lowest(), net::buffer(*refusal_), [self = self()](error_code, std::size_t) {
      // The rest of what it sent is in the other protocol, read by no one.
      self->buffer_.consume(self->buffer_.size());
      self->linger();
    });
  }

  // Waiting for a request's first byte is kept apart from reading its header, so that an
  // idle keep-alive connection has its own timeout and stop() can tell it is idle.
  void do_wait_for_request() {
    if (stopping()) return close();
    if (buffer_.size() > 0) return do_read_header();  // pipelined: already here
    phase_ = Phase::idle;
    note_waiting();
    lowest().expires_after(first_request_ ? shared_->options.header_timeout
                                          : shared_->options.idle_timeout);
    stream_.async_read_some(
        buffer_.prepare(4096),
        beast::bind_front_handler(&BasicHttpSession::on_wait_for_request, self()));
  }

  void on_wait_for_request(error_code ec, std::size_t bytes) {
    if (ec) return close();  // the client went away, timed out, or stop() closed us
    buffer_.commit(bytes);
    if constexpr (!kTls)
      if (first_request_ && starts_tls_handshake()) return refuse_other_protocol();
    do_read_header();
  }

  // Gathered here, not by Beast, whose parser unfolds folded lines without a trace.
  void do_read_header() {
    phase_ = Phase::header;
    parser_.emplace();
    parser_->header_limit(shared_->options.max_header_bytes);
    // The route's limit is applied once the header says which route it is. (Not
    // boost::none: Beast 1.74 compares a Content-Length with an empty limit as exceeding it.)
    parser_->body_limit(std::numeric_limits<std::uint64_t>::max());
    lowest().expires_after(shared_->options.header_timeout);
    header_scanned_ = 0;
    read_header_more();
  }

  void read_header_more() {
    const std::string_view data(static_cast<const char*>(buffer_.data().data()), buffer_.size());
    // Resumed a little before where the last look ended: the blank line may straddle reads.
    const std::size_t end = data.find("\r\n\r\n", header_scanned_ < 3 ? 0 : header_scanned_ - 3);
    const std::size_t limit = shared_->options.max_header_bytes;
    if (end != std::string_view::npos && end + 4 <= limit) return on_header_bytes(end + 4);
    if (data.size() >= limit) {
      auto problem = raw_header_problem(data, shared_->options.max_target_bytes);
      return send(problem ? std::move(*problem) : header_too_large(limit), true);
    }
    header_scanned_ = data.size();
    stream_.async_read_some(buffer_.prepare(std::min<std::size_t>(4096, limit - data.size())),
                            [self = self()](error_code ec, std::size_t bytes) {
                              if (ec) return self->on_read_error(ec, "header");
                              self->buffer_.commit(bytes);
                              self->read_header_more();
                            });
  }

  void on_header_bytes(std::size_t size) {
    const std::string_view header(static_cast<const char*>(buffer_.data().data()), size);
    if (auto problem = raw_header_problem(header, shared_->options.max_target_bytes))
      return send(std::move(*problem), true);
    error_code ec;
    const std::size_t used = parser_->put(net::buffer(header.data(), header.size()), ec);
    buffer_.consume(used);
    if (!ec && !parser_->is_header_done()) ec = http::error::partial_message;
    if (ec) return on_read_error(ec, "header");
    on_read_header();
  }

  void on_read_header() {
    auto& request = parser_->get();
    request_started_ = std::chrono::steady_clock::now();
    method_ = std::string(request.method_string());
    head_only_ = request.method() == http::verb::head;
    const RequestHead head = head_of(request);
    if (auto problem = framing_problem(head, shared_->options.max_target_bytes))
      return send(std::move(*problem), true);
    first_request_ = false;
    keep_alive_ = request.keep_alive();
    const bool body_follows = !parser_->is_done();

    const std::string_view target = head.target;
    const std::size_t question = target.find('?');
    path_ = std::string(target.substr(0, question));
    route_ = shared_->router.match(head.method, path_);
    if (!route_.handler) return send(std::move(route_.error), body_follows || !keep_alive_);
    // Refused before the body is read, so a stranger cannot make the server take one in.
    if (auto refused =
            shared_->options.authorize(route_.role, head.field("authorization").value_or("")))
      return send(std::move(*refused), body_follows || !keep_alive_);
    if (auto refused = browser_problem(shared_->options.origins, head, route_.content_type, kTls))
      return send(std::move(*refused), body_follows || !keep_alive_);

    auto query = parse_query(question == std::string_view::npos ? std::string_view()
                                                                : target.substr(question + 1));
    if (!query)
      return send(
          error_response(400, "bad_request", "the query string is not valid percent-encoding"),
          body_follows || !keep_alive_);
    query_ = std::move(*query);

    const std::size_t limit = route_.body_limit.value_or(shared_->options.default_body_limit);
    if (const auto length = parser_->content_length(); length && *length > limit)
      return send(too_large(limit), true);
    parser_->body_limit(limit);  // also caps a chunked body, whose size is not announced

    if (route_.sink) return start_streaming(body_follows);
    if (!body_follows) return dispatch();
    const auto length = parser_->content_length();
    if (!length || *length <= shared_->options.budgeted_body_bytes) return read_body_now();
    // Waits, without a timer, until the body fits in the server's budget for bodies.
    lowest().expires_never();
    shared_->body_budget.acquire(*length, [self = self(), bytes = *length] {
      net::dispatch(self->stream_.get_executor(), [self, bytes] {
        self->budget_held_ = bytes;
        self->read_body_now();
      });
    });
  }

  void read_body_now() {
    if (beast::iequals(parser_->get()[http::field::expect], "100-continue")) return do_continue();
    do_read_body();
  }

  // A streamed body (BodySink): no budget, since at most one piece of it is held at a time.
  void start_streaming(bool body_follows) {
    HttpRequest head = plain_request(parser_->get());
    head.path = path_;
    head.params = route_.params;
    head.remote_address = remote_address_;
    try {
      sink_ = (*route_.sink)(head);
    } catch (const std::exception& e) {
      spdlog::error("http {}: no sink for the body: {}", route_.pattern, e.what());
      return send(error_response(500, "internal_error", "the body cannot be taken"), true);
    }
    if (!sink_) {  // the route refused it from its head: answered unread, then closed
      keep_alive_ = false;
      return dispatch();
    }
    if (!body_follows) return dispatch();
    read_body_now();
  }

  // Pieces of about a mebibyte go to the sink, each once the last was taken; the client's
  // deadline stands still while the sink works.
  void hand_piece() {
    std::string piece = std::move(parser_->get().body());
    parser_->get().body().clear();
    lowest().expires_never();
    const auto handed = std::chrono::steady_clock::now();
    sink_->write(std::move(piece), [self = self(), handed](bool taken) {
      net::dispatch(self->stream_.get_executor(), [self, handed, taken] {
        if (!taken)
          return self->send(error_response(507, "insufficient_storage",
                                           "the coordinator could not store the body"),
                            true);
        self->body_deadline_ += std::chrono::steady_clock::now() - handed;
        if (self->parser_->is_done()) return self->dispatch();
        self->read_body_more();
      });
    });
  }

  void release_body_budget() {
    if (budget_held_ == 0) return;
    shared_->body_budget.release(budget_held_);
    budget_held_ = 0;
  }

  // The client waits for this before sending a body it announced with Expect.
  void do_continue() {
    static constexpr std::string_view kContinue = "HTTP/1.1 100 Continue\r\n\r\n";
    phase_ = Phase::writing;
    lowest().expires_after(shared_->options.write_timeout);
    net::async_write(stream_, net::buffer(kContinue.data(), kContinue.size()),
                     [self = self()](error_code ec, std::size_t) {
                       if (ec) return self->close();
                       self->do_read_body();
                     });
  }

  void do_read_body() {
    phase_ = Phase::body;
    body_deadline_ = std::chrono::steady_clock::now() + shared_->options.body_timeout;
    read_body_more();
  }

  // The body's deadline moves out by what arrives at the minimum rate: an honest upload
  // of any size finishes, one that trickles in is cut off (as Apache's MinRate does).
  void read_body_more() {
    lowest().expires_at(body_deadline_);
    http::async_read_some(
        stream_, buffer_, *parser_, [self = self()](error_code ec, std::size_t bytes) {
          if (ec) return self->on_read_body(ec);
          if (self->sink_ &&
              (self->parser_->is_done() || self->parser_->get().body().size() >= kStreamPiece))
            return self->hand_piece();
          if (self->parser_->is_done()) return self->on_read_body(ec);
          self->body_deadline_ +=
              std::chrono::microseconds(bytes * 1'000'000 / self->shared_->options.min_body_rate);
          self->read_body_more();
        });
  }

  void on_read_body(error_code ec) {
    if (ec) release_body_budget();
    if (ec == http::error::body_limit)
      return send(too_large(route_.body_limit.value_or(shared_->options.default_body_limit)), true);
    if (ec) return on_read_error(ec, "body");
    dispatch();
  }

  void on_read_error(error_code ec, const char* what) {
    // A message that does not parse: say so, then close, since where the next one would
    // begin is unknown. Anything else (timeouts, resets, end of stream) leaves no one to tell.
    if (ec.category() == http::make_error_code(http::error::end_of_stream).category() &&
        ec != http::error::end_of_stream && ec != http::error::partial_message)
      return send(malformed_request(ec.message()), true);
    spdlog::debug("http {}: reading the {} failed: {}", remote_address_, what, ec.message());
    close();
  }

  HttpResponse too_large(std::size_t limit) const {
    const auto announced = parser_ ? parser_->content_length() : boost::none;
    return body_too_large(announced ? std::optional<std::uint64_t>(*announced) : std::nullopt,
                          limit);
  }

  void dispatch();

  void send(HttpResponse response, bool close_after) {
    if (phase_ == Phase::closed || phase_ == Phase::closing) return;
    close_after = close_after || stopping();
    if (response.status < 100 || response.status > 599) {
      spdlog::error("http {} {}: handler answered with status {}", route_.pattern, path_,
                    response.status);
      response = error_response(500, "internal_error", "the handler answered an invalid status");
    }
    if (shared_->options.metrics) {
      // Refused before its header was read: no route, no method, no time.
      const bool headed = request_started_ != std::chrono::steady_clock::time_point{};
      const double seconds =
          headed
              ? std::chrono::duration<double>(std::chrono::steady_clock::now() - request_started_)
                    .count()
              : 0.0;
      shared_->options.metrics->record(headed && route_.handler ? route_.pattern : "", method_,
                                       response.status, seconds);
    }
    request_started_ = {};
    method_.clear();
    if (response.stream) return start_stream(std::move(response));
    answer_.emplace(response_message(std::move(response), head_only_, close_after,
                                     route_.pattern.empty() ? path_ : route_.pattern));
    std::visit([&](auto& message) { write(message, close_after); }, *answer_);
  }

  template <typename Message>
  void write(Message& message, bool close_after) {
    phase_ = Phase::writing;
    lowest().expires_after(shared_->options.write_timeout);
    http::async_write(stream_, message,
                      beast::bind_front_handler(&BasicHttpSession::on_write, self(), close_after));
  }

  void on_write(bool close_after, error_code ec, std::size_t) {
    answer_.reset();
    if (ec) {
      spdlog::debug("http {}: writing the response failed: {}", remote_address_, ec.message());
      return close();
    }
    if (close_after) return linger();
    do_wait_for_request();
  }

  void on_shut_down() {
    if (phase_ == Phase::streaming) return streamer_->end();
    if (phase_ == Phase::idle) close();
    // Otherwise the current request finishes, and stopping() ends the connection after it.
  }

  void start_stream(HttpResponse response) {
    phase_ = Phase::streaming;
    std::weak_ptr<HttpSession> weak = weak_from_this();
    streamer_ = std::make_unique<StreamWriter<Stream>>(
        stream_, std::weak_ptr<void>(weak), std::move(response.stream),
        shared_->options.write_timeout, [this] { return stopping(); }, [this] { close(); });
    streamer_->start(stream_header(response));
  }

  // Half-closes, then discards what the client still sends until it closes too: closing
  // with unread bytes would make the kernel send a reset, which can destroy the response
  // before the client has read it (a 413 sent while the client is still uploading).
  void linger() {
    phase_ = Phase::closing;
    error_code ec;
    lowest().socket().shutdown(tcp::socket::shutdown_send, ec);
    if (ec) return close();
    lowest().expires_after(kLingerTime);
    do_drain();
  }

  void do_drain() {
    if (!drain_) drain_ = std::make_unique<std::array<char, 4096>>();
    // From the TCP stream even under TLS: what is discarded need not be decrypted, and a
    // refused plain-HTTP client's bytes are no TLS at all.
    lowest().async_read_some(net::buffer(*drain_), [self = self()](error_code ec, std::size_t) {
      if (ec) return self->close();
      self->do_drain();
    });
  }

  void note_waiting() {
    waiting_since_us = std::chrono::duration_cast<std::chrono::microseconds>(
                           std::chrono::steady_clock::now().time_since_epoch())
                           .count();
  }

  void close() {
    phase_ = Phase::closed;
    error_code ec;
    lowest().socket().shutdown(tcp::socket::shutdown_both, ec);
    lowest().close();
  }

  std::shared_ptr<net::ssl::context> tls_;  // before stream_, which uses it; null for plain
  Stream stream_;
  std::shared_ptr<ServerShared> shared_;
  beast::flat_buffer buffer_;
  std::optional<http::request_parser<http::string_body>> parser_;
  std::optional<WireMessage> answer_;               // alive while being written
  std::unique_ptr<std::array<char, 4096>> drain_;   // only while lingering
  std::unique_ptr<std::string> refusal_;            // to a client of the other protocol
  std::unique_ptr<StreamWriter<Stream>> streamer_;  // only while streaming a body
  static constexpr std::size_t kStreamPiece = 1 << 20;
  std::shared_ptr<BodySink> sink_;  // the streamed body's, for a route that has one
  std::size_t budget_held_ = 0;     // of shared_->body_budget, for the body being read or served
  std::string remote_address_;
  Phase phase_ = Phase::idle;
  bool first_request_ = true;
  bool keep_alive_ = true;
  bool head_only_ = false;          // HEAD: the GET route's answer, without its body
  std::size_t header_scanned_ = 0;  // of buffer_, looked through for the header's end
  std::chrono::steady_clock::time_point body_deadline_;
  // The request being served.
  std::string path_;
  std::string method_;                                     // of the request being answered
  std::chrono::steady_clock::time_point request_started_;  // when its header was read
  std::map<std::string, std::string> query_;
  RouteMatch route_;
};

template <typename Stream>
void BasicHttpSession<Stream>::dispatch() {
  phase_ = Phase::handler;
  waiting_since_us = 0;
  HttpRequest request = plain_request(parser_->get());
  request.path = std::move(path_);
  request.query = std::move(query_);
  request.params = std::move(route_.params);
  request.remote_address = remote_address_;
  request.body_sink = std::move(sink_);
  parser_.reset();
  // A body is read through buffer_, which then keeps its largest size (64 KiB): with a
  // thousand workers parked on a claim, that memory would idle with them. Empty, it is
  // given back; the next request's first read allocates a small one again.
  if (buffer_.size() == 0) buffer_.shrink_to_fit();

  auto pending = std::make_shared<PendingResponse>(
      [self = self()](HttpResponse response) { self->deliver(std::move(response)); }, shared_->io);
  Respond respond = [pending](HttpResponse response) { pending->answer(std::move(response)); };
  try {
    (*route_.handler)(std::move(request), std::move(respond));
  } catch (const std::exception& e) {
    spdlog::error("http {}: handler threw: {}", route_.pattern, e.what());
    pending->answer(error_response(500, "internal_error", "internal error"));
  }
  request.body = std::string();  // what the handler did not take of it
}

void start_http_session(tcp::socket socket, std::shared_ptr<ServerShared> shared,
                        const std::string& peer) {
  if (auto tls = shared->tls_context())
    return std::make_shared<BasicHttpSession<TlsStream>>(std::move(socket), std::move(shared),
                                                         std::move(tls))
        ->start(peer);
  std::make_shared<BasicHttpSession<PlainStream>>(std::move(socket), std::move(shared))
      ->start(peer);
}

void shut_down_sessions(ServerShared& shared) {
  // Collected first and told outside the lock: dropping what may be the last reference
  // runs a session's destructor, which takes the lock.
  std::vector<std::shared_ptr<HttpSession>> open;
  {
    std::lock_guard lock(shared.mutex);
    for (auto& [raw, entry] : shared.sessions)
      if (auto session = entry.session.lock()) open.push_back(std::move(session));
  }
  for (const auto& session : open) session->shut_down();
}

}  // namespace tessera
