#include "common/net/http_client.hpp"

#include <utility>  // before Asio: Boost 1.74 with GCC 12 in C++20 needs it

#include <algorithm>
#include <atomic>
#include <cctype>
#include <charconv>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <mutex>
#include <optional>
#include <set>
#include <stdexcept>
#include <type_traits>

#include <openssl/err.h>
#include <openssl/ssl.h>
#include <openssl/x509v3.h>
#include <boost/asio/connect.hpp>
#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/ssl.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/http/buffer_body.hpp>
#include <boost/beast/http/file_body.hpp>
#include <boost/beast/ssl.hpp>

#include "common/net/client_tls.hpp"
#include "common/text/ascii_case.hpp"

namespace tessera {

namespace net = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
using tcp = net::ip::tcp;
using error_code = beast::error_code;

namespace {

// Beast 1.74 speaks boost::string_view.
beast::string_view to_beast(std::string_view text) { return {text.data(), text.size()}; }

std::string lower(beast::string_view text) {
  return ascii_lower(std::string_view(text.data(), text.size()));
}

// The server closed a kept-alive connection before (or while) we reused it: harmless,
// the request can go again on a new connection.
bool is_closed_by_peer(const error_code& ec) {
  return ec == http::error::end_of_stream || ec == net::error::eof ||
         ec == net::error::connection_reset || ec == net::error::broken_pipe ||
         ec == net::error::connection_aborted || ec == net::ssl::error::stream_truncated;
}

}  // namespace

namespace {

std::string host_header_of(const BaseUrl& url) {
  const bool v6 = url.host.find(':') != std::string::npos;
  return (v6 ? "[" + url.host + "]" : url.host) + ":" + std::to_string(url.port);
}

std::string where_of(const BaseUrl& url) {
  return (url.tls ? "https://" : "http://") + host_header_of(url);
}

}  // namespace

struct HttpClient::Connection {
  Connection(BaseUrl base, std::chrono::milliseconds limit,
             std::shared_ptr<net::ssl::context> tls_context)
      : url(std::move(base)),
        host_header(host_header_of(url)),
        timeout(limit),
        tls(std::move(tls_context)),
        plain(io) {}

  // Runs one asynchronous operation to completion on the private io_context: the
  // asynchronous form is what gives tcp_stream its timeouts.
  template <typename Start>
  error_code run(Start start) {
    error_code result;
    start([&result](error_code ec, auto&&...) { result = ec; });
    io.restart();
    io.run();
    return result;
  }

  std::string where() const { return where_of(url); }

  // The TCP stream under everything: timeouts, cancel, close.
  beast::tcp_stream& lowest() { return secure ? beast::get_lowest_layer(*secure) : plain; }
  // Calls f with the stream requests go over: TLS or plain.
  template <typename F>
  auto with_stream(F&& f) {
    return secure ? f(*secure) : f(plain);
  }

  void connect() {
    tcp::resolver resolver(io);
    error_code ec;
    const auto endpoints = resolver.resolve(url.host, std::to_string(url.port), ec);
    if (ec)
      throw HttpError(HttpError::Kind::connect_failed,
                      "cannot resolve " + url.host + ": " + ec.message());
    // A TLS session is not reused across connections: each gets a stream of its own.
    if (tls) secure.emplace(io, *tls);
    lowest().expires_after(timeout);
    ec = run([&](auto handler) { lowest().async_connect(endpoints, std::move(handler)); });
    if (ec == beast::error::timeout)
      throw HttpError(HttpError::Kind::timeout, "connecting to " + where() + " timed out after " +
                                                    std::to_string(timeout.count()) + " ms");
    if (ec)
      throw HttpError(HttpError::Kind::connect_failed,
                      "cannot connect to " + where() + ": " + ec.message());
    lowest().socket().set_option(tcp::no_delay(true), ec);
    if (secure) handshake();
    buffer.clear();
    open = true;
  }

  // Verifies the peer's chain (the context's verify_peer) and that it names url.host.
  void handshake() {
    SSL* ssl = secure->native_handle();
    error_code ec;
    net::ip::make_address(url.host, ec);  // fails for a DNS name
    X509_VERIFY_PARAM* param = SSL_get0_param(ssl);
    X509_VERIFY_PARAM_set_hostflags(param, X509_CHECK_FLAG_NO_PARTIAL_WILDCARDS);
    const bool named = ec ? X509_VERIFY_PARAM_set1_host(param, url.host.c_str(), 0) == 1
                          : X509_VERIFY_PARAM_set1_ip_asc(param, url.host.c_str()) == 1;
    // SNI, for a proxy that serves several names; not for an address.
    if (!named || (ec && SSL_set_tlsext_host_name(ssl, url.host.c_str()) != 1)) {
      close();
      throw HttpError(HttpError::Kind::tls, "cannot set up TLS for " + where());
    }
    lowest().expires_after(timeout);
    ec = run([&](auto handler) {
      secure->async_handshake(net::ssl::stream_base::client, std::move(handler));
    });
    if (!ec) return;
    const std::string why = ec == beast::error::timeout
                                ? "TLS handshake with " + where() + " timed out"
                                : handshake_failure(ssl, ec, where());
    close();
    throw HttpError(ec == beast::error::timeout ? HttpError::Kind::timeout : HttpError::Kind::tls,
                    why);
  }

  void close() {
    error_code ignored;
    // No TLS close_notify: the connection is dropped either way, and waiting for the
    // peer's would only add a round trip.
    lowest().socket().shutdown(tcp::socket::shutdown_both, ignored);
    lowest().close();
    secure.reset();
    buffer.clear();
    open = false;
  }

  struct Outcome {
    std::optional<HttpResult> result;
    error_code error;
    bool got_some = false;  // some of an answer arrived before the error
  };

  // Writes the request in one go within the timeout, or, with `progress` (a file's
  // upload), a piece at a time, each within the timeout, calling it (where set) after each.
  template <typename Body>
  error_code write(http::request<Body>& request, const HttpClient::UploadProgress* progress) {
    lowest().expires_after(timeout);
    if (progress == nullptr)
      return run([&](auto handler) {
        with_stream([&](auto& stream) { http::async_write(stream, request, std::move(handler)); });
      });
    http::request_serializer<Body> serializer(request);
    const std::uint64_t total = request.payload_size().value_or(0);
    std::uint64_t written = 0;  // the header's bytes too: a few hundred, in a count of millions
    while (!serializer.is_done()) {
      lowest().expires_after(timeout);
      std::size_t bytes = 0;
      const error_code ec = run([&](auto handler) {
        with_stream([&](auto& stream) {
          http::async_write_some(stream, serializer,
                                 [&bytes, handler](error_code e, std::size_t n) mutable {
                                   bytes = n;
                                   handler(e);
                                 });
        });
      });
      if (ec) return ec;
      written += bytes;
      if (*progress) (*progress)(std::min(written, total), total);
    }
    return {};
  }

  template <typename Body>
  Outcome exchange(http::request<Body>& request, const HttpClient::UploadProgress* progress,
                   const std::filesystem::path* into) {
    Outcome outcome;
    const error_code write_error = write(request, progress);
    // A piecewise upload's answer has a timeout of its own; else one covers both.
    if (progress != nullptr) lowest().expires_after(timeout);
    if (write_error == beast::error::timeout) {
      outcome.error = write_error;
      return outcome;
    }
    // Even when the write failed, the server may have answered first (a 413 sent before
    // the whole body arrived), so read what is there.
    if (into != nullptr) return read_answer<http::file_body>(request, write_error, into);
    return read_answer<http::string_body>(request, write_error, nullptr);
  }

  // The answer to `request` read as stream() does.
  Outcome stream_answer(http::request<http::empty_body>& request,
                        const HttpClient::OnData& on_data) {
    Outcome outcome;
    if (const error_code ec = write(request, nullptr)) {
      outcome.error = ec;
      return outcome;
    }
    http::response_parser<http::buffer_body> parser;
    parser.body_limit(std::numeric_limits<std::uint64_t>::max());
    parser.header_limit(64 * 1024);
    lowest().expires_after(timeout);
    error_code ec = run([&](auto handler) {
      with_stream([&](auto& stream) {
        http::async_read_header(stream, buffer, parser, std::move(handler));
      });
    });
    if (ec) {
      outcome.error = ec;
      outcome.got_some = parser.got_some();
      return outcome;
    }
    HttpResult result;
    result.status = static_cast<int>(parser.get().result_int());
    for (const auto& field : parser.get()) {
      auto [it, inserted] = result.headers.try_emplace(lower(field.name_string()), field.value());
      if (!inserted) it->second.append(", ").append(field.value().data(), field.value().size());
    }
    const bool taken = result.status >= 200 && result.status < 300;
    std::vector<char> piece(16 * 1024);
    while (!parser.is_done()) {
      parser.get().body().data = piece.data();
      parser.get().body().size = piece.size();
      lowest().expires_after(timeout);
      ec = run([&](auto handler) {
        with_stream([&](auto& stream) {
          http::async_read_some(stream, buffer, parser, std::move(handler));
        });
      });
      if (ec == http::error::need_buffer) ec = {};
      const std::size_t got = piece.size() - parser.get().body().size;
      if (got > 0) {
        if (!taken) {
          if (result.body.size() < 64 * 1024) result.body.append(piece.data(), got);
        } else if (!on_data(std::string_view(piece.data(), got))) {
          break;
        }
      }
      if (ec == http::error::end_of_stream) break;  // a body that runs until the close
      if (ec) {
        outcome.error = ec;
        outcome.got_some = true;
        close();
        return outcome;
      }
    }
    close();
    outcome.result = std::move(result);
    return outcome;
  }

  template <typename ResponseBody>
  Outcome read_answer(const http::request_header<>& request, error_code write_error,
                      const std::filesystem::path* into) {
    Outcome outcome;
    http::response_parser<ResponseBody> parser;
    // Not boost::none: Beast 1.74 compares a Content-Length with an empty limit as exceeding it.
    parser.body_limit(std::numeric_limits<std::uint64_t>::max());
    parser.header_limit(64 * 1024);
    if (request.method() == http::verb::head) parser.skip(true);
    if constexpr (std::is_same_v<ResponseBody, http::file_body>) {
      error_code ec;
      parser.get().body().open(into->c_str(), beast::file_mode::write, ec);
      if (ec) throw std::runtime_error("cannot write " + into->string() + ": " + ec.message());
    }
    const error_code read_error = run([&](auto handler) {
      with_stream(
          [&](auto& stream) { http::async_read(stream, buffer, parser, std::move(handler)); });
    });
    if (read_error) {
      outcome.error = write_error ? write_error : read_error;
      if (read_error == beast::error::timeout) outcome.error = read_error;
      outcome.got_some = parser.got_some();
      return outcome;
    }
    auto& response = parser.get();
    HttpResult result;
    result.status = static_cast<int>(response.result_int());
    for (const auto& field : response) {
      auto [it, inserted] = result.headers.try_emplace(lower(field.name_string()), field.value());
      if (!inserted) it->second.append(", ").append(field.value().data(), field.value().size());
    }
    if constexpr (std::is_same_v<ResponseBody, http::file_body>) {
      response.body().close();
      if (result.status < 200 || result.status >= 300) {
        std::ifstream error_body(*into, std::ios::binary);
        result.body.resize(64 * 1024);
        error_body.read(result.body.data(), static_cast<std::streamsize>(result.body.size()));
        result.body.resize(static_cast<std::size_t>(error_body.gcount()));
        std::error_code ignored;
        std::filesystem::remove(*into, ignored);
      }
    } else {
      result.body = std::move(response.body());
    }
    if (write_error || !response.keep_alive()) close();
    outcome.result = std::move(result);
    return outcome;
  }

  BaseUrl url;
  std::string host_header;
  std::chrono::milliseconds timeout;
  std::shared_ptr<net::ssl::context> tls;  // null for http://
  net::io_context io;
  beast::tcp_stream plain;                                     // http://; after io, which it uses
  std::optional<beast::ssl_stream<beast::tcp_stream>> secure;  // https://, while connected
  beast::flat_buffer buffer;
  bool open = false;
};

// The connections of one client: those kept alive between requests, and those a request
// is using, which interrupt() reaches.
struct HttpClient::Pool {
  Pool(BaseUrl base, std::chrono::milliseconds limit, const TlsSettings& settings)
      : url(std::move(base)),
        where(where_of(url)),
        timeout(limit),
        tls(url.tls ? client_tls_context(settings.ca_file) : nullptr) {}

  // A connection for one request, back in the pool however the request ends.
  struct Taken {
    explicit Taken(Pool& from) : pool(from), connection(from.take(taken_in)) {}
    ~Taken() { pool.give_back(std::move(connection), taken_in); }
    Taken(const Taken&) = delete;
    Taken& operator=(const Taken&) = delete;
    Pool& pool;
    std::uint64_t taken_in = 0;
    std::unique_ptr<Connection> connection;
  };

  // Also the interrupt generation it is taken in, which give_back() compares.
  std::unique_ptr<Connection> take(std::uint64_t& taken_in) {
    std::unique_ptr<Connection> c;
    {
      std::lock_guard lock(mutex);
      if (!idle.empty()) {
        c = std::move(idle.back());
        idle.pop_back();
      }
    }
    if (!c) c = std::make_unique<Connection>(url, timeout.load(), tls);
    c->timeout = timeout.load();
    std::lock_guard lock(mutex);
    busy.insert(c.get());
    taken_in = interrupts;
    return c;
  }

  // Kept for the next request while it is open; a connection an interrupt may have reached
  // is not kept (the cancel posted to it could still be queued).
  void give_back(std::unique_ptr<Connection> c, std::uint64_t taken_in) {
    std::lock_guard lock(mutex);
    busy.erase(c.get());
    if (c->open && !interrupted && interrupts == taken_in) idle.push_back(std::move(c));
  }

  BaseUrl url;
  std::string where;
  std::uint64_t interrupts = 0;  // interrupt() calls so far, under the mutex
  std::atomic<std::chrono::milliseconds> timeout;
  std::atomic<bool> interrupted{false};
  std::shared_ptr<net::ssl::context> tls;  // one for every connection; null for http://
  std::mutex mutex;
  std::vector<std::unique_ptr<Connection>> idle;
  std::set<Connection*> busy;
};

HttpClient::HttpClient(std::string base_url, std::chrono::milliseconds timeout,
                       const TlsSettings& tls)
    : base_url_(std::move(base_url)),
      pool_(std::make_unique<Pool>(parse_base_url(base_url_), timeout, tls)) {}

HttpClient::~HttpClient() = default;
HttpClient::HttpClient(HttpClient&&) noexcept = default;
HttpClient& HttpClient::operator=(HttpClient&&) noexcept = default;

void HttpClient::set_timeout(std::chrono::milliseconds timeout) { pool_->timeout = timeout; }

void HttpClient::set_bearer_token(std::string token) {
  authorization_ = token.empty() ? "" : "Bearer " + token;
}

void HttpClient::interrupt() {
  std::lock_guard lock(pool_->mutex);
  pool_->interrupted = true;
  ++pool_->interrupts;
  // Posting is what io_context allows from another thread; the cancel then runs on the
  // requesting thread, inside its run(), and aborts the operation under way.
  for (Connection* c : pool_->busy) net::post(c->io, [c] { c->lowest().cancel(); });
  pool_->idle.clear();
}

void HttpClient::clear_interrupt() { pool_->interrupted = false; }

template <typename Message>
void HttpClient::prepare(Message& message, std::string_view method, std::string_view target,
                         bool has_body, std::string_view content_type,
                         const Headers& headers) const {
  message.version(11);
  const http::verb verb = http::string_to_verb(to_beast(method));
  if (verb == http::verb::unknown)
    message.method_string(to_beast(method));
  else
    message.method(verb);
  message.target(to_beast(target));
  message.set(http::field::user_agent, "tessera");
  // Also on a bodiless POST or PUT: the coordinator requires it of every request that
  // changes state, since a web page cannot send it to another site without asking.
  const bool changes =
      verb == http::verb::post || verb == http::verb::put || verb == http::verb::patch;
  if ((has_body || changes) && !content_type.empty())
    message.set(http::field::content_type, to_beast(content_type));
  if (!authorization_.empty()) message.set(http::field::authorization, authorization_);
  for (const auto& [name, value] : headers) message.set(name, value);
}

HttpResult HttpClient::request(std::string_view method, std::string_view target, std::string body,
                               std::string_view content_type, const Headers& headers) {
  http::request<http::string_body> message;
  prepare(message, method, target, !body.empty(), content_type, headers);
  message.body() = std::move(body);
  message.prepare_payload();
  return send(message, method, target, nullptr, [] {});
}

HttpResult HttpClient::send_file(std::string_view method, std::string_view target,
                                 const std::filesystem::path& path, std::string_view content_type,
                                 const UploadProgress& progress, const Headers& headers) {
  http::request<http::file_body> message;
  prepare(message, method, target, true, content_type, headers);
  error_code ec;
  message.body().open(path.c_str(), beast::file_mode::scan, ec);
  if (ec) throw std::runtime_error("cannot open " + path.string() + ": " + ec.message());
  message.prepare_payload();
  auto& file = message.body();
  return send(message, method, target, &progress, [&file] {
    error_code ignored;
    file.file().seek(0, ignored);
  });
}

HttpResult HttpClient::stream(std::string_view target, const OnData& on_data,
                              const Headers& headers) {
  http::request<http::empty_body> message;
  prepare(message, "GET", target, false, "", headers);
  message.set(http::field::accept, "text/event-stream");
  message.prepare_payload();
  if (pool_->interrupted)
    throw HttpError(HttpError::Kind::interrupted, "GET " + std::string(target) + ": interrupted");
  const Pool::Taken taken(*pool_);
  Connection& c = *taken.connection;
  if (message.find(http::field::host) == message.end())
    message.set(http::field::host, c.host_header);
  // A connection of its own: a kept-alive one may have been closed meanwhile, and a stream
  // is not sent twice.
  if (c.open) c.close();
  c.connect();
  Connection::Outcome outcome = c.stream_answer(message, on_data);
  if (outcome.result) {
    if (observer_ && !outcome.result->body.empty()) observer_("GET", target, *outcome.result);
    return std::move(*outcome.result);
  }
  const std::string what = "GET " + std::string(target) + " on " + c.where();
  if (outcome.error == beast::error::timeout)
    throw HttpError(HttpError::Kind::timeout,
                    what + ": nothing within " + std::to_string(c.timeout.count()) + " ms");
  throw HttpError(HttpError::Kind::protocol,
                  what + ": connection failed: " + outcome.error.message());
}

HttpResult HttpClient::receive_file(std::string_view method, std::string_view target,
                                    const std::filesystem::path& into, const Headers& headers) {
  http::request<http::empty_body> message;
  prepare(message, method, target, false, "", headers);
  message.prepare_payload();
  return send(
      message, method, target, nullptr, [] {}, &into);
}

template <typename Message>
HttpResult HttpClient::send(Message& message, std::string_view method, std::string_view target,
                            const UploadProgress* progress, const std::function<void()>& rewind,
                            const std::filesystem::path* into) {
  const auto interrupted = [&] {
    return HttpError(HttpError::Kind::interrupted, std::string(method) + " " + std::string(target) +
                                                       " on " + pool_->where + ": interrupted");
  };
  if (pool_->interrupted) throw interrupted();
  const Pool::Taken taken(*pool_);
  Connection& c = *taken.connection;
  // The caller's own Host, where it gave one (prepare()), stands.
  if (message.find(http::field::host) == message.end())
    message.set(http::field::host, c.host_header);

  for (int attempt = 0;; ++attempt) {
    if (pool_->interrupted) throw interrupted();
    const bool reused = c.open;
    if (!c.open) {
      try {
        c.connect();
      } catch (const HttpError&) {
        if (pool_->interrupted) throw interrupted();  // the interrupt canceled the connect
        throw;
      }
    }
    Connection::Outcome outcome = c.exchange(message, progress, into);
    if (outcome.result) {
      if (observer_) observer_(method, target, *outcome.result);
      return std::move(*outcome.result);
    }
    c.close();
    if (pool_->interrupted) throw interrupted();
    if (reused && attempt == 0 && !outcome.got_some && is_closed_by_peer(outcome.error)) {
      rewind();
      continue;
    }

    const std::string what = std::string(method) + " " + std::string(target) + " on " + c.where();
    if (outcome.error == beast::error::timeout)
      throw HttpError(HttpError::Kind::timeout,
                      what + ": no answer within " + std::to_string(c.timeout.count()) + " ms");
    if (outcome.error.category() == http::make_error_code(http::error::end_of_stream).category() &&
        outcome.error != http::error::end_of_stream &&
        outcome.error != http::error::partial_message)
      throw HttpError(HttpError::Kind::protocol,
                      what + ": malformed answer: " + outcome.error.message());
    throw HttpError(HttpError::Kind::protocol,
                    what + ": connection failed: " + outcome.error.message());
  }
}

}  // namespace tessera
