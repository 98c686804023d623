// A job's state, as the API, the CLI and the database write it.
#pragma once

#include <optional>
#include <string_view>

#include "common/protocol/names.hpp"

namespace tessera {

// paused: its tiles stay where they are, its leases run out and no new tile goes out,
// until it is resumed (to running, or queued when it had not started).
enum class JobState { queued, running, paused, completed, failed, canceled };

namespace protocol {
// The words of the API and of the database; changing one breaks both.
inline constexpr NameTable<JobState, 6> kJobStateNames{{
    {JobState::queued, "queued"},
    {JobState::running, "running"},
    {JobState::paused, "paused"},
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
// Whether its tiles go out to workers.
inline bool hands_out_tiles(JobState s) { return s == JobState::queued || s == JobState::running; }

}  // namespace tessera
