#include "client/import_command.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>

#include <nlohmann/json.hpp>

#include "client/job_commands.hpp"
#include "common/scn/scn_import.hpp"
#include "common/text/printable.hpp"

namespace tessera {
namespace {

struct ImportOptions {
  std::string scene_path;
  std::string output_path;
  int width = ScnImportOptions{}.width;
  int height = ScnImportOptions{}.height;
};

int fail(int code, const std::string& message) {
  std::fprintf(stderr, "error: %s\n", printable(message).c_str());
  return code;
}

// Written beside the output and renamed into place, so that a failed write leaves no
// half-written scene and an older one stays whole.
int write_scene(const std::filesystem::path& output, const nlohmann::json& scene) {
  const std::filesystem::path part = output.string() + ".part";
  std::ofstream out(part, std::ios::binary | std::ios::trunc);
  if (!out)
    return fail(kExitUsage, "cannot write " + output.string() + ": " + std::strerror(errno));
  out << scene.dump(2) << '\n';
  out.close();
  std::error_code error;
  if (out) std::filesystem::rename(part, output, error);
  if (!out || error) {
    std::filesystem::remove(part, error);
    return fail(kExitJobFailed, "cannot write " + output.string());
  }
  std::printf("wrote %s\n", printable(std::filesystem::absolute(output).string()).c_str());
  return kExitOk;
}

int run_import(const ImportOptions& options) {
  std::filesystem::path output = options.output_path;
  if (output.empty()) output = std::filesystem::path(options.scene_path).stem().string() + ".json";
  std::error_code error;
  if (std::filesystem::is_directory(output, error))
    return fail(kExitUsage, output.string() + " is a directory; name the JSON file");
  ScnImportOptions import;
  import.width = options.width;
  import.height = options.height;
  import.output_dir = output.parent_path();
  import.warn = [](const std::string& warning) {
    std::fprintf(stderr, "warning: %s\n", printable(warning).c_str());
};
nlohmann::json scene;
try {
  scene = import_scn(options.scene_path, import);
} catch (const ScnError& e) {
  return fail(kExitUsage, e.what());  // names the file and line
} catch (const std::invalid_argument& e) {
  return fail(kExitUsage, e.what());
}
return write_scene(output, scene);
}  // namespace

}  // namespace tessera

void add_import_command(CLI::App& app) {
  auto options = std::make_shared<ImportOptions>();
  CLI::App* command =
      app.add_subcommand("import", "Convert a COS 426 .scn scene file into a JSON scene");
  command->add_option("scene", options->scene_path, "Scene file (.scn)")->required();
  command->add_option("-o,--output", options->output_path,
                      "Output JSON file (default: SCENE's name with .json, here)");
  command->add_option("--width", options->width, "Image width (default 640)")
      ->check(CLI::Range(1, 16384));
  command->add_option("--height", options->height, "Image height (default 480)")
      ->check(CLI::Range(1, 16384));
  command->final_callback([options] {
    const int code = run_import(*options);
    if (code != 0) throw CLI::RuntimeError(code);
  });
}

}  // namespace tessera
