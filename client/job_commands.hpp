#pragma once

#include <CLI/CLI.hpp>

namespace tessera {

// Exit codes of every command, as documented in README.md.
enum ExitCode : int {
  kExitOk = 0,
  kExitJobFailed = 1,  // the job failed or was canceled (or another server-side refusal)
  kExitUsage = 2,      // bad arguments or an invalid scene
  kExitUnreachable = 3,
};

// Registers submit, status, watch, list, get, cancel, rm, priority, pause, resume, retry,
// workers, drain, undrain, remove-worker and health.
void add_job_commands(CLI::App& app);

}  // namespace tessera
