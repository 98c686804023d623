// How a command of the CLI ends early: one line on stderr, starting "error:", and its exit
// code (client/job_commands.hpp), carried up to the command's runner by an exception.
#pragma once

#include <cstdio>
#include <string>

#include "client/job_commands.hpp"
#include "common/text/printable.hpp"

namespace tessera {

struct CommandFailed {
  int code;
};

// Text from elsewhere (a server's message, a file name) is escaped by printable().
[[noreturn]] inline void fail(int code, const std::string& message) {
  std::fprintf(stderr, "error: %s\n", printable(message).c_str());
  throw CommandFailed{code};
}

}  // namespace tessera
