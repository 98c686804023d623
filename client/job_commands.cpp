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
#include "client/job_follow.hpp"
#include "client/job_frames.hpp"
#include "client/job_image.hpp"
#include "client/job_tables.hpp"
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
