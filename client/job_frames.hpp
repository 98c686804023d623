// A farm job's frames on this machine: each frame's image saved where the '#' of an output
// name stand for its number (client/frame_paths.hpp), as soon as it is done, and movies of
// them (client/movie_file.hpp). For `tessera submit -o` and `tessera get`.
#pragma once

#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "common/net/coordinator_client.hpp"
#include "common/protocol/image_format.hpp"

namespace tessera {

// The frames a --frames list names, read for its syntax alone (which frames a job has is
// the coordinator's to say); none when there is no list. A list that cannot be read fails
// (client/command_failure.hpp) with kExitUsage.
std::optional<std::vector<int>> read_frames_option(const std::optional<std::string>& text);

// The frames of `list` that `asked` names, or all of them when none are, in increasing
// order. A frame the job does not render fails with kExitJobFailed, naming it.
std::vector<protocol::FrameStatus> frames_named(const protocol::FrameList& list,
                                                const std::optional<std::vector<int>>& asked,
                                                const std::string& job_id);

// The ffmpeg that encodes movies; fails with kExitUsage, saying how to install it, when
// there is none.
std::filesystem::path ffmpeg_or_fail();

// Saves one job's frames to `pattern`, each once.
class FrameDownloads {
 public:
  // Called after each frame saved, with the file it is in.
  using OnSaved = std::function<void(int frame, const std::filesystem::path& path)>;

  // `pattern`: a name with '#' for the frame number, whose extension is an image format's.
  FrameDownloads(CoordinatorClient& api, std::string job_id, std::string pattern, OnSaved on_saved);

  // Saves the frames done since the last look. The coordinator is asked which only when
  // `job` counts more frames done than were seen, so this may follow every event.
  void catch_up(const protocol::JobStatus& job);
  // Saves every frame done that is not saved yet.
  void finish();
  // One frame, done (or as far as it is rendered, with `partial`); again if saved before.
  void save(int frame, bool partial);

  // The frames saved, each with its file.
  const std::map<int, std::filesystem::path>& saved() const { return saved_; }

 private:
  void save_done(const protocol::FrameList& list);

  CoordinatorClient& api_;
  std::string job_id_;
  std::string pattern_;
  const ImageFormat* format_;
  OnSaved on_saved_;
  int seen_done_ = 0;
  std::map<int, std::filesystem::path> saved_;
};

// `tessera get JOB -o out_####.png`: the frames done of those `asked` (all of the job's
// when none are), each frame that is not yet done too with `partial`. A frame asked for
// that is not done fails with kExitJobFailed once the others are saved; with none asked,
// those not done are only mentioned. Returns the exit code.
int save_job_frames(CoordinatorClient& api, const std::string& job_id, const std::string& pattern,
                    const std::optional<std::vector<int>>& asked, bool partial);

// `tessera get JOB -o movie.mp4`: the frames `asked` (all of the job's when none are),
// every one of them done, encoded at `fps` frames a second. Returns the exit code.
int save_job_movie(CoordinatorClient& api, const std::string& job_id,
                   const std::filesystem::path& ffmpeg, const std::filesystem::path& output,
                   const std::optional<std::vector<int>>& asked, double fps);

// Encodes `frames` (PNG files, in order) into `output` and says so; fails with
// kExitJobFailed for ffmpeg's errors.
void encode_frames(const std::filesystem::path& ffmpeg,
                   const std::vector<std::filesystem::path>& frames, double fps,
                   const std::filesystem::path& output);

// Fails with kExitUsage when the folder `output` goes in is not there (a folder name with
// '#' in it is one per frame, and left to the download).
void check_output_folder(const std::filesystem::path& output);

}  // namespace tessera
