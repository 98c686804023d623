#include "client/short_ids.hpp"

#include <algorithm>
#include <vector>

#include "common/text/printable.hpp"

namespace tessera {
namespace {

constexpr std::size_t kJobIdSize = 2 + 32;  // "j-" and 128 bits in hex
// Candidates listed when a prefix is ambiguous; more only make the message longer.
constexpr int kCandidatesShown = 10;

bool all_hex(std::string_view text) {
  return std::all_of(text.begin(), text.end(),
                     [](char c) { return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'); });
}

std::string with_kind(const std::string& text, const char* kind) {
  return text.starts_with(kind) ? text : kind + text;
}

[[noreturn]] void ambiguous(const std::string& what, const std::string& text,
                            const std::vector<std::string>& candidates, bool more) {
  std::string message = what + " id " + printable(text) + " is ambiguous: it begins ";
  for (std::size_t i = 0; i < candidates.size(); ++i)
    message += (i == 0 ? "" : ", ") + printable(candidates[i]);
  if (more) message += " and more";
  throw UnknownId(message + "; give more of it");
}

}  // namespace

std::string resolve_job_id(CoordinatorClient& api, const std::string& text) {
  const std::string prefix = with_kind(text, "j-");
  if (prefix.size() == kJobIdSize && all_hex(std::string_view(prefix).substr(2))) return prefix;
  if (text.empty()) throw UnknownId("a job id is empty");
  // An id's prefix first, as it is shown in lists; else the job's name, where one job has it.
  const bool id_like = all_hex(std::string_view(prefix).substr(2));
  protocol::JobList found;
  if (id_like) found = api.jobs_with_prefix(prefix, kCandidatesShown + 1);
  if (found.jobs.empty()) {
    const protocol::JobList named = api.jobs_named(text, kCandidatesShown + 1);
    if (named.jobs.size() == 1) return named.jobs.front().id;
    if (named.jobs.size() > 1) {
      std::vector<std::string> candidates;
      for (const auto& job : named.jobs)
        if (candidates.size() < kCandidatesShown) candidates.push_back(job.id);
      std::string message = "more than one job is named " + printable(text) + ": ";
      for (std::size_t i = 0; i < candidates.size(); ++i)
        message += (i == 0 ? "" : ", ") + candidates[i];
      if (named.jobs.size() > kCandidatesShown) message += " and more";
      throw UnknownId(message + "; give its id");
    }
  }
  if (found.jobs.empty()) throw UnknownId("no job " + printable(text) + ", by id or by name");
  if (found.jobs.size() == 1) return found.jobs.front().id;
  std::vector<std::string> candidates;
  for (const auto& job : found.jobs)
    if (candidates.size() < kCandidatesShown) candidates.push_back(job.id + " (" + job.name + ")");
  ambiguous("job", text, candidates, found.jobs.size() > kCandidatesShown);
}

std::string resolve_worker_id(CoordinatorClient& api, const std::string& text) {
  if (text.empty()) throw UnknownId("a worker id is empty");
  const protocol::WorkerList list = api.workers();
  const std::string prefix = with_kind(text, "w-");
  std::vector<std::string> matches;
  for (const protocol::Worker& worker : list.workers)
    if (worker.id == prefix) return worker.id;
  for (const protocol::Worker& worker : list.workers)
    if (worker.id.starts_with(prefix) || worker.name == text)
      matches.push_back(worker.id + " (" + worker.name + ")");
  if (matches.empty()) throw UnknownId("no worker " + printable(text));
  if (matches.size() == 1) return matches.front().substr(0, matches.front().find(' '));
  const bool more = matches.size() > kCandidatesShown;
  matches.resize(std::min<std::size_t>(matches.size(), kCandidatesShown));
  ambiguous("worker", text, matches, more);
}

std::string short_id(const std::string& id) {
  return id.substr(0, std::min<std::size_t>(id.size(), 10));
}

}  // namespace tessera
