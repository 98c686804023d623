// Secrets (API and worker tokens) from where they do not show in a process list: a file
// or an environment variable, or a command-line value for convenience.
#pragma once

#include <string>

namespace tessera {

// The first of: `value` when not empty, the contents of the file at `file` when not empty
// (trailing white space removed), the environment variable `env` when set. "" when none
// is given. Throws std::runtime_error, naming `what`, for a file that cannot be read or
// holds nothing, or for a secret with white space or control characters in it.
std::string resolve_secret(const std::string& value, const std::string& file, const char* env,
                           const std::string& what);

// What to warn of a secret's file that others than its owner may read (its mode grants the
// group or everyone any access): "" when it is private, or when there is no file.
std::string loose_secret_file(const std::string& file, const std::string& what);

}  // namespace tessera
