// Whether the coordinator should be sent traffic, for GET /readyz. Liveness (/healthz)
// only says the process answers; a load balancer or a Kubernetes Service also needs to
// know when to stop routing to a coordinator that is shutting down, while it still
// answers the requests already on their way.
#pragma once

#include <atomic>

namespace tessera {

class Readiness {
 public:
  enum class State { starting, ready, draining };

  // Start-up is over: the database is open and the Scheduler has reconciled it. Only
  // from `starting`, so that a late call cannot undo a shutdown that has begun.
  void mark_ready() {
    State expected = State::starting;
    state_.compare_exchange_strong(expected, State::ready);
  }
  // Shutdown has begun; there is no way back.
  void mark_draining() { state_ = State::draining; }

  State state() const { return state_; }

 private:
  std::atomic<State> state_{State::starting};
};

}  // namespace tessera
