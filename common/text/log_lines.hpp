// One format for the log lines of every Tessera program, in which the message part is
// escaped (printable()): a job or worker name, a path or a peer's error can neither forge
// a line of its own nor reach the terminal of whoever tails the log as escape sequences.
#pragma once

#include <string>
#include <string_view>

namespace tessera {

// Installs that format on spdlog's default logger. Call once, early in main().
void use_escaped_log_lines();

// Instead, one JSON object per line, for a log collector (--log-format json):
//   {"time": "2026-12-05T14:00:00.123Z", "level": "info", "message": "...",
//    "job": "j-...", "worker": "w-...", "lease": "l-..."}
// `job`, `worker` and `lease` are the first job, worker and lease id the message names,
// each present only when it names one, so that a collector can select by them.
void use_json_log_lines();
// The fields use_json_log_lines() writes for one message (without the time), for tests.
std::string json_log_line(std::string_view level, std::string_view message, std::string_view time);

}  // namespace tessera
