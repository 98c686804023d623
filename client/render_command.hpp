#pragma once

#include <CLI/CLI.hpp>

namespace tessera {

// Registers `tessera render`: renders a scene file on this machine, without a server.
void add_render_command(CLI::App& app);

}  // namespace tessera
