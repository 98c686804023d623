// `tessera`: the command-line client.
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <string_view>

#include <CLI/CLI.hpp>

#include "client/import_command.hpp"
#include "client/job_commands.hpp"
#include "client/render_command.hpp"
#include "common/image/huge_page_malloc.hpp"
#include "common/text/printable.hpp"

namespace {

// Ends the process once a command has written all it makes, without the destructors of
// static objects, ours and those of the ~260 libraries OpenImageIO brings: after `tessera
// render` wrote its image, exit() spent 15 ms on them (docs/performance.md). Sanitized
// builds exit normally, so that LeakSanitizer still looks for leaks.
[[noreturn]] void leave(int code) {
  std::fflush(nullptr);
#ifdef __SANITIZE_ADDRESS__
  std::exit(code);
#else
  std::_Exit(code);
#endif
}

}  // namespace

int main(int argc, char** argv) {
  // Rendering loads the whole scene into memory; the other commands are small.
  if (argc > 1 && std::string_view(argv[1]) == "render")
    tessera::restart_with_huge_page_malloc(argv);
  CLI::App app{"tessera: distributed tile ray tracing"};
  app.set_version_flag("--version", "tessera " TESSERA_VERSION);
  app.require_subcommand(1);
  // The global options (--server, --json, --token...) also after the subcommand, as in
  // git, gh and kubectl: `tessera list --json`.
  app.fallthrough();
  tessera::add_render_command(app);
  tessera::add_job_commands(app);
  tessera::add_import_command(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::RuntimeError& e) {
    leave(e.get_exit_code());  // a command's own exit code, already reported
  } catch (const CLI::CallForHelp& e) {
    leave(app.exit(e));  // the help asked for, on stdout
  } catch (const CLI::CallForAllHelp& e) {
    leave(app.exit(e));
  } catch (const CLI::CallForVersion& e) {
    leave(app.exit(e));
  } catch (const CLI::ParseError& e) {
    // One line, as every other error (README, "Exit codes"): CLI11's own print adds a second
    // line of advice.
    std::string message = e.what();
    while (!message.empty() && (message.back() == '\n' || message.back() == ' '))
      message.pop_back();
    for (char& c : message)
      if (c == '\n') c = ' ';
    std::fprintf(stderr, "error: %s (tessera --help lists the commands)\n",
                 tessera::printable(message).c_str());
    leave(2);  // every usage error is exit code 2, as documented
  } catch (const std::exception& e) {
    // Whatever a command did not turn into a message itself: still one line, never abort().
    std::fprintf(stderr, "error: %s\n", tessera::printable(e.what()).c_str());
    leave(1);
  }
  leave(0);
}
