#include "client/job_commands.hpp"

#include <unistd.h>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <optional>
#include <thread>

#include "client/command_failure.hpp"
#include "client/frame_paths.hpp"
#include "client/human_time.hpp"
#include "client/job_frames.hpp"
#include "client/movie_file.hpp"
#include "client/output_file.hpp"
#include "client/scene_assets.hpp"
#include "client/scene_input.hpp"
#include "client/short_ids.hpp"
#include "common/mesh_files/folder_scene_files.hpp"
#include "common/net/coordinator_client.hpp"
#include "common/protocol/events.hpp"
#include "common/protocol/image_format.hpp"
#include "common/protocol/paths.hpp"
#include "common/scene/frame_list.hpp"
#include "common/scene/scene_parser.hpp"
#include "common/text/printable.hpp"
#include "common/text/secret.hpp"

namespace tessera {
namespace {

struct Options {
  std::string server;
  std::string token;
  std::string token_file;
  std::string ca_file;
  bool json_output = false;
  // submit
  std::string scene_path;
  std::string name;
  int priority = 50;
  bool wait = false;
  std::string output;
  std::optional<std::string> frames;       // and get
  std::vector<std::string> allowed_paths;  // folders besides the scene's its files may be in
  // others
  std::string job;
  std::string state;
  int limit = 20;
  bool partial = false;
  std::optional<double> fps;
  std::string worker;
};

std::string server_url(const Options& options) {
  if (!options.server.empty()) return options.server;
  if (const char* env = std::getenv("TESSERA_SERVER"); env && *env) return env;
  return "http://127.0.0.1:8640";
}

std::string format_duration(double seconds) {
  const long s = std::lround(seconds);
  char text[32];
  if (s >= 3600)
    std::snprintf(text, sizeof text, "%ld:%02ld:%02ld", s / 3600, s / 60 % 60, s % 60);
  else
    std::snprintf(text, sizeof text, "%ld:%02ld", s / 60, s % 60);
  return text;
}

// Signs of trouble the coordinator saw on a job, when there are any: a farm that renders
// the same tiles again, or delivers nothing, must not look like a slow one.
void print_health(const protocol::JobHealth& health) {
  std::string trouble;
  const auto add = [&](const std::string& sign) {
    trouble += (trouble.empty() ? "" : ", ") + sign;
  };
  const auto count = [&](int n, const char* one, const char* many) {
    if (n > 0) add(std::to_string(n) + " " + (n == 1 ? one : many));
  };
  count(health.tile_failures, "tile failure", "tile failures");
  count(health.refused_results, "result refused", "results refused");
  count(health.repeated_handouts, "tile sent out again", "tiles sent out again");
  // Half a minute without a tile while rendering is long for any tile size people use.
  if (health.no_progress_s >= 30)
    add("no tile delivered for " + format_duration(health.no_progress_s));
  if (trouble.empty()) return;
  std::printf("  trouble: %s\n", printable(trouble).c_str());
  if (health.last_problem)
    std::printf("  last problem: %s\n", printable(*health.last_problem).c_str());
}

// At most `columns` characters of `text` (whole UTF-8 sequences), the last one "…" when it
// was cut: a long name keeps a table's columns in line.
std::string cut_to(const std::string& text, std::size_t columns) {
  std::size_t characters = 0;
  for (std::size_t at = 0; at < text.size(); ++at) {
    if ((static_cast<unsigned char>(text[at]) & 0xc0) == 0x80) continue;  // inside a sequence
    if (++characters == columns) {
      std::size_t end = at + 1;
      while (end < text.size() && (static_cast<unsigned char>(text[end]) & 0xc0) == 0x80) ++end;
      return end >= text.size() ? text : text.substr(0, at) + "\u2026";
    }
  }
  return text;
}

// A job's state as people read it: a paused job whose leases are still out is "pausing",
// its workers finishing the tiles they hold.
const char* state_words(const protocol::JobStatus& job) {
  if (job.state == JobState::paused && job.tiles.rendering > 0) return "pausing";
  return to_string(job.state);
}

void print_status(const protocol::JobStatus& job) {
  std::printf("%s  %-9s  %-20s  %3d%%  %d/%d tiles  priority %d  %dx%d\n",
              printable(job.id).c_str(), state_words(job), printable(job.name).c_str(),
              static_cast<int>(job.progress * 100), job.tiles.done, job.tiles.total, job.priority,
              job.width, job.height);
  if (job.frames.total > 1) {
    std::string frames = std::to_string(job.frames.done) + "/" + std::to_string(job.frames.total) +
                         " done of " + job.frames.list;
    if (job.frames.failed > 0) frames += ", failed " + job.frames.failed_list;
    if (job.frames.current) frames += ", next to finish " + std::to_string(*job.frames.current);
    std::printf("  frames: %s\n", printable(frames).c_str());
  }
  if (job.error) std::printf("  error: %s\n", printable(*job.error).c_str());
  print_health(job.health);
}

// One row per job under a header, the id cut to what tells it apart (any unique prefix
// works wherever a job id is asked for).
void print_job_table(const std::vector<protocol::JobStatus>& jobs) {
  const std::int64_t now = now_ms();
  std::printf("%-10s  %-20s  %-9s  %4s  %-13s  %4s  %-11s  %s\n", "ID", "NAME", "STATE", "DONE",
              "TILES", "PRIO", "SIZE", "SUBMITTED");
  for (const protocol::JobStatus& job : jobs) {
    const std::string tiles =
        std::to_string(job.tiles.done) + "/" + std::to_string(job.tiles.total);
    const std::string size = std::to_string(job.width) + "x" + std::to_string(job.height);
    // Padded by characters, not bytes, so that a name in another script stays in line.
    const std::string name = printable(cut_to(job.name, 20));
    std::size_t characters = 0;
    for (const char c : name) characters += (static_cast<unsigned char>(c) & 0xc0) != 0x80;
    std::printf("%-10s  %s%s  %-9s  %3d%%  %-13s  %4d  %-11s  %s\n",
                printable(short_id(job.id)).c_str(), name.c_str(),
                std::string(characters < 20 ? 20 - characters : 0, ' ').c_str(), state_words(job),
                static_cast<int>(job.progress * 100), tiles.c_str(), job.priority, size.c_str(),
                time_ago(job.created_at, now).c_str());
  }
}

void print_worker_table(const std::vector<protocol::Worker>& workers) {
  const std::int64_t now = now_ms();
  std::printf("%-14s  %-16s  %-15s  %-9s  %7s  %6s  %-10s  %s\n", "ID", "NAME", "HOST", "STATE",
              "THREADS", "TILES", "JOB", "LAST SEEN");
  for (const protocol::Worker& w : workers) {
    std::string state(protocol::name_in(protocol::kWorkerStateNames, w.state));
    if (w.draining) state += "*";  // draining: the footnote says so
    std::printf("%-14s  %-16s  %-15s  %-9s  %7d  %6llu  %-10s  %s\n", printable(w.id).c_str(),
                printable(w.name).c_str(), printable(w.host).c_str(), state.c_str(), w.threads,
                static_cast<unsigned long long>(w.tiles_rendered),
                printable(short_id(w.current_job.value_or("-"))).c_str(),
                time_ago(w.last_seen, now).c_str());
  }
  if (std::any_of(workers.begin(), workers.end(), [](const auto& w) { return w.draining; }))
    std::printf("* draining: takes no more tiles once its lease is done\n");
}

// What a job has done: its tiles, or for several frames the frames done and the tiles of
// the frame it finishes next (`frame_tiles`, when known).
std::string progress_count(const protocol::JobStatus& job,
                           const std::optional<protocol::JobStatus::Tiles>& frame_tiles) {
  const auto of = [](int done, int total) {
    return std::to_string(done) + "/" + std::to_string(total);
  };
  if (job.frames.total <= 1) return of(job.tiles.done, job.tiles.total) + " tiles";
  std::string count = of(job.frames.done, job.frames.total) + " frames";
  if (job.frames.failed > 0) count += ", " + std::to_string(job.frames.failed) + " failed";
  if (job.frames.current && frame_tiles)
    count += " (frame " + std::to_string(*job.frames.current) + ": " +
             of(frame_tiles->done, frame_tiles->total) + " tiles)";
  return count;
}

std::string progress_line(const protocol::JobStatus& job, bool bar,
                          const std::optional<protocol::JobStatus::Tiles>& frame_tiles) {
  const std::string eta = job.eta_s ? format_duration(*job.eta_s) : "--:--";
  char text[256];
  std::string drawn;
  if (bar) {
    constexpr int kWidth = 30;
    const int filled = static_cast<int>(job.progress * kWidth);
    drawn = "[" + std::string(filled, '#') + std::string(kWidth - filled, '.') + "] ";
  }
  std::snprintf(text, sizeof text, "%s%s %s %5.1f%%  elapsed %s  eta %s  %.2f Mrays/s",
                drawn.c_str(), to_string(job.state), progress_count(job, frame_tiles).c_str(),
                job.progress * 100, format_duration(job.elapsed_s).c_str(), eta.c_str(),
                job.stats.rays_per_s / 1e6);
  return text;
}

// ASCII only: a C1 control inside a string would reach the terminal raw otherwise.
void print_json(const nlohmann::json& body) {
  std::printf("%s\n", body.dump(2, ' ', true).c_str());
}

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
                                        ProgressPrinter& printer, const OnUpdate& on_update) {
  while (true) {
    const protocol::JobStatus job = api.job(id, 0.5);
    printer.show(job);
    if (on_update) on_update(job);
    if (is_finished(job.state)) return job;
  }
}

// Follows a job until it finishes, by the farm's events (GET /v1/events): its status each
// time it changes, four times a second at most, and its end at once. The job's status is
// read once the stream is open, and again after a "resync"; a stream that breaks is
// resumed after the last event seen.
protocol::JobStatus watch(CoordinatorClient& api, const std::string& id, ProgressPrinter& printer,
                          const OnUpdate& on_update = {}) {
  protocol::JobStatus job;
  bool finished = false;
  std::optional<std::string> last_event;
  const auto update = [&](protocol::JobStatus now) {
    job = std::move(now);
    printer.show(job);
    if (on_update) on_update(job);
    finished = is_finished(job.state);
  };
  for (int breaks = 0; !finished;) {
    bool opened = false;
    try {
      api.events(
          std::string(protocol::route::events), last_event,
          [&] {
            opened = true;
            update(api.job(id));
            return !finished;
          },
          [&](const ServerEvent& event) {
            if (!event.id.empty()) last_event = event.id;
            if (finished) return false;
            if (event.type == protocol::event::resync) {
              update(api.job(id));
            } else if (event.type == protocol::event::job) {
              const auto data = nlohmann::json::parse(event.data, nullptr, false);
              if (!data.is_object() || data.value("id", "") != id) return true;
              update(protocol::JobStatus::read(protocol::FieldReader(data)));
            } else if (event.type == protocol::event::job_removed &&
                       event.data.find("\"" + id + "\"") != std::string::npos) {
              fail(kExitJobFailed, "job " + id + " was removed");
            }
            return !finished;
          });
      // A stream that ended before it opened came from no coordinator that has events.
      if (!opened) return poll_until_finished(api, id, printer, on_update);
    } catch (const ApiError& e) {
      if (e.status() != 404) throw;
      return poll_until_finished(api, id, printer, on_update);  // a coordinator without events
    } catch (const HttpError&) {
      // The coordinator restarted, or the network broke: resumed, a few times.
      if (++breaks > 5) throw;
      std::this_thread::sleep_for(std::chrono::seconds(breaks));
    }
  }
  return job;
}

int job_exit_code(const protocol::JobStatus& job) {
  if (job.state == JobState::completed) return kExitOk;
  if (job.error)
    std::fprintf(stderr, "job %s %s: %s\n", printable(job.id).c_str(), to_string(job.state),
                 printable(*job.error).c_str());
  else
    std::fprintf(stderr, "job %s %s\n", printable(job.id).c_str(), to_string(job.state));
  if (job.frames.total > 1 && job.frames.failed > 0)
    std::fprintf(stderr, "failed frames: %s (%d of %d)\n",
                 printable(job.frames.failed_list).c_str(), job.frames.failed, job.frames.total);
  return kExitJobFailed;
}

// The format of a single image's output; fails with kExitUsage for a folder or an
// extension of no image format.
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

// The job's image, or one frame's.
void save_image(CoordinatorClient& api, const std::string& id, const std::string& output,
                bool partial, std::optional<int> frame = std::nullopt) {
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

// What submit does with its output, settled before anything is sent: a mistake in the
// command costs no render.
struct SubmitPlan {
  enum class Output { none, image, frames, movie };
  Output output = Output::none;
  std::optional<std::string> frames;  // what the submission asks for
  std::filesystem::path ffmpeg;       // a movie's
  double fps = 24;                    // a movie's: the scene's
};

SubmitPlan plan_submit(const Options& options, const Animation& animation) {
  SubmitPlan plan;
  plan.frames = options.frames;
  plan.fps = animation.fps;
  // A still scene's frames are the coordinator's to refuse: it names the field.
  std::vector<int> listed;
  if (options.frames && animation.animated) {
    try {
      listed =
          parse_frame_list(*options.frames, animation.first, animation.last, Limits{}.max_frames);
    } catch (const FrameListError& e) {
      fail(kExitUsage, std::string("--frames: ") + e.what());
    }
  }
  const std::string& output = options.output;
  if (output.empty()) return plan;
  check_output_folder(output);
  if (is_movie_path(output)) {
    if (!animation.animated)
      fail(kExitUsage, options.scene_path + ": a movie needs an animated scene (\"animation\")");
    plan.ffmpeg = ffmpeg_or_fail();  // before the render, not after it
    plan.output = SubmitPlan::Output::movie;
    return plan;
  }
  if (has_frame_number(output)) {
    if (!image_format_of_path(frame_path(output, 0)))
      fail(kExitUsage, output + ": unknown image extension (use " + image_format_names(true) + ")");
    plan.output = SubmitPlan::Output::frames;
    return plan;
  }
  image_output_format(output);
  plan.output = SubmitPlan::Output::image;
  if (!animation.animated) return plan;
  if (listed.size() > 1)
    fail(kExitUsage, output + ": " + std::to_string(listed.size()) +
                         " frames need '#' in the output's name where the frame number goes, "
                         "such as out_####.png");
  // One image of an animation is its first frame, as `tessera render` makes it: the farm
  // renders no other.
  if (!options.frames) plan.frames = std::to_string(animation.first);
  return plan;
}

int submit(const Options& options, CoordinatorClient& api) {
  nlohmann::json scene;
  Animation animation;
  const std::filesystem::path folder = std::filesystem::path(options.scene_path).parent_path();
  try {
    scene = parse_json_text(read_scene_text(options.scene_path));
    // Mistakes are reported with their JSON Pointer (and a mesh file's, with its line)
    // before anything is sent.
    // What the scene names is sent to the farm: only files inside its folder, or an
    // --allow-path, are read at all.
    const FolderSceneFiles files(folder,
                                 {options.allowed_paths.begin(), options.allowed_paths.end()});
    animation = parse_scene(scene, Limits{}, nullptr, &files).animation;
  } catch (const SceneError& e) {
    fail(kExitUsage, options.scene_path + ": " + e.what());
  } catch (const std::exception& e) {
    fail(kExitUsage, e.what());
  }
  const SubmitPlan plan = plan_submit(options, animation);
  const std::string name = options.name.empty()
                               ? std::filesystem::path(options.scene_path).stem().string()
                               : options.name;
  // The scene's mesh files go first, as assets the scene then names by digest. An asset the
  // coordinator removed between its answer and the submission (its collection of old
  // assets) is sent again, once.
  const auto send_and_submit = [&](nlohmann::json with_files) {
    try {
      const AssetUploads sent = send_scene_assets(with_files, folder, api, stderr);
      if (sent.uploaded + sent.held > 0)
        std::fprintf(stderr, "assets: %zu uploaded (%llu bytes), %zu already on the coordinator\n",
                     sent.uploaded, static_cast<unsigned long long>(sent.bytes), sent.held);
    } catch (const SceneFileError& e) {
      fail(kExitUsage, options.scene_path + ": " + e.what());
    }
    protocol::JobSubmission submission;
    submission.name = name;
    submission.priority = options.priority;
    submission.frames = plan.frames;
    submission.scene = std::move(with_files);
    return api.submit(submission);
  };
  protocol::JobStatus job;
  try {
    job = send_and_submit(scene);
  } catch (const ApiError& e) {
    if (e.code() != "missing_asset") throw;
    job = send_and_submit(std::move(scene));
  }
  const std::string id = job.id;
  const bool follow = options.wait || plan.output != SubmitPlan::Output::none;  // -o implies --wait
  if (options.json_output && !follow)
    print_json(protocol::to_json(job));
  else
    std::printf("submitted %s (%s)\n", printable(id).c_str(), printable(name).c_str());
  std::fflush(stdout);  // scripts reading the id need it now, not when --wait ends
  if (!follow) return kExitOk;
  ProgressPrinter printer(api, id);
  if (plan.output == SubmitPlan::Output::none || plan.output == SubmitPlan::Output::image) {
    const protocol::JobStatus final_job = watch(api, id, printer);
    if (options.json_output) print_json(protocol::to_json(final_job));
    const int code = job_exit_code(final_job);
    if (code == kExitOk && plan.output == SubmitPlan::Output::image)
      save_image(api, id, options.output, false);
    return code;
  }
  // Frames are saved as each is done, rather than all at the end: a long animation's
  // first frames can be looked at while the others render, and a job that fails leaves
  // those done on disk.
  const bool movie = plan.output == SubmitPlan::Output::movie;
  std::optional<TemporaryFolder> movie_frames;
  if (movie) {
    try {
      movie_frames.emplace("tessera-frames-");
    } catch (const MovieError& e) {
      fail(kExitJobFailed, e.what());
    }
  }
  const std::string pattern =
      movie ? (movie_frames->path() / "frame_#######.png").string() : options.output;
  FrameDownloads downloads(api, id, pattern, [&](int frame, const std::filesystem::path& path) {
    printer.note(
        "frame " + std::to_string(frame) + ": " +
        (movie ? std::string("downloaded") : "wrote " + std::filesystem::absolute(path).string()));
  });
  const protocol::JobStatus final_job =
      watch(api, id, printer, [&](const protocol::JobStatus& now) { downloads.catch_up(now); });
  if (options.json_output) print_json(protocol::to_json(final_job));
  // A movie needs every frame; the frames done of a job that failed are still saved.
  if (!movie || final_job.state == JobState::completed) downloads.finish();
  const int code = job_exit_code(final_job);
  if (code != kExitOk) {
    if (movie)
      std::fprintf(stderr, "%s not written: a movie needs every frame\n",
                   printable(options.output).c_str());
    return code;
  }
  if (movie) {
    if (static_cast<int>(downloads.saved().size()) != final_job.frames.total)
      fail(kExitJobFailed, "job " + id + " completed with " +
                               std::to_string(final_job.frames.total) +
                               " frames, of which the coordinator served " +
                               std::to_string(downloads.saved().size()));
    std::vector<std::filesystem::path> paths;
    for (const auto& [frame, path] : downloads.saved()) paths.push_back(path);
    encode_frames(plan.ffmpeg, paths, plan.fps, options.output);
  }
  return kExitOk;
}

// Runs one command, turning every failure into one line and its documented exit code.
int run(const std::function<int(CoordinatorClient&)>& command, const Options& options) {
  const std::string url = server_url(options);
  const auto say = [](const std::string& message) {
    std::fprintf(stderr, "error: %s\n", printable(message).c_str());
  };
  std::string token;
  try {
    token = resolve_secret(options.token, options.token_file, "TESSERA_API_TOKEN", "API token");
  } catch (const std::exception& e) {  // a token file that cannot be read, say
    say(e.what());
    return kExitUsage;
  }
  std::optional<CoordinatorClient> api;
  try {
    api.emplace(url, token, std::chrono::seconds(60), TlsSettings{ca_file_or_env(options.ca_file)});
  } catch (const BadServerUrl& e) {
    say(std::string(e.what()) + " (from " +
        (options.server.empty() ? "$TESSERA_SERVER" : "--server") + ")");
    return kExitUsage;
  } catch (const std::exception& e) {  // a CA file that cannot be read
    say(e.what());
    return kExitUsage;
  }
  try {
    return command(*api);
  } catch (const CommandFailed& failed) {
    return failed.code;
  } catch (const HttpError& e) {
    say("cannot reach the server at " + url + ": " + e.what());
    return kExitUnreachable;
  } catch (const ApiError& e) {
    if (e.code().empty()) {  // not a coordinator's error: a proxy's page, say
      say("the server at " + url + " answered HTTP " + std::to_string(e.status()) +
          " without a Tessera error" +
          (e.from_gateway() ? " (a proxy in front of a coordinator it cannot reach?)" : ""));
      return e.from_gateway() ? kExitUnreachable : kExitJobFailed;
    }
    // The one thing to do about it, rather than the route's words.
    if (e.code() == "missing_token") {
      say("the server at " + url +
          " needs an API token: set TESSERA_API_TOKEN, or pass --token-file FILE (or --token)");
      return kExitJobFailed;  // refused, as any other refusal
    }
    // http:// to a coordinator's TLS port: as a TLS failure.
    if (e.code() == "tls_required" || e.code() == "tls_not_served") {
      say("the server at " + url + " answered: " + e.what());
      return kExitUnreachable;
    }
    const bool path_named =
        e.path().empty() || std::string(e.what()).find(e.path()) != std::string::npos;
    say(std::string(e.what()) + (path_named ? "" : " (at " + e.path() + ")"));
    return kExitJobFailed;
  } catch (const protocol::ProtocolError& e) {
    say("the server at " + url + " answered in a form this CLI does not know: " + e.what());
    return kExitJobFailed;
  } catch (const std::exception& e) {
    say(e.what());
    return kExitJobFailed;
  }
}

using SharedOptions = std::shared_ptr<Options>;
using Command = std::function<int(const Options&, CoordinatorClient&)>;

// A subcommand that runs `command` with the options parsed, and exits with its code.
CLI::App* on(CLI::App& app, const SharedOptions& options, const char* name, const char* help,
             Command command) {
  CLI::App* sub = app.add_subcommand(name, help);
  sub->final_callback([options, command] {
    const int code = run([&](CoordinatorClient& api) { return command(*options, api); }, *options);
    if (code != 0) throw CLI::RuntimeError(code);
  });
  return sub;
}

void add_submit_command(CLI::App& app, const SharedOptions& options) {
  CLI::App* submit_cmd = on(app, options, "submit", "Submit a scene as a render job", submit);
  submit_cmd->add_option("scene", options->scene_path, "Scene file (JSON, or a COS 426 .scn)")
      ->required();
  submit_cmd->add_option("--name", options->name, "Job name (default: the file's name)");
  submit_cmd->add_option("--priority", options->priority, "0..100, higher first (default 50)")
      ->check(CLI::Range(0, 100));
  submit_cmd->add_flag("--wait", options->wait, "Follow the job until it finishes");
  submit_cmd->add_option("--allow-path", options->allowed_paths,
                         "A folder whose files the scene may name and send besides its own "
                         "folder's (repeat for more); nothing outside them is read");
  submit_cmd->add_option("--frames", options->frames,
                         "Frames of an animated scene: 1-48, 1-100x2 (every second), 1,5,10-20 "
                         "(default: all, or the first for an OUTPUT without #)");
  submit_cmd->add_option("-o,--output", options->output,
                         "Save the image here once the job completes (implies --wait); # for "
                         "the frame number (out_####.png), each frame saved as soon as it is "
                         "done; .mp4, .mkv or .mov for a movie at the scene's fps (needs ffmpeg)");
}

// `tessera get`: a movie, frames to a name with '#', one frame, or the job's image. The
// mistakes that need no coordinator to be seen are refused before it is asked anything.
int get_output(const Options& o, CoordinatorClient& api) {
  const std::string& output = o.output;
  const bool movie = is_movie_path(output);
  if (o.fps && !movie) fail(kExitUsage, "--fps is for a movie (-o OUT.mp4, .mkv or .mov)");
  const std::optional<std::vector<int>> asked = read_frames_option(o.frames);
  if (movie) {
    if (o.partial) fail(kExitUsage, "a movie is made of frames done; --partial is for images");
    std::error_code ec;
    if (std::filesystem::is_directory(output, ec))
      fail(kExitUsage, output + " is a directory; name the movie file, such as " +
                           (std::filesystem::path(output) / "movie.mp4").string());
    check_output_folder(output);
    const std::filesystem::path ffmpeg = ffmpeg_or_fail();  // before any download
    return save_job_movie(api, resolve_job_id(api, o.job), ffmpeg, output, asked,
                          o.fps.value_or(24.0));
  }
  if (has_frame_number(output)) {
    if (!image_format_of_path(frame_path(output, 0)))
      fail(kExitUsage, output + ": unknown image extension (use " + image_format_names(true) + ")");
    check_output_folder(output);
    return save_job_frames(api, resolve_job_id(api, o.job), output, asked, o.partial);
  }
  image_output_format(output);
  if (asked && asked->size() > 1)
    fail(kExitUsage, output + ": " + std::to_string(asked->size()) +
                         " frames need '#' in the output's name where the frame number goes, "
                         "such as out_####.png");
  const std::string id = resolve_job_id(api, o.job);
  if (asked) {
    frames_named(api.frames(id), asked, id);  // a frame the job does not render is named
    save_image(api, id, output, o.partial, asked->front());
  } else {
    save_image(api, id, output, o.partial);
  }
  return kExitOk;
}

// status, watch, list and get: they read what the coordinator has.
void add_job_queries(CLI::App& app, const SharedOptions& options) {
  CLI::App* status_cmd = on(app, options, "status", "Show a job's status",
                            [](const Options& o, CoordinatorClient& api) {
                              const protocol::JobStatus job = api.job(resolve_job_id(api, o.job));
                              if (o.json_output)
                                print_json(protocol::to_json(job));
                              else
                                print_status(job);
                              return kExitOk;
                            });
  status_cmd->add_option("job", options->job, "Job id (or a unique prefix)")->required();

  CLI::App* watch_cmd = on(app, options, "watch", "Follow a job's progress until it finishes",
                           [](const Options& o, CoordinatorClient& api) {
                             const std::string id = resolve_job_id(api, o.job);
                             ProgressPrinter printer(api, id);
                             return job_exit_code(watch(api, id, printer));
                           });
  watch_cmd->add_option("job", options->job, "Job id (or a unique prefix)")->required();

  CLI::App* list_cmd =
      on(app, options, "list", "List jobs, newest first",
         [](const Options& o, CoordinatorClient& api) {
           std::optional<JobState> state;
           if (!o.state.empty()) {
             state = job_state_from_string(o.state);
             if (!state)
               fail(kExitUsage, "--state must be " + protocol::names_of(protocol::kJobStateNames));
           }
           // One more than shown, to tell whether there are more.
           protocol::JobList reply = api.jobs(state, std::min(o.limit + 1, 1000));
           const bool more = static_cast<int>(reply.jobs.size()) > o.limit;
           if (more) reply.jobs.resize(o.limit);
           if (o.json_output) {
             print_json(protocol::to_json(reply));
           } else {
             print_job_table(reply.jobs);
             if (more)
               std::printf("(more jobs than these %d: tessera list --limit %d shows more)\n",
                           o.limit, std::min(o.limit * 2, 1000));
           }
           return kExitOk;
         });
  list_cmd->add_option("--state", options->state, "Only jobs in this state");
  list_cmd->add_option("--limit", options->limit, "At most this many")->check(CLI::Range(1, 1000));

  CLI::App* get_cmd =
      on(app, options, "get", "Download a job's image, frames or movie", get_output);
  get_cmd->add_option("job", options->job, "Job id (or a unique prefix)")->required();
  get_cmd
      ->add_option("-o,--output", options->output,
                   "OUT.png, .exr, .jpg or .tif; # for the frame number (out_####.exr): "
                   "every frame done; .mp4, .mkv or .mov: a movie of the frames (needs ffmpeg)")
      ->required();
  get_cmd->add_option("--frames", options->frames,
                      "Only these frames of an animation: 1-48, 1-100x2, 1,5,10-20");
  get_cmd->add_option("--fps", options->fps, "A movie's frames per second (default 24)")
      ->check(CLI::Validator(
          [](const std::string& text) {
            char* end = nullptr;
            const double fps = std::strtod(text.c_str(), &end);
            if (end != text.c_str() && *end == '\0' && std::isfinite(fps) && fps > 0) return "";
            return "must be a number of frames a second above 0, such as 24 or 29.97";
          },
          "FPS"));
  get_cmd->add_flag("--partial", options->partial, "The tiles rendered so far, before completion");
}

void add_job_changes(CLI::App& app, const SharedOptions& options) {
  CLI::App* cancel_cmd =
      on(app, options, "cancel", "Cancel a job", [](const Options& o, CoordinatorClient& api) {
        const protocol::JobStatus job = api.cancel(resolve_job_id(api, o.job));
        if (o.json_output)
          print_json(protocol::to_json(job));
        else
          print_status(job);
        return kExitOk;
      });
  cancel_cmd->add_option("job", options->job, "Job id (or a unique prefix)")->required();

  CLI::App* rm_cmd = on(app, options, "rm", "Remove a finished job and its files",
                        [](const Options& o, CoordinatorClient& api) {
                          const std::string id = resolve_job_id(api, o.job);
                          api.remove(id);
                          if (!o.json_output) std::printf("removed %s\n", printable(id).c_str());
                          return kExitOk;
                        });
  rm_cmd->add_option("job", options->job, "Job id (or a unique prefix)")->required();
}

// Priority, pause, resume, retry: each answers with the job's status.
void add_job_controls(CLI::App& app, const SharedOptions& options) {
  const auto shown = [](const Options& o, const protocol::JobStatus& job) {
    if (o.json_output)
      print_json(protocol::to_json(job));
    else
      print_status(job);
    return kExitOk;
  };
  CLI::App* priority_cmd =
      on(app, options, "priority", "Change a job's priority",
         [shown](const Options& o, CoordinatorClient& api) {
           return shown(o, api.change(resolve_job_id(api, o.job), {o.priority}));
         });
  priority_cmd->add_option("job", options->job, "Job id (or a unique prefix)")->required();
  priority_cmd->add_option("priority", options->priority, "0..100, higher first")
      ->required()
      ->check(CLI::Range(0, 100));
  using Control = protocol::JobStatus (CoordinatorClient::*)(std::string_view);
  const auto control = [&](const char* name, const char* help, Control call) {
    CLI::App* sub =
        on(app, options, name, help, [shown, call](const Options& o, CoordinatorClient& api) {
          return shown(o, (api.*call)(resolve_job_id(api, o.job)));
        });
    sub->add_option("job", options->job, "Job id (or a unique prefix)")->required();
  };
  control("pause", "Pause a job: its leases run out and no new tiles go out",
          &CoordinatorClient::pause);
  control("resume", "Resume a paused job", &CoordinatorClient::resume);
  control("retry", "Render a failed or canceled job's unfinished tiles again",
          &CoordinatorClient::retry);
}

// Drain, undrain and remove a worker, named by a unique prefix of its id or by its name.
void add_worker_controls(CLI::App& app, const SharedOptions& options) {
  const auto drain = [&](const char* name, const char* help, bool draining) {
    CLI::App* sub =
        on(app, options, name, help, [draining](const Options& o, CoordinatorClient& api) {
          const protocol::Worker worker = api.drain(resolve_worker_id(api, o.worker), draining);
          if (o.json_output)
            print_json(protocol::to_json(worker));
          else
            print_worker_table({worker});
          return kExitOk;
        });
    sub->add_option("worker", options->worker, "Worker id (or a unique prefix), or its name")
        ->required();
  };
  drain("drain", "Let a worker finish its lease and take no more tiles", true);
  drain("undrain", "Let a drained worker take tiles again", false);
  CLI::App* remove_cmd =
      on(app, options, "remove-worker",
         "Take a worker off the farm; its tiles go back to the queue (a live worker process "
         "registers again: drain it or stop it first)",
         [](const Options& o, CoordinatorClient& api) {
           const std::string id = resolve_worker_id(api, o.worker);
           api.remove_worker(id);
           if (!o.json_output) std::printf("removed %s\n", printable(id).c_str());
           return kExitOk;
         });
  remove_cmd->add_option("worker", options->worker, "Worker id (or a unique prefix), or its name")
      ->required();
}

void add_workers_command(CLI::App& app, const SharedOptions& options) {
  on(app, options, "workers", "List the workers", [](const Options& o, CoordinatorClient& api) {
    const protocol::WorkerList reply = api.workers();
    if (o.json_output) {
      print_json(protocol::to_json(reply));
      return kExitOk;
    }
    print_worker_table(reply.workers);
    return kExitOk;
  });
}

// Whether the coordinator answers GET /healthz: for container health checks, which may
// have to speak TLS and have no curl.
void add_health_command(CLI::App& app, const SharedOptions& options) {
  on(app, options, "health", "Check that the coordinator is up (GET /healthz)",
     [](const Options& o, CoordinatorClient& api) {
       const protocol::Health health = api.health();
       if (o.json_output)
         print_json(protocol::to_json(health));
       else
         std::printf("ok\n");
       return kExitOk;
     });
}

}  // namespace

void add_job_commands(CLI::App& app) {
  auto options = std::make_shared<Options>();
  app.add_option("--server", options->server,
                 "Coordinator URL (default: $TESSERA_SERVER or http://127.0.0.1:8640)");
  app.add_flag("--json", options->json_output, "Print the server's JSON");
  app.add_option("--token", options->token,
                 "The server's API token (default: $TESSERA_API_TOKEN; --token-file keeps it "
                 "out of the process list)");
  app.add_option("--token-file", options->token_file, "Read the API token from this file");
  app.add_option("--ca-file", options->ca_file,
                 "Trust the CAs of this PEM file for an https:// server, instead of the "
                 "system's (default: $TESSERA_CA_FILE)");

  add_submit_command(app, options);
  add_job_queries(app, options);
  add_job_changes(app, options);
  add_job_controls(app, options);
  add_workers_command(app, options);
  add_worker_controls(app, options);
  add_health_command(app, options);
}

}  // namespace tessera
