#include <array>
#include <utility>

#include "server/scheduler.hpp"

namespace tessera {
namespace {

// The words of the API and of the database; changing one breaks both.
constexpr std::array<std::pair<JobState, const char*>, 5> job_state_names{{
    {JobState::queued, "queued"},
    {JobState::running, "running"},
    {JobState::completed, "completed"},
    {JobState::failed, "failed"},
    {JobState::canceled, "canceled"},
}};

}  // namespace

const char* to_string(JobState state) {
  for (const auto& [value, name] : job_state_names)
    if (value == state) return name;
  return "unknown";
}

std::optional<JobState> job_state_from_string(std::string_view text) {
  for (const auto& [value, name] : job_state_names)
    if (text == name) return value;
  return std::nullopt;
}

}  // namespace tessera
