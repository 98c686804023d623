#include "bench/coordinator_load/simulated_worker.hpp"

#include "common/protocol_limits.hpp"

#include <nlohmann/json.hpp>

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
  register_body_ =
      nlohmann::json{
          {"name", name_}, {"host", "load"}, {"threads", 1}, {"protocol", kWorkerProtocolVersion}}
          .dump();
  http_.request("POST", "/v1/workers", json_header, register_body_,
                [this](const error_code& ec, int status, std::string_view body) {
    if (ec || status != 201)
      return state_.fail(name_ + ": register: " + (ec ? ec.message() : std::to_string(status)));
    const nlohmann::json reply = nlohmann::json::parse(body);
    id_ = reply.at("id").get<std::string>();
    state_.heartbeat_interval = std::chrono::milliseconds(
        static_cast<long>(reply.value("heartbeat_interval_s", 5.0) * 1000));
    claim_target_ = "/v1/workers/" + id_ + "/claim?wait_s=" + std::to_string(state_.claim_wait_s) +
                    "&max_tiles=" + std::to_string(state_.max_tiles);
    do_claim();
  });
}

void SimulatedWorker::do_claim() {
  if (state_.finished) return;
  timed_ = state_.timing;
  claim_sent_ = std::chrono::steady_clock::now();
  http_.request("POST", claim_target_, "", {},
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
        std::chrono::duration<float, std::milli>(std::chrono::steady_clock::now() - claim_sent_).count());
  ++state_.leases;
  const nlohmann::json lease = nlohmann::json::parse(body);
  lease_target_ = "/v1/leases/" + lease.at("id").get<std::string>() + "/result";
  tiles_.clear();
  for (const nlohmann::json& tile : lease.at("tiles"))
    tiles_.push_back({tile.at("index").get<int>(),
                      tile.at("width").get<std::size_t>() * tile.at("height").get<std::size_t>() * 3 *
                          sizeof(float)});
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
  heartbeat_timer_.async_wait([this, lease = lease_target_](const error_code& ec) {
    if (ec || state_.finished || lease != lease_target_ || next_tile_ == tiles_.size()) return;
    // "/v1/leases/ID/result" -> "ID"
    const std::size_t start = std::string("/v1/leases/").size();
    state_.heartbeat(lease_target_.substr(start, lease_target_.rfind('/') - start));
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
  std::string indexes;
  std::string rays;
  group_end_ = next_tile_;
  while (group_end_ < tiles_.size() &&
         (group_end_ == next_tile_ || bytes + tiles_[group_end_].bytes <= state_.max_upload_bytes)) {
    bytes += tiles_[group_end_].bytes;
    if (!indexes.empty()) {
      indexes += ',';
      rays += ',';
    }
    indexes += std::to_string(tiles_[group_end_].index);
    rays += "1000";
    ++group_end_;
  }
  upload_headers_ = "Content-Type: application/octet-stream\r\nX-Tessera-Tiles: " + indexes +
                    "\r\nX-Tessera-Rays: " + rays + "\r\n";
  const std::span<const char> body(state_.pixels.data(), std::min(bytes, state_.pixels.size()));
  http_.request("PUT", lease_target_, upload_headers_, body,
                [this](const error_code& ec, int status, std::string_view answer) {
    if (state_.finished) return;
    if (ec) return state_.fail(name_ + ": upload: " + ec.message());
    if (status != 200 || answer.find("\"accepted\"") == std::string_view::npos)
      return state_.fail(name_ + ": upload answered " + std::to_string(status) + ": " +
                         std::string(answer));
    ++state_.uploads;
    state_.tiles_accepted += group_end_ - next_tile_;
    next_tile_ = group_end_;
    if (state_.on_uploaded) state_.on_uploaded();
    do_upload();
  });
}

}  // namespace tessera::load
