#include "client/job_image.hpp"

#include <cstdio>
#include <filesystem>
#include <system_error>

#include "client/command_failure.hpp"
#include "client/output_file.hpp"
#include "common/text/printable.hpp"

namespace tessera {

const ImageFormat& image_output_format(const std::string& output) {
  std::error_code ec;
  if (std::filesystem::is_directory(output, ec))
    fail(kExitUsage, output + " is a directory; name the image file, such as " +
                         (std::filesystem::path(output) / "image.png").string());
  const ImageFormat* format = image_format_of_path(output);
  if (!format)
    fail(kExitUsage, output + ": unknown image extension (use " + image_format_names(true) +
                         ", or .mp4, .mkv or .mov for a movie of an animation's frames)");
  return *format;
}

void save_image(CoordinatorClient& api, const std::string& id, const std::string& output,
                bool partial, std::optional<int> frame) {
  const ImageFormat& format = image_output_format(output);
  OutputFile file(output);
  std::string bytes;
  try {
    bytes = frame ? api.frame_image(id, *frame, format, partial) : api.image(id, format, partial);
  } catch (const ApiError& e) {
    if (e.status() != 409 || partial) throw;
    if (frame)
      fail(kExitJobFailed, "frame " + std::to_string(*frame) + " of job " + id +
                               " is not done; `tessera get " + id + " --frames " +
                               std::to_string(*frame) + " --partial -o " + output +
                               "` gets the tiles rendered so far");
    fail(kExitJobFailed, "job " + id + " has not completed; `tessera get " + id + " --partial -o " +
                             output + "` gets the tiles rendered so far");
  }
  file.commit(bytes);
  std::printf("wrote %s\n", printable(std::filesystem::absolute(output).string()).c_str());
}

}  // namespace tessera
