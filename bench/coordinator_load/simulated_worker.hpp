// A worker that renders nothing: it registers, claims leases with `max_tiles` as
// tessera-worker does, and uploads constant pixels of the right size for every tile at
// once, in groups of at most the worker's upload limit, with X-Tessera-Tiles and
// X-Tessera-Rays. What it sends is worker/worker_daemon.cpp's requests, without the time
// spent rendering between them.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <boost/asio/steady_timer.hpp>

#include "bench/coordinator_load/http_connection.hpp"

namespace tessera::load {

// What every simulated worker shares: settings, the phase of the run and the tallies.
struct LoadState {
  int max_tiles = 256;
  std::size_t max_upload_bytes = 16u << 20;  // worker/worker_daemon.cpp's kMaxUploadBytes
  int claim_wait_s = 20;
  // How long each lease is "rendered" before its tiles are uploaded: 0 for as fast as the
  // coordinator allows; tessera-worker sizes its batches to about half a second.
  std::chrono::milliseconds render_time{0};
  std::vector<char> pixels;  // constant float32 bytes, at least max_upload_bytes

  bool timing = false;    // claims sent from now on are timed
  bool finished = false;  // the job is done: no more requests
  std::uint64_t tiles_accepted = 0;
  std::uint64_t uploads = 0;
  std::uint64_t leases = 0;
  std::uint64_t empty_claims = 0;  // answered 204: no work within the wait
  std::uint64_t heartbeats = 0;
  std::uint64_t heartbeats_lost = 0;  // answered other than 200
  std::uint64_t errors = 0;
  std::string first_error;
  std::vector<float> claim_latency_ms;  // timed claims answered with a lease

  std::chrono::milliseconds heartbeat_interval{5000};  // from the registration's answer
  // Sends one, proven by the worker's secret.
  std::function<void(const std::string& lease_id, const std::string& secret)> heartbeat;
  std::function<void()> on_parked;    // a worker has sent its first claim
  std::function<void()> on_uploaded;  // tiles_accepted grew
  std::function<void()> on_error;     // the first error: the run stops
  // Counts an error, unless the run has already stopped (its aborted requests fail too).
  void fail(const std::string& what);
  // Counts an error whatever the phase.
  void record_error(const std::string& what);
};

class SimulatedWorker {
 public:
  SimulatedWorker(boost::asio::io_context& io, const boost::asio::ip::tcp::endpoint& server,
                  const std::string& authorization, LoadState& state, int number);
  void start();
  void stop();

 private:
  struct Tile {
    int index;
    std::size_t bytes;
  };
  void do_register();
  void do_claim();
  void on_claim(int status, std::string_view body);
  void do_upload();
  void schedule_heartbeat();

  HttpConnection http_;
  boost::asio::steady_timer heartbeat_timer_;
  boost::asio::steady_timer render_timer_;
  LoadState& state_;
  std::string name_;
  std::string id_;
  std::string secret_;         // from the registration, sent with every later request
  std::string claim_headers_;  // with the secret
  std::string claim_target_;
  bool parked_once_ = false;
  bool timed_ = false;
  std::chrono::steady_clock::time_point claim_sent_;
  std::string lease_id_;
  std::string lease_target_;  // "/v1/leases/ID/result"
  std::vector<Tile> tiles_;
  std::size_t next_tile_ = 0;  // first tile not yet uploaded
  std::size_t group_end_ = 0;  // one past the last tile of the upload in flight
  std::string upload_headers_;
  std::string register_body_;
};

}  // namespace tessera::load
