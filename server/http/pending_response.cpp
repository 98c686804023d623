#include "server/http/pending_response.hpp"

#include <spdlog/spdlog.h>

namespace tessera {

PendingResponse::PendingResponse(std::function<void(HttpResponse)> deliver,
                                 boost::asio::io_context& io)
    : deliver_(std::move(deliver)), work_(boost::asio::make_work_guard(io)) {}

PendingResponse::~PendingResponse() {
  if (!answered_.exchange(true))
    deliver_(error_response(500, "internal_error", "the request was never answered"));
}

void PendingResponse::answer(HttpResponse response) {
  if (answered_.exchange(true)) {
    spdlog::warn("a request was answered twice; the second answer is dropped");
    return;
  }
  deliver_(std::move(response));
}

}  // namespace tessera
