#pragma once

#include <CLI/CLI.hpp>

namespace tessera {

// Registers `tessera import`: converts a COS 426 .scn scene file into our JSON format.
void add_import_command(CLI::App& app);

}  // namespace tessera
