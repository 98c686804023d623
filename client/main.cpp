// `tessera`: the command-line client.
#include <string_view>

#include <CLI/CLI.hpp>

#include "client/job_commands.hpp"
#include "client/render_command.hpp"
#include "common/huge_page_malloc.hpp"

int main(int argc, char** argv) {
  // Rendering loads the whole scene into memory; the other commands are small.
  if (argc > 1 && std::string_view(argv[1]) == "render")
    tessera::restart_with_huge_page_malloc(argv);
  CLI::App app{"tessera: distributed tile ray tracing"};
  app.require_subcommand(1);
  tessera::add_render_command(app);
  tessera::add_job_commands(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::RuntimeError& e) {
    return e.get_exit_code();  // a command's own exit code, already reported
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);  // prints the usage error, or the help asked for
    return code == 0 ? 0 : 2;      // every usage error is exit code 2, as documented
  }
  return 0;
}
