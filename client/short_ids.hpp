// Ids as people type them: a unique prefix of a job's id ("j-3f9a", or "3f9a") or of a
// worker's, or a worker's name.
#pragma once

#include <stdexcept>
#include <string>

#include "common/net/coordinator_client.hpp"

namespace tessera {

// No job or worker is named so, or more than one is: says which, listing the candidates.
class UnknownId : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The whole id of the one job whose id begins with `text` ("j-" may be left out), or else
// of the one job named `text`. A whole id is taken as it is, without asking.
std::string resolve_job_id(CoordinatorClient& api, const std::string& text);
// The id of the one worker whose id begins with `text` ("w-" may be left out), or whose
// name is `text`.
std::string resolve_worker_id(CoordinatorClient& api, const std::string& text);
// The first characters of an id, enough to tell it apart among a farm's jobs or workers
// (ids are random: 8 hex digits leave a collision among 10,000 jobs at about 1 in 900).
std::string short_id(const std::string& id);

}  // namespace tessera
