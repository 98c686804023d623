// Writes a streamed body (server-sent events) to one connection. A header because it is a
// template over the session's stream; only http_session.cpp includes it.
#pragma once

#include <algorithm>
#include <array>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <utility>

#include <boost/asio/post.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/asio/write.hpp>
#include <boost/beast/core.hpp>

#include "server/http/http_types.hpp"

namespace tessera {

// The header, then what the BodyStream has whenever it has something, a keep-alive when it
// had nothing for a while, until the peer goes, the stream ends or the server stops. A peer
// that stops reading is ended once a write has waited longer than `write_timeout`. Kept
// apart from the session so that its state (the timer, the text being written) lives only
// while a stream does; everything runs on the connection's strand.
template <typename Stream>
class StreamWriter {
 public:
  // `owner` (the session) is kept alive by every wait; `stopping` says the server stops;
  // `on_end` runs once, when the stream ends for any reason, and closes the connection.
  StreamWriter(Stream& stream, std::weak_ptr<void> owner, std::shared_ptr<BodyStream> body,
               std::chrono::steady_clock::duration write_timeout, std::function<bool()> stopping,
               std::function<void()> on_end)
      : stream_(stream),
        owner_(std::move(owner)),
        body_(std::move(body)),
        write_timeout_(write_timeout),
        stopping_(std::move(stopping)),
        on_end_(std::move(on_end)),
        timer_(stream.get_executor()) {}

  void start(std::string header) {
    auto& lowest = boost::beast::get_lowest_layer(stream_);
    lowest.expires_never();
    // What the kernel holds for a peer that stops reading is bounded too, not only the
    // stream's queue: the system's autotuning would let a thousand stalled subscribers
    // hold 4 MiB each.
    boost::beast::error_code ignored;
    lowest.socket().set_option(boost::asio::socket_base::send_buffer_size(kSendBuffer), ignored);
    watch_peer();
    write(std::move(header));
  }

  // From the strand: the server stops, or the peer went.
  void end() {
    if (ended_) return;
    ended_ = true;
    body_->cancel();
    ++generation_;
    timer_.cancel();
    on_end_();
  }

 private:
  static constexpr int kSendBuffer = 128 * 1024;  // the kernel doubles it

  // Called only from a handler the owner's lifetime covers, so `this` is alive with it.
  std::shared_ptr<void> owner() const { return owner_.lock(); }

  void write(std::string text) {
    writing_ = true;
    out_ = std::move(text);
    write_started_ = std::chrono::steady_clock::now();
    arm_keepalive();  // which also catches a write that waits too long
    boost::asio::async_write(stream_, boost::asio::buffer(out_),
                             [this, keep = owner()](boost::beast::error_code ec, std::size_t) {
                               writing_ = false;
                               if (ec) return end();
                               pump();
                             });
  }

  void pump() {
    if (ended_ || writing_) return;
    if (stopping_()) return end();
    bool finished = false;
    std::string text = body_->take(finished);
    if (!text.empty()) return write(std::move(text));
    if (finished) return end();
    arm_keepalive();
    // Weak: a stream with nothing to say must not keep a closed connection alive.
    body_->wait([this, weak = owner_] {
      if (auto keep = weak.lock())
        boost::asio::post(stream_.get_executor(), [this, keep] { pump(); });
    });
  }

  void on_keepalive() {
    if (ended_) return;
    if (!writing_) return write(body_->keepalive());
    // A write still waiting on a peer that does not read.
    if (std::chrono::steady_clock::now() - write_started_ > write_timeout_) return end();
    arm_keepalive();
  }

  // The timer of on_keepalive(), from now; an earlier one is forgotten.
  void arm_keepalive() {
    const std::uint64_t generation = ++generation_;
    timer_.expires_after(
        std::min<std::chrono::steady_clock::duration>(body_->keepalive_interval(), write_timeout_));
    timer_.async_wait([this, keep = owner(), generation](boost::beast::error_code ec) {
      if (!ec && generation == generation_) on_keepalive();
    });
  }

  // A stream's peer sends nothing; a read that ends says it went.
  void watch_peer() {
    stream_.async_read_some(boost::asio::buffer(discard_),
                            [this, keep = owner()](boost::beast::error_code ec, std::size_t) {
                              if (ec) return end();
                              watch_peer();
                            });
  }

  Stream& stream_;
  std::weak_ptr<void> owner_;
  std::shared_ptr<BodyStream> body_;
  std::chrono::steady_clock::duration write_timeout_;
  std::function<bool()> stopping_;
  std::function<void()> on_end_;
  boost::asio::steady_timer timer_;
  std::uint64_t generation_ = 0;
  std::string out_;  // alive while being written
  bool writing_ = false;
  bool ended_ = false;
  std::chrono::steady_clock::time_point write_started_;
  std::array<char, 512> discard_{};
};

}  // namespace tessera
