// A request's answer-to-be, shared by every copy of its Respond (http_types.hpp).
#pragma once

#include <utility>  // before Asio: Boost 1.74 with GCC 12 in C++20 needs it

#include <atomic>
#include <functional>

#include <boost/asio/executor_work_guard.hpp>
#include <boost/asio/io_context.hpp>

#include "server/http/http_types.hpp"

namespace tessera {

// It keeps the io_context running while a handler works elsewhere (a long-poll must not
// let io.run() return), and answers 500 if the last copy disappears unanswered, so a
// buggy handler cannot leave a client waiting forever.
class PendingResponse {
 public:
  // `deliver` sends the answer on its connection, once.
  PendingResponse(std::function<void(HttpResponse)> deliver, boost::asio::io_context& io);
  ~PendingResponse();
  PendingResponse(const PendingResponse&) = delete;
  PendingResponse& operator=(const PendingResponse&) = delete;

  // The first answer goes out; a second is dropped, and said so in the log.
  void answer(HttpResponse response);

 private:
  std::function<void(HttpResponse)> deliver_;
  boost::asio::executor_work_guard<boost::asio::io_context::executor_type> work_;
  std::atomic<bool> answered_{false};
};

}  // namespace tessera
