// A job's state, as the API, the CLI and the database write it.
#pragma once

#include <optional>
#include <string_view>

#include "common/protocol/names.hpp"

namespace tessera {

enum class JobState { queued, running, completed, failed, canceled };

namespace protocol {
// The words of the API and of the database; changing one breaks both.
inline constexpr NameTable<JobState, 5> kJobStateNames{{
    {JobState::queued, "queued"},
    {JobState::running, "running"},
    {JobState::completed, "completed"},
    {JobState::failed, "failed"},
    {JobState::canceled, "canceled"},
}};
}  // namespace protocol

inline const char* to_string(JobState state) {
  return protocol::name_in(protocol::kJobStateNames, state).data();
}
inline std::optional<JobState> job_state_from_string(std::string_view text) {
  return protocol::value_in(protocol::kJobStateNames, text);
}
inline bool is_finished(JobState s) {
  return s == JobState::completed || s == JobState::failed || s == JobState::canceled;
}

}  // namespace tessera
