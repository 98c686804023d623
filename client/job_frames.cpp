#include "client/job_frames.hpp"

#include <algorithm>
#include <cstdio>
#include <utility>

#include "client/command_failure.hpp"
#include "client/frame_paths.hpp"
#include "client/movie_file.hpp"
#include "client/output_file.hpp"
#include "common/scene/animation.hpp"
#include "common/scene/frame_list.hpp"
#include "common/text/printable.hpp"

namespace tessera {
namespace {

namespace fs = std::filesystem;
using protocol::FrameState;
using protocol::FrameStatus;

std::vector<int> numbers_of(const std::vector<FrameStatus>& frames) {
  std::vector<int> numbers;
  for (const FrameStatus& frame : frames) numbers.push_back(frame.frame);
  return numbers;
}

// "frame 4" or "frames 4-6,9".
std::string frames_text(const std::vector<int>& frames) {
  return (frames.size() == 1 ? "frame " : "frames ") + format_frame_list(frames);
}

// Frames that are not done, by what they are instead: "rendering 4, pending 5-6".
std::string states_text(const std::vector<FrameStatus>& frames) {
  std::string text;
  for (const auto& [state, name] : protocol::kFrameStateNames) {
    std::vector<int> in_state;
    for (const FrameStatus& frame : frames)
      if (frame.state == state) in_state.push_back(frame.frame);
    if (in_state.empty()) continue;
    text += (text.empty() ? "" : ", ") + std::string(name) + " " + format_frame_list(in_state);
  }
  return text;
}

std::string absolute_text(const fs::path& path) { return printable(fs::absolute(path).string()); }

}  // namespace

std::optional<std::vector<int>> read_frames_option(const std::optional<std::string>& text) {
  if (!text) return std::nullopt;
  try {
    // Every frame number a scene may have, as many as there are.
    return parse_frame_list(*text, 0, max_frame_number, std::size_t{max_frame_number} + 1);
  } catch (const FrameListError& e) {
    fail(kExitUsage, std::string("--frames: ") + e.what());
  }
}

std::vector<FrameStatus> frames_named(const protocol::FrameList& list,
                                      const std::optional<std::vector<int>>& asked,
                                      const std::string& job_id) {
  std::vector<FrameStatus> all = list.frames;
  std::sort(all.begin(), all.end(),
            [](const FrameStatus& a, const FrameStatus& b) { return a.frame < b.frame; });
  if (!asked) return all;
  std::vector<FrameStatus> named;
  std::vector<int> foreign;
  for (const int frame : *asked) {
    const auto found = std::lower_bound(
        all.begin(), all.end(), frame,
        [](const FrameStatus& status, int number) { return status.frame < number; });
    if (found != all.end() && found->frame == frame)
      named.push_back(*found);
    else
      foreign.push_back(frame);
  }
  if (!foreign.empty())
    fail(kExitJobFailed, frames_text(foreign) + (foreign.size() == 1 ? " is" : " are") +
                             " not among the frames of job " + job_id + " (" +
                             format_frame_list(numbers_of(all)) + ")");
  return named;
}

fs::path ffmpeg_or_fail() {
  try {
    return find_ffmpeg();
  } catch (const MovieError& e) {
    fail(kExitUsage, e.what());
  }
}

void check_output_folder(const fs::path& output) {
  const fs::path folder = output.parent_path();
  if (folder.empty() || has_frame_number(folder.string())) return;
  std::error_code error;
  if (!fs::is_directory(folder, error))
    fail(kExitUsage, "cannot write " + output.string() + ": there is no folder " + folder.string());
}

FrameDownloads::FrameDownloads(CoordinatorClient& api, std::string job_id, std::string pattern,
                               OnSaved on_saved)
    : api_(api),
      job_id_(std::move(job_id)),
      pattern_(std::move(pattern)),
      format_(image_format_of_path(frame_path(pattern_, 0))),
      on_saved_(std::move(on_saved)) {
  if (!format_)
    fail(kExitUsage, pattern_ + ": unknown image extension (use " + image_format_names(true) + ")");
}

void FrameDownloads::catch_up(const protocol::JobStatus& job) {
  if (job.frames.done > seen_done_) save_done(api_.frames(job_id_));
}

void FrameDownloads::finish() { save_done(api_.frames(job_id_)); }

void FrameDownloads::save_done(const protocol::FrameList& list) {
  int done = 0;
  for (const FrameStatus& frame : list.frames) {
    if (frame.state != FrameState::done) continue;
    ++done;
    if (!saved_.contains(frame.frame)) save(frame.frame, false);
  }
  seen_done_ = done;
}

void FrameDownloads::save(int frame, bool partial) {
  const fs::path path = frame_path(pattern_, frame);
  OutputFile file(path);
  file.commit(api_.frame_image(job_id_, frame, *format_, partial));
  saved_[frame] = path;
  if (on_saved_) on_saved_(frame, path);
}

int save_job_frames(CoordinatorClient& api, const std::string& job_id, const std::string& pattern,
                    const std::optional<std::vector<int>>& asked, bool partial) {
  const std::vector<FrameStatus> frames = frames_named(api.frames(job_id), asked, job_id);
  FrameDownloads downloads(api, job_id, pattern, [](int frame, const fs::path& path) {
    std::printf("frame %d: wrote %s\n", frame, absolute_text(path).c_str());
    std::fflush(stdout);
  });
  std::vector<FrameStatus> missing;
  for (const FrameStatus& frame : frames) {
    if (frame.state == FrameState::done) downloads.save(frame.frame, false);
    // A frame no worker has begun is black all over: only when it is asked for by name.
    else if (partial && (asked || frame.state != FrameState::pending))
      downloads.save(frame.frame, true);
    else
      missing.push_back(frame);
  }
  if (missing.empty()) return kExitOk;
  const std::string which = frames_text(numbers_of(missing)) + " of job " + job_id +
                            (missing.size() == 1 ? " is" : " are") + " not done (" +
                            states_text(missing) + ")";
  const std::string hint = "`tessera get " + job_id + " --partial -o " + pattern +
                           "` gets them as far as they are rendered";
  if (asked) fail(kExitJobFailed, which + "; " + hint);
  if (downloads.saved().empty())
    fail(kExitJobFailed, "no frame of job " + job_id + " is done yet; " + hint);
  std::fprintf(stderr, "note: %s, and not saved\n", printable(which).c_str());
  return kExitOk;
}

void encode_frames(const fs::path& ffmpeg, const std::vector<fs::path>& frames, double fps,
                   const fs::path& output) {
  try {
    encode_movie(ffmpeg, frames, fps, output);
  } catch (const MovieError& e) {
    fail(kExitJobFailed, e.what());
  }
  std::printf("wrote %s: %zu frames at %g fps\n", absolute_text(output).c_str(), frames.size(),
              fps);
}

int save_job_movie(CoordinatorClient& api, const std::string& job_id, const fs::path& ffmpeg,
                   const fs::path& output, const std::optional<std::vector<int>>& asked,
                   double fps) {
  const std::vector<FrameStatus> frames = frames_named(api.frames(job_id), asked, job_id);
  std::vector<FrameStatus> missing;
  for (const FrameStatus& frame : frames)
    if (frame.state != FrameState::done) missing.push_back(frame);
  if (!missing.empty())
    fail(kExitJobFailed, "a movie needs every frame done, and " + frames_text(numbers_of(missing)) +
                             " of job " + job_id + (missing.size() == 1 ? " is" : " are") +
                             " not (" + states_text(missing) + ")");
  std::optional<TemporaryFolder> folder;
  try {
    folder.emplace("tessera-frames-");
  } catch (const MovieError& e) {
    fail(kExitJobFailed, e.what());
  }
  FrameDownloads downloads(api, job_id, (folder->path() / "frame_#######.png").string(),
                           [](int frame, const fs::path&) {
                             std::printf("frame %d: downloaded\n", frame);
                             std::fflush(stdout);
                           });
  std::vector<fs::path> paths;
  for (const FrameStatus& frame : frames) {
    downloads.save(frame.frame, false);
    paths.push_back(downloads.saved().at(frame.frame));
  }
  encode_frames(ffmpeg, paths, fps, output);
  return kExitOk;
}

}  // namespace tessera
