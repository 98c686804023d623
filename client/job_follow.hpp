// Following a farm job from the CLI until it finishes (`tessera submit --wait`, `watch`):
// its progress drawn as it changes, by the farm's events or, from an older coordinator, by
// long polls; and the exit code its end gives.
#pragma once

#include <unistd.h>
#include <chrono>
#include <cstdio>
#include <functional>
#include <optional>
#include <string>

#include "client/job_tables.hpp"
#include "common/net/coordinator_client.hpp"
#include "common/protocol/jobs.hpp"
#include "common/text/printable.hpp"

namespace tessera {

// A job's progress as it changes: a redrawn bar on a terminal, plain lines otherwise (at
// most one a second, and the last). For an animation, the tiles of the frame it finishes
// next are asked of the coordinator only for a line about to be shown.
class ProgressPrinter {
 public:
  ProgressPrinter(CoordinatorClient& api, std::string id) : api_(api), id_(std::move(id)) {}

  void show(const protocol::JobStatus& job) {
    using clock = std::chrono::steady_clock;
    const bool done = is_finished(job.state);
    if (tty_) {
      drawn_ = progress_line(job, true, frame_tiles(job));
      std::printf("\r%s\033[K%s", drawn_.c_str(), done ? "\n" : "");
      if (done) drawn_.clear();
    } else if (done || clock::now() - printed_ >= std::chrono::seconds(1)) {
      const std::string line = progress_line(job, false, frame_tiles(job));
      if (line != last_) {
        std::printf("%s\n", line.c_str());
        last_ = line;
        printed_ = clock::now();
      }
    }
    std::fflush(stdout);
  }

  // A line of its own, such as a file written; on a terminal, above the bar.
  void note(const std::string& line) {
    if (tty_ && !drawn_.empty()) std::printf("\r\033[K");
    std::printf("%s\n", printable(line).c_str());
    if (tty_ && !drawn_.empty()) std::printf("%s", drawn_.c_str());
    std::fflush(stdout);
  }

 private:
  std::optional<protocol::JobStatus::Tiles> frame_tiles(const protocol::JobStatus& job) {
    using clock = std::chrono::steady_clock;
    if (job.frames.total <= 1 || !job.frames.current || !frames_served_) return std::nullopt;
    // A bar redrawn at every event asks four times a second at most.
    if (asked_frame_ == *job.frames.current &&
        clock::now() - asked_ < std::chrono::milliseconds(250))
      return tiles_;
    tiles_.reset();
    try {
      for (const protocol::FrameStatus& frame : api_.frames(id_).frames)
        if (frame.frame == *job.frames.current) tiles_ = frame.tiles;
    } catch (const ApiError&) {
      frames_served_ = false;  // the progress is shown without them
    } catch (const protocol::ProtocolError&) {
      frames_served_ = false;
    }
    asked_frame_ = *job.frames.current;
    asked_ = clock::now();
    return tiles_;
  }

  CoordinatorClient& api_;
  std::string id_;
  const bool tty_ = ::isatty(STDOUT_FILENO);
  std::string last_;
  std::string drawn_;  // the bar on the terminal now, if any
  std::chrono::steady_clock::time_point printed_{};
  bool frames_served_ = true;
  int asked_frame_ = -1;
  std::chrono::steady_clock::time_point asked_{};
  std::optional<protocol::JobStatus::Tiles> tiles_;
};

// Called with each status of a job followed, after it is shown.
using OnUpdate = std::function<void(const protocol::JobStatus&)>;

// Follows a job by long polls, each waiting on the server for the job to finish: for a
// coordinator without events (an older build).
protocol::JobStatus poll_until_finished(CoordinatorClient& api, const std::string& id,
                                        ProgressPrinter& printer, const OnUpdate& on_update);

// Follows a job until it finishes, by the farm's events (GET /v1/events): its status each
// time it changes, four times a second at most, and its end at once. The job's status is
// read once the stream is open, and again after a "resync"; a stream that breaks is
// resumed after the last event seen.
protocol::JobStatus watch(CoordinatorClient& api, const std::string& id, ProgressPrinter& printer,
                          const OnUpdate& on_update = {});

// kExitOk for a completed job; else what went wrong on stderr, and kExitJobFailed.
int job_exit_code(const protocol::JobStatus& job);

}  // namespace tessera
