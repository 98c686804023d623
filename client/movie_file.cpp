#include "client/movie_file.hpp"
#include "common/text/ascii_case.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string_view>

extern char** environ;

namespace tessera {
namespace {

namespace fs = std::filesystem;

// The frames as ffmpeg's image-sequence reader wants them: numbered from 0 in one folder.
// Links, not copies: the frames stay where they are.
class NumberedFrames {
 public:
  explicit NumberedFrames(const std::vector<fs::path>& frames) : dir_("tessera-movie-") {
    for (std::size_t i = 0; i < frames.size(); ++i) {
      char name[32];
      std::snprintf(name, sizeof name, "%07zu.png", i);
      std::error_code error;
      fs::create_symlink(fs::absolute(frames[i]), dir_.path() / name, error);
      if (error) throw MovieError("cannot link " + frames[i].string() + ": " + error.message());
    }
  }

  std::string pattern() const { return (dir_.path() / "%07d.png").string(); }

 private:
  TemporaryFolder dir_;
};

// Runs `argv` (argv[0] the program's path) with its standard error in a pipe; the exit
// status and the end of what it wrote there.
std::pair<int, std::string> run(const std::vector<std::string>& argv) {
  int pipe_fds[2];
  if (::pipe2(pipe_fds, O_CLOEXEC) != 0)
    throw MovieError(std::string("cannot run ffmpeg: ") + std::strerror(errno));
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, pipe_fds[1], STDERR_FILENO);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  std::vector<char*> args;
  for (const std::string& arg : argv) args.push_back(const_cast<char*>(arg.c_str()));
  args.push_back(nullptr);
  pid_t pid = 0;
  const int spawned = ::posix_spawn(&pid, argv[0].c_str(), &actions, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  ::close(pipe_fds[1]);
  if (spawned != 0) {
    ::close(pipe_fds[0]);
    throw MovieError("cannot run " + argv[0] + ": " + std::strerror(spawned));
  }
  // Kept to its last few kilobytes: the error is at the end.
  constexpr std::size_t kept = 4096;
  std::string errors;
  std::array<char, 4096> buffer{};
  while (true) {
    const ssize_t n = ::read(pipe_fds[0], buffer.data(), buffer.size());
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    errors.append(buffer.data(), static_cast<std::size_t>(n));
    if (errors.size() > 2 * kept) errors.erase(0, errors.size() - kept);
  }
  ::close(pipe_fds[0]);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (errors.size() > kept) errors.erase(0, errors.size() - kept);
  return {status, errors};
}

}  // namespace

TemporaryFolder::TemporaryFolder(const std::string& prefix) {
  std::string pattern = (fs::temp_directory_path() / (prefix + "XXXXXX")).string();
  if (::mkdtemp(pattern.data()) == nullptr)
    throw MovieError("cannot make a temporary folder: " + std::string(std::strerror(errno)));
  path_ = pattern;
}

TemporaryFolder::~TemporaryFolder() {
  std::error_code ignored;
  fs::remove_all(path_, ignored);
}

bool is_movie_path(const fs::path& path) {
  const std::string extension = ascii_lower(path.extension().string());
  return extension == ".mp4" || extension == ".mkv" || extension == ".mov";
}

fs::path find_ffmpeg() {
  const char* path = std::getenv("PATH");
  std::string_view dirs = path ? path : "";
  while (!dirs.empty()) {
    const std::size_t colon = dirs.find(':');
    const std::string_view dir = dirs.substr(0, colon);
    dirs = colon == std::string_view::npos ? std::string_view() : dirs.substr(colon + 1);
    if (dir.empty()) continue;
    const fs::path candidate = fs::path(dir) / "ffmpeg";
    if (::access(candidate.c_str(), X_OK) == 0) return candidate;
  }
  throw MovieError(
      "ffmpeg is not installed, and it encodes movies: install Debian's package (sudo apt-get "
      "install ffmpeg), or write the frames as images (-o out_####.png)");
}

void encode_movie(const fs::path& ffmpeg, const std::vector<fs::path>& frames, double fps,
                  const fs::path& output) {
  if (frames.empty()) throw MovieError("no frames to encode");
  const NumberedFrames numbered(frames);
  // Beside the movie and then renamed, so that a failure leaves no half-written file; the
  // name keeps the extension, which tells ffmpeg the container.
  const fs::path partial =
      output.parent_path() / (".tessera-partial-" + output.filename().string());
  char rate[32];
  std::snprintf(rate, sizeof rate, "%.6g", fps);
  // "file:" keeps ffmpeg from reading a name as a protocol ("http:", "pipe:"): names are
  // the user's data, never instructions.
  const auto [status, errors] =
      run({ffmpeg.string(), "-hide_banner", "-loglevel", "error", "-nostdin", "-y", "-framerate",
           rate, "-i", numbered.pattern(), "-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2", "-c:v",
           "libx264", "-pix_fmt", "yuv420p", "-r", rate, "file:" + fs::absolute(partial).string()});
  std::error_code ignored;
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    fs::remove(partial, ignored);
    throw MovieError("ffmpeg could not encode " + output.string() + ": " +
                     (errors.empty() ? std::string("it exited with an error") : errors));
  }
  std::error_code error;
  fs::rename(partial, output, error);
  if (error) {
    fs::remove(partial, ignored);
    throw MovieError("cannot write " + output.string() + ": " + error.message());
  }
}

}  // namespace tessera
