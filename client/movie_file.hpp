// Movies from frames: a sequence of images encoded by Debian's ffmpeg, which Tessera runs
// as a program of its own when it is installed (it is not needed otherwise).
#pragma once

#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

namespace tessera {

// What went wrong, in words for the user: ffmpeg missing (and how to install it), or
// ffmpeg's own last lines.
class MovieError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A folder of its own under the system's temporary folder, removed with what it holds.
class TemporaryFolder {
 public:
  // `prefix`: the start of its name. Throws MovieError when it cannot be made.
  explicit TemporaryFolder(const std::string& prefix);
  ~TemporaryFolder();
  TemporaryFolder(const TemporaryFolder&) = delete;
  TemporaryFolder& operator=(const TemporaryFolder&) = delete;
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

// .mp4, .mkv or .mov (any case): a name that frames are encoded into.
bool is_movie_path(const std::filesystem::path& path);

// The ffmpeg on PATH; a MovieError that says how to install it when there is none.
std::filesystem::path find_ffmpeg();

// Encodes `frames` (PNG files, in the order shown) into `output` at `fps` frames a second:
// H.264 in 4:2:0, an odd width or height padded by one pixel, as players expect.
// `output` is written whole or not at all: ffmpeg writes a file beside it, renamed once
// done. Throws MovieError.
void encode_movie(const std::filesystem::path& ffmpeg,
                  const std::vector<std::filesystem::path>& frames, double fps,
                  const std::filesystem::path& output);

}  // namespace tessera
