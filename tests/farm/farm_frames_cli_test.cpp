// The `tessera` commands for an animation on a real farm: `submit --frames --wait -o` saves
// each frame as it is done, bit for bit the frame `tessera render --frames` makes; `get`
// saves frames, one frame or a movie; `watch` counts frames. Real processes, as a user
// runs them (stdout is a file here, so progress comes as plain lines).
#include <unistd.h>

#include <regex>
#include <set>

#include <gtest/gtest.h>

#include "tests/farm/farm_fixture.hpp"

namespace tessera {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using nlohmann::json;
using test::CliRun;
using test::contains;
using test::Farm;

// Frames 1 to 3 of the showcase at 32x24 in tiles of 8 (12 a frame), the camera moving
// along a track, so that every frame differs; 12 frames a second.
json tiny_animation() {
  json scene = test::showcase(32, 24, 1, 8);
  scene["animation"] = {{"frames", {1, 3}}, {"fps", 12}};
  scene["camera"]["eye"] = {{"keys", {{1, {0.0, 2.2, 7.5}}, {3, {3.0, 2.2, 6.5}}}}};
  return scene;
}

CliRun tessera_cli(Farm& farm, std::vector<std::string> args,
                   std::chrono::milliseconds limit = 60s) {
  args.insert(args.begin(), {"--server", farm.url()});
  return test::run_cli(farm.dir(), args, limit);
}

std::string job_id_of(const CliRun& run) {
  std::smatch match;
  if (!std::regex_search(run.output, match, std::regex(R"(submitted (\S+) )"))) return "";
  return match[1];
}

// The names of the files in `dir`.
std::set<std::string> files_in(const fs::path& dir) {
  std::set<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir)) names.insert(entry.path().filename());
  return names;
}

// Whether an executable of that name is on PATH.
bool on_path(const std::string& program) {
  const char* path = std::getenv("PATH");
  std::string dirs = path ? path : "";
  std::size_t start = 0;
  while (start <= dirs.size()) {
    const std::size_t end = std::min(dirs.find(':', start), dirs.size());
    const std::string dir = dirs.substr(start, end - start);
    if (!dir.empty() && ::access((fs::path(dir) / program).c_str(), X_OK) == 0) return true;
    start = end + 1;
  }
  return false;
}

// The frames ffprobe counts in a movie's video stream, or what it said instead.
std::string probed_frames(const fs::path& dir, const fs::path& movie) {
  const fs::path log = dir / "ffprobe.log";
  fs::remove(log);
  test::Process probe(
      "/usr/bin/env",
      {"ffprobe", "-v", "error", "-count_frames", "-select_streams", "v:0", "-show_entries",
       "stream=nb_read_frames", "-of", "csv=p=0", "file:" + movie.string()},
      log);
  probe.wait_for(30s);
  std::string text = test::read_text(log);
  while (!text.empty() && (text.back() == '\n' || text.back() == '\r')) text.pop_back();
  return text;
}

TEST(FarmFramesCliTest, SubmitSavesEachFrameAsRenderMakesItAndGetSavesFrames) {
  Farm farm("frames-cli", 2);
  const fs::path scene_file = farm.dir() / "anim.json";
  test::write_text(scene_file, tiny_animation().dump());

  // The frames as one machine renders them.
  const fs::path local = farm.dir() / "local";
  fs::create_directories(local);
  const CliRun rendered = test::run_cli(
      farm.dir(),
      {"render", scene_file.string(), "--frames", "1-3", "-o", (local / "local_##.exr").string()});
  ASSERT_EQ(rendered.exit_code, 0) << rendered.output;

  // Each frame saved as it is done, to the name with its number; nothing else left there.
  const fs::path out = farm.dir() / "out";
  fs::create_directories(out);
  const CliRun submitted = tessera_cli(farm,
                                       {"submit", scene_file.string(), "--frames", "1-3", "--wait",
                                        "-o", (out / "f_##.exr").string()},
                                       120s);
  ASSERT_EQ(submitted.exit_code, 0) << submitted.output;
  const std::string id = job_id_of(submitted);
  ASSERT_FALSE(id.empty()) << submitted.output;
  EXPECT_EQ(files_in(out), (std::set<std::string>{"f_01.exr", "f_02.exr", "f_03.exr"}))
      << submitted.output;
  for (const char* frame : {"01", "02", "03"}) {
    EXPECT_TRUE(contains(submitted.output, "frame " + std::to_string(std::stoi(frame)) +
                                               ": wrote " + (out / "f_").string() + frame))
        << submitted.output;
    EXPECT_TRUE(test::same_pixels(read_image(out / ("f_" + std::string(frame) + ".exr")),
                                  read_image(local / ("local_" + std::string(frame) + ".exr"))))
        << "frame " << frame;
  }
  const json job = farm.api().job(id);
  EXPECT_EQ(job["frames"]["list"], "1-3") << job.dump();
  EXPECT_EQ(job["frames"]["done"], 3) << job.dump();

  // One frame of the job by --frames, to a name with '#' and to a plain name.
  const fs::path some = farm.dir() / "some";
  fs::create_directories(some);
  const CliRun second =
      tessera_cli(farm, {"get", id, "-o", (some / "g_###.exr").string(), "--frames", "2"});
  ASSERT_EQ(second.exit_code, 0) << second.output;
  EXPECT_EQ(files_in(some), std::set<std::string>{"g_002.exr"}) << second.output;
  EXPECT_TRUE(
      test::same_pixels(read_image(some / "g_002.exr"), read_image(local / "local_02.exr")));
  const fs::path plain = farm.dir() / "third.exr";
  const CliRun third = tessera_cli(farm, {"get", id, "-o", plain.string(), "--frames", "3"});
  ASSERT_EQ(third.exit_code, 0) << third.output;
  EXPECT_TRUE(test::same_pixels(read_image(plain), read_image(local / "local_03.exr")));

  // Every frame when none are named, as PNGs.
  const fs::path pngs = farm.dir() / "pngs";
  fs::create_directories(pngs);
  const CliRun all = tessera_cli(farm, {"get", id, "-o", (pngs / "p_#.png").string()});
  ASSERT_EQ(all.exit_code, 0) << all.output;
  EXPECT_EQ(files_in(pngs), (std::set<std::string>{"p_1.png", "p_2.png", "p_3.png"})) << all.output;

  // A frame the job does not render is named, and nothing is saved; a list that cannot be
  // read is a usage error; several frames need '#'.
  const fs::path none = farm.dir() / "none";
  fs::create_directories(none);
  const CliRun foreign =
      tessera_cli(farm, {"get", id, "-o", (none / "n_##.exr").string(), "--frames", "2-7x5"});
  EXPECT_EQ(foreign.exit_code, 1) << foreign.output;
  EXPECT_TRUE(
      contains(foreign.output, "error: frame 7 is not among the frames of job " + id + " (1-3)"))
      << foreign.output;
  const CliRun unreadable =
      tessera_cli(farm, {"get", id, "-o", (none / "n_##.exr").string(), "--frames", "1-x"});
  EXPECT_EQ(unreadable.exit_code, 2) << unreadable.output;
  EXPECT_TRUE(contains(unreadable.output, "--frames: frame list \"1-x\", at character 3"))
      << unreadable.output;
  const CliRun several =
      tessera_cli(farm, {"get", id, "-o", (none / "plain.exr").string(), "--frames", "1-2"});
  EXPECT_EQ(several.exit_code, 2) << several.output;
  EXPECT_TRUE(contains(several.output, "need '#'")) << several.output;
  EXPECT_TRUE(files_in(none).empty()) << foreign.output << unreadable.output;

  // A movie without ffmpeg: said how to install it, before anything is downloaded.
  const CliRun no_ffmpeg = test::run_cli(
      farm.dir(), {"--server", farm.url(), "get", id, "-o", (none / "movie.mp4").string()}, 30s,
      {"/usr/bin/env", "PATH=" + (farm.dir() / "empty").string()});
  EXPECT_EQ(no_ffmpeg.exit_code, 2) << no_ffmpeg.output;
  EXPECT_TRUE(contains(no_ffmpeg.output, "apt-get install ffmpeg")) << no_ffmpeg.output;
  EXPECT_FALSE(contains(no_ffmpeg.output, "downloaded")) << no_ffmpeg.output;
  EXPECT_TRUE(files_in(none).empty());

  // watch of the finished animation counts its frames.
  const CliRun watched = tessera_cli(farm, {"watch", id});
  EXPECT_EQ(watched.exit_code, 0) << watched.output;
  EXPECT_EQ(watched.output.rfind("completed 3/3 frames 100.0%", 0), 0u) << watched.output;
  EXPECT_FALSE(contains(watched.output, "tiles")) << watched.output;
}

TEST(FarmFramesCliTest, SubmitRefusesWhatItCannotSaveAndMakesOneImageOfTheFirstFrame) {
  Farm farm("frames-cli-submit", 1);
  const fs::path scene_file = farm.dir() / "anim.json";
  test::write_text(scene_file, tiny_animation().dump());
  const fs::path still_file = farm.dir() / "still.json";
  test::write_text(still_file, test::showcase(32, 24, 1, 8).dump());

  // Refused before anything is sent: a frame the scene does not have, several frames for
  // one file, a movie of a still scene.
  const CliRun outside = tessera_cli(farm, {"submit", scene_file.string(), "--frames", "2-4"});
  EXPECT_EQ(outside.exit_code, 2) << outside.output;
  EXPECT_TRUE(contains(outside.output, "frame 4 is not one of the scene's, 1 to 3"))
      << outside.output;
  const CliRun several = tessera_cli(farm, {"submit", scene_file.string(), "--frames", "1-2", "-o",
                                            (farm.dir() / "one.exr").string()});
  EXPECT_EQ(several.exit_code, 2) << several.output;
  EXPECT_TRUE(contains(several.output, "2 frames need '#'")) << several.output;
  const CliRun still_movie =
      tessera_cli(farm, {"submit", still_file.string(), "-o", (farm.dir() / "s.mp4").string()});
  EXPECT_EQ(still_movie.exit_code, 2) << still_movie.output;
  EXPECT_TRUE(contains(still_movie.output, "a movie needs an animated scene"))
      << still_movie.output;
  EXPECT_TRUE(farm.api().jobs("", 10)["jobs"].empty()) << "a refused submission reached the farm";

  // Frames of a still scene are the coordinator's to refuse; its error is shown.
  const CliRun still_frames = tessera_cli(farm, {"submit", still_file.string(), "--frames", "2"});
  EXPECT_EQ(still_frames.exit_code, 1) << still_frames.output;
  EXPECT_TRUE(contains(still_frames.output, "error: ")) << still_frames.output;

  // One image of an animation is its first frame, as `tessera render` makes it, and the
  // farm renders no other.
  const fs::path first = farm.dir() / "first.exr";
  const CliRun submitted = tessera_cli(farm, {"submit", scene_file.string(), "-o", first.string()});
  ASSERT_EQ(submitted.exit_code, 0) << submitted.output;
  const fs::path local = farm.dir() / "local.exr";
  const CliRun rendered =
      test::run_cli(farm.dir(), {"render", scene_file.string(), "-o", local.string()});
  ASSERT_EQ(rendered.exit_code, 0) << rendered.output;
  EXPECT_TRUE(test::same_pixels(read_image(first), read_image(local)));
  const json job = farm.api().job(job_id_of(submitted));
  EXPECT_EQ(job["frames"]["list"], "1") << job.dump();
}

TEST(FarmFramesCliTest, SubmitSavesAFrameAsSoonAsItIsDone) {
  Farm farm("frames-cli-early", 1);
  // Five frames big enough that the first is done well before the last.
  json scene = tiny_animation();
  scene["image"] = {{"width", 320}, {"height", 240}};
  scene["render"]["samples_per_pixel"] = 8;
  scene["render"]["tile_size"] = 32;
  scene["animation"]["frames"] = {1, 5};
  const fs::path scene_file = farm.dir() / "anim.json";
  test::write_text(scene_file, scene.dump());
  const fs::path out = farm.dir() / "out";
  fs::create_directories(out);
  test::Process waiting(TESSERA_CLI_BIN,
                        {"--server", farm.url(), "submit", scene_file.string(), "--wait", "-o",
                         (out / "f_#.png").string()},
                        farm.dir() / "wait.log");
  // Paused once its first frame is done: the frame must reach the disk while the job
  // cannot finish.
  std::string id;
  ASSERT_TRUE(test::eventually(
      [&] {
        const json jobs = farm.api().jobs("", 10)["jobs"];
        if (jobs.empty()) return false;
        id = jobs[0]["id"];
        return jobs[0]["frames"]["done"] >= 1;
      },
      60s));
  farm.api().pause(id);
  EXPECT_TRUE(test::eventually([&] { return fs::exists(out / "f_1.png"); }, 20s))
      << test::read_text(farm.dir() / "wait.log");
  const json paused = farm.api().job(id);
  EXPECT_EQ(paused["state"], "paused") << paused.dump();
  EXPECT_LT(paused["frames"]["done"], 5) << "the job finished before it was paused";
  farm.api().resume(id);
  const auto status = waiting.wait_for(60s);
  ASSERT_TRUE(status.has_value()) << test::read_text(farm.dir() / "wait.log");
  EXPECT_TRUE(WIFEXITED(*status) && WEXITSTATUS(*status) == 0)
      << test::read_text(farm.dir() / "wait.log");
  EXPECT_EQ(files_in(out),
            (std::set<std::string>{"f_1.png", "f_2.png", "f_3.png", "f_4.png", "f_5.png"}));
}

TEST(FarmFramesCliTest, AFrameThatFailsLeavesTheOthersSavedAndIsNamed) {
  Farm farm("frames-cli-failed", 0);
  // Tile 13 is of the second frame (12 tiles a frame, numbered frame after frame): every
  // worker fails it, so frame 2 fails and frames 1 and 3 render.
  std::vector<std::unique_ptr<test::Process>> workers;
  ::setenv("TESSERA_FAULT_INJECTION", "error:13", 1);
  for (const char* name : {"one", "two"}) workers.push_back(farm.start_worker(name));
  ::unsetenv("TESSERA_FAULT_INJECTION");
  const fs::path scene_file = farm.dir() / "anim.json";
  test::write_text(scene_file, tiny_animation().dump());

  const fs::path out = farm.dir() / "out";
  fs::create_directories(out);
  const CliRun submitted = tessera_cli(farm,
                                       {"submit", scene_file.string(), "--frames", "1-3", "--wait",
                                        "-o", (out / "f_##.exr").string()},
                                       120s);
  EXPECT_EQ(submitted.exit_code, 1) << submitted.output;
  EXPECT_TRUE(contains(submitted.output, "failed frames: 2 (1 of 3)")) << submitted.output;
  EXPECT_EQ(files_in(out), (std::set<std::string>{"f_01.exr", "f_03.exr"})) << submitted.output;
  const std::string id = job_id_of(submitted);
  ASSERT_FALSE(id.empty()) << submitted.output;

  // Asked for by name, the failed frame is an error naming it, after the others are saved.
  const fs::path listed = farm.dir() / "listed";
  fs::create_directories(listed);
  const CliRun named =
      tessera_cli(farm, {"get", id, "-o", (listed / "l_#.exr").string(), "--frames", "1-3"});
  EXPECT_EQ(named.exit_code, 1) << named.output;
  EXPECT_TRUE(contains(named.output, "error: frame 2 of job " + id + " is not done (failed 2)"))
      << named.output;
  EXPECT_EQ(files_in(listed), (std::set<std::string>{"l_1.exr", "l_3.exr"})) << named.output;
  // Not asked for by name, it is mentioned, and the command succeeds with what is done.
  const fs::path every = farm.dir() / "every";
  fs::create_directories(every);
  const CliRun all = tessera_cli(farm, {"get", id, "-o", (every / "e_#.exr").string()});
  EXPECT_EQ(all.exit_code, 0) << all.output;
  EXPECT_TRUE(contains(all.output, "note: frame 2 of job " + id + " is not done (failed 2)"))
      << all.output;
  EXPECT_EQ(files_in(every), (std::set<std::string>{"e_1.exr", "e_3.exr"})) << all.output;
  // A movie needs every frame.
  if (on_path("ffmpeg")) {
    const CliRun movie = tessera_cli(farm, {"get", id, "-o", (every / "m.mp4").string()});
    EXPECT_EQ(movie.exit_code, 1) << movie.output;
    EXPECT_TRUE(contains(movie.output, "a movie needs every frame done, and frame 2 of job " + id +
                                           " is not (failed 2)"))
        << movie.output;
    EXPECT_FALSE(fs::exists(every / "m.mp4"));
  }

  const CliRun watched = tessera_cli(farm, {"watch", id});
  EXPECT_EQ(watched.exit_code, 1) << watched.output;
  EXPECT_EQ(watched.output.rfind("failed 2/3 frames, 1 failed ", 0), 0u) << watched.output;
}

TEST(FarmFramesCliTest, MoviesOfAJobsFrames) {
  if (!on_path("ffmpeg") || !on_path("ffprobe"))
    GTEST_SKIP() << "ffmpeg and ffprobe are not installed (deploy/install-deps.sh installs them)";
  Farm farm("frames-cli-movie", 2);
  const fs::path scene_file = farm.dir() / "anim.json";
  test::write_text(scene_file, tiny_animation().dump());

  // submit: the frames downloaded as they are done, encoded at the scene's fps.
  const fs::path submitted_movie = farm.dir() / "submitted.mp4";
  const CliRun submitted = tessera_cli(
      farm, {"submit", scene_file.string(), "--wait", "-o", submitted_movie.string()}, 120s);
  ASSERT_EQ(submitted.exit_code, 0) << submitted.output;
  EXPECT_TRUE(contains(submitted.output, "3 frames at 12 fps")) << submitted.output;
  EXPECT_EQ(probed_frames(farm.dir(), submitted_movie), "3");
  const std::string id = job_id_of(submitted);

  // get: every frame, or those named, at --fps.
  const fs::path movie = farm.dir() / "got.mp4";
  const CliRun got = tessera_cli(farm, {"get", id, "-o", movie.string(), "--fps", "6"});
  ASSERT_EQ(got.exit_code, 0) << got.output;
  EXPECT_TRUE(contains(got.output, "3 frames at 6 fps")) << got.output;
  EXPECT_EQ(probed_frames(farm.dir(), movie), "3");
  const fs::path two = farm.dir() / "two.mkv";
  const CliRun got_two = tessera_cli(farm, {"get", id, "-o", two.string(), "--frames", "1,3"});
  ASSERT_EQ(got_two.exit_code, 0) << got_two.output;
  EXPECT_EQ(probed_frames(farm.dir(), two), "2");
  const CliRun foreign =
      tessera_cli(farm, {"get", id, "-o", (farm.dir() / "x.mp4").string(), "--frames", "4"});
  EXPECT_EQ(foreign.exit_code, 1) << foreign.output;
  EXPECT_TRUE(contains(foreign.output, "frame 4 is not among the frames")) << foreign.output;
  EXPECT_FALSE(fs::exists(farm.dir() / "x.mp4"));
}

}  // namespace
}  // namespace tessera
