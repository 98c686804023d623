#include "bench/coordinator_load/simulated_worker.hpp"

#include "common/protocol/leases.hpp"
#include "common/protocol/paths.hpp"
#include "common/protocol/workers.hpp"

namespace tessera::load {

using error_code = boost::system::error_code;

void LoadState::fail(const std::string& what) {
  if (finished) return;
  record_error(what);
  if (on_error) on_error();
}

void LoadState::record_error(const std::string& what) {
  if (errors++ == 0) first_error = what;
}

SimulatedWorker::SimulatedWorker(boost::asio::io_context& io,
                                 const boost::asio::ip::tcp::endpoint& server,
                                 const std::string& authorization, LoadState& state, int number)
    : http_(io, server, authorization),
      heartbeat_timer_(io),
      render_timer_(io),
      state_(state),
      name_("load-" + std::to_string(number)) {}

void SimulatedWorker::stop() {
  heartbeat_timer_.cancel();
  render_timer_.cancel();
  http_.close();
}

void SimulatedWorker::start() {
  http_.connect([this](const error_code& ec) {
    if (ec) return state_.fail(name_ + ": connect: " + ec.message());
    do_register();
  });
}

void SimulatedWorker::do_register() {
  static const std::string json_header = "Content-Type: application/json\r\n";
  // Kept in a member: the body must outlive the request.
  register_body_ = protocol::to_json(protocol::WorkerRegistration{name_, "load", 1}).dump();
  http_.request(
      "POST", std::string(protocol::route::workers), json_header, register_body_,
      [this](const error_code& ec, int status, std::string_view body) {
        if (ec || status != 201)
          return state_.fail(name_ + ": register: " + (ec ? ec.message() : std::to_string(status)));
        protocol::Registration reply;
        try {
          reply = protocol::read_body<protocol::Registration>(body);
        } catch (const protocol::ProtocolError& e) {
          return state_.fail(name_ + ": register: " + e.what());
        }
        id_ = reply.id;
        secret_ = reply.secret;
        claim_headers_ =
            json_header + std::string(protocol::kWorkerSecretHeader) + ": " + secret_ + "\r\n";
        state_.heartbeat_interval =
            std::chrono::milliseconds(static_cast<long>(reply.heartbeat_interval_s * 1000));
        claim_target_ = protocol::claim_target(id_, state_.claim_wait_s, state_.max_tiles);
        do_claim();
      });
}

void SimulatedWorker::do_claim() {
  if (state_.finished) return;
  timed_ = state_.timing;
  claim_sent_ = std::chrono::steady_clock::now();
  http_.request("POST", claim_target_, claim_headers_, {},
                [this](const error_code& ec, int status, std::string_view body) {
                  if (state_.finished) return;
                  if (ec) return state_.fail(name_ + ": claim: " + ec.message());
                  on_claim(status, body);
                });
  if (!parked_once_) {
    parked_once_ = true;
    if (state_.on_parked) state_.on_parked();
  }
}

void SimulatedWorker::on_claim(int status, std::string_view body) {
  if (status == 204) {
    ++state_.empty_claims;
    return do_claim();
  }
  if (status != 200) return state_.fail(name_ + ": claim answered " + std::to_string(status));
  if (timed_)
    state_.claim_latency_ms.push_back(
        std::chrono::duration<float, std::milli>(std::chrono::steady_clock::now() - claim_sent_)
            .count());
  ++state_.leases;
  protocol::Lease lease;
  try {
    lease = protocol::read_body<protocol::Lease>(body);
  } catch (const protocol::ProtocolError& e) {
    return state_.fail(name_ + ": claim: " + e.what());
  }
  lease_id_ = lease.id;
  lease_target_ = protocol::fill(protocol::route::lease_result, lease.id);
  tiles_.clear();
  for (const protocol::LeaseTile& tile : lease.tiles)
    tiles_.push_back({tile.index, static_cast<std::size_t>(tile.width) *
                                      static_cast<std::size_t>(tile.height) * 3 * sizeof(float)});
  next_tile_ = 0;
  schedule_heartbeat();
  if (state_.render_time.count() == 0) return do_upload();
  render_timer_.expires_after(state_.render_time);
  render_timer_.async_wait([this](const error_code& ec) {
    if (!ec) do_upload();
  });
}

void SimulatedWorker::schedule_heartbeat() {
  // Every interval while the lease owes tiles, as worker/lease_heartbeat.cpp does.
  heartbeat_timer_.expires_after(state_.heartbeat_interval);
  heartbeat_timer_.async_wait([this, lease = lease_id_](const error_code& ec) {
    if (ec || state_.finished || lease != lease_id_ || next_tile_ == tiles_.size()) return;
    state_.heartbeat(lease_id_, secret_);
    schedule_heartbeat();
  });
}

void SimulatedWorker::do_upload() {
  if (state_.finished) return;
  if (next_tile_ == tiles_.size()) {
    heartbeat_timer_.cancel();
    return do_claim();
  }
  // Whole tiles up to the byte limit, and always at least one (worker/tile_uploads.cpp).
  std::size_t bytes = 0;
  std::vector<std::uint64_t> indexes;
  group_end_ = next_tile_;
  while (
      group_end_ < tiles_.size() &&
      (group_end_ == next_tile_ || bytes + tiles_[group_end_].bytes <= state_.max_upload_bytes)) {
    bytes += tiles_[group_end_].bytes;
    indexes.push_back(static_cast<std::uint64_t>(tiles_[group_end_].index));
    ++group_end_;
  }
  const std::vector<std::uint64_t> rays(indexes.size(), 1000);
  upload_headers_ = "Content-Type: " + std::string(protocol::kPixelsContentType) + "\r\n" +
                    std::string(protocol::kTilesHeader) + ": " + protocol::number_list(indexes) +
                    "\r\n" + std::string(protocol::kRaysHeader) + ": " +
                    protocol::number_list(rays) + "\r\n" +
                    std::string(protocol::kWorkerSecretHeader) + ": " + secret_ + "\r\n";
  const std::span<const char> body(state_.pixels.data(), std::min(bytes, state_.pixels.size()));
  http_.request("PUT", lease_target_, upload_headers_, body,
                [this](const error_code& ec, int status, std::string_view answer) {
                  if (state_.finished) return;
                  if (ec) return state_.fail(name_ + ": upload: " + ec.message());
                  bool accepted = false;
                  try {
                    accepted = status == 200 &&
                               protocol::read_body<protocol::ResultAnswer>(answer).status ==
                                   protocol::ResultStatus::accepted;
                  } catch (const protocol::ProtocolError&) {
                  }
                  if (!accepted)
                    return state_.fail(name_ + ": upload answered " + std::to_string(status) +
                                       ": " + std::string(answer));
                  ++state_.uploads;
                  state_.tiles_accepted += group_end_ - next_tile_;
                  next_tile_ = group_end_;
                  if (state_.on_uploaded) state_.on_uploaded();
                  do_upload();
                });
}

}  // namespace tessera::load
