// One format for the log lines of every Tessera program, in which the message part is
// escaped (printable()): a job or worker name, a path or a peer's error can neither forge
// a line of its own nor reach the terminal of whoever tails the log as escape sequences.
#pragma once

namespace tessera {

// Installs that format on spdlog's default logger. Call once, early in main().
void use_escaped_log_lines();

}  // namespace tessera
