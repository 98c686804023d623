// `tessera`: the command-line client.
#include <CLI/CLI.hpp>

#include "client/job_commands.hpp"
#include "client/render_command.hpp"

int main(int argc, char** argv) {
  CLI::App app{"tessera: distributed tile ray tracing"};
  app.require_subcommand(1);
  tessera::add_render_command(app);
  tessera::add_job_commands(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  return 0;
}
