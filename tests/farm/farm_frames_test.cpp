// Animations on a real farm: every frame the workers render is bit for bit the frame a
// single process renders; frames are served as each is done; a coordinator killed with
// SIGKILL in the middle of an animation loses no finished frame and no delivered tile.
#include <csignal>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>

#include <gtest/gtest.h>

#include "common/scene/scene_parser.hpp"
#include "tests/farm/farm_fixture.hpp"
#include "tests/unit/worker/render_helpers.hpp"
#include "tracer/local_render.hpp"
#include "tracer/renderer.hpp"

namespace tessera {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using nlohmann::json;
using test::Farm;

// The example turntable (the camera orbits the showcase on a smooth track) at a test's size.
json turntable(int width, int height, int spp, int tile_size) {
  json scene =
      read_json_file(fs::path(TESSERA_SOURCE_DIR) / "examples" / "animation" / "turntable.json");
  scene["image"] = {{"width", width}, {"height", height}};
  scene["render"]["samples_per_pixel"] = spp;
  scene["render"]["tile_size"] = tile_size;
  return scene;
}

// The fly-through: the camera, a light, a rolling sphere and a turning box all move, and
// here a torus of 480 triangles turns too, which a worker places (a BVH of its own, built
// for the first frame it holds, mesh_bvh.hpp) where one process builds each frame whole.
json flythrough(int width, int height, int tile_size) {
  json scene = read_json_file(fs::path(TESSERA_SOURCE_DIR) / "examples" / "animation" /
                              "corridor_flythrough.json");
  json ring = test::torus(20, 12, 0.35, 0.1, true);
  ring["material"] = "gold";
  ring["transform"] = {
      {{"rotate",
        {{"axis", {1, 0, 0.3}},
         {"degrees", {{"keys", {{1, 20}, {60, 160}}}, {"interpolation", "linear"}}}}}},
      {{"translate", {0.9, 1.2, -0.6}}}};
  scene["objects"].push_back(ring);
  scene["image"] = {{"width", width}, {"height", height}};
  scene["render"]["samples_per_pixel"] = 1;
  scene["render"]["tile_size"] = tile_size;
  return scene;
}

// Frame `frame` as one process renders it, read whole at that frame.
Image local_frame(const json& scene, int frame) {
  const Renderer renderer(parse_scene_frame(scene, frame, Limits{}));
  return render_local(renderer, 2).image;
}

std::string submit_frames(test::JsonApi& api, const std::string& name, const json& scene,
                          const std::string& frames) {
  protocol::JobSubmission submission{name, 50, scene, frames};
  return api.client().submit(submission).id;
}

Image frame_image(Farm& farm, const std::string& id, int frame) {
  const fs::path path = farm.dir() / (id + "-" + std::to_string(frame) + ".exr");
  test::write_text(path,
                   farm.api().client().frame_image(id, frame, *image_format_named("exr"), false));
  return read_image(path);
}

TEST(FarmFramesTest, EveryFrameIsBitIdenticalToTheSameFrameRenderedInOneProcess) {
  Farm farm("frames-identical", 2);
  const json orbit = turntable(64, 48, 2, 16);
  const json fly = flythrough(48, 32, 8);
  const std::string orbit_id = submit_frames(farm.api(), "orbit", orbit, "1-25x12");
  const std::string fly_id = submit_frames(farm.api(), "fly", fly, "1,30,60");
  for (const auto& [id, scene, frames] : {std::tuple{orbit_id, orbit, std::vector<int>{1, 13, 25}},
                                          std::tuple{fly_id, fly, std::vector<int>{1, 30, 60}}}) {
    const json done = farm.wait_finished(id);
    ASSERT_EQ(done["state"], "completed") << done.dump();
    EXPECT_EQ(done["frames"]["done"], 3);
    EXPECT_EQ(done["frames"]["current"], nullptr);
    const protocol::FrameList list = farm.api().client().frames(id);
    ASSERT_EQ(list.frames.size(), 3u);
    for (std::size_t i = 0; i < frames.size(); ++i) {
      EXPECT_EQ(list.frames[i].frame, frames[i]);
      EXPECT_EQ(list.frames[i].state, protocol::FrameState::done);
      EXPECT_TRUE(
          test::same_pixels(frame_image(farm, id, frames[i]), local_frame(scene, frames[i])))
          << "frame " << frames[i] << " of " << done["name"];
    }
  }
  // Frames that differ are different images: the animation did move.
  EXPECT_FALSE(test::same_pixels(frame_image(farm, orbit_id, 1), frame_image(farm, orbit_id, 13)));
  // The job's own image is its first frame.
  EXPECT_TRUE(test::same_pixels(test::farm_image(farm, fly_id), local_frame(fly, 1)));
}

TEST(FarmFramesTest, AFrameIsServedAsSoonAsItIsDoneAndItsRoutesSayWhatIsWrong) {
  Farm farm("frames-routes", 0);  // no workers until the test starts one
  HttpClient http = farm.http(10s);
  const json scene = turntable(32, 24, 1, 16);
  const std::string id = submit_frames(farm.api(), "orbit", scene, "1-3");
  const auto status_of = [&](const std::string& target) {
    return http.request("GET", target).status;
  };
  const std::string frames = "/v1/jobs/" + id + "/frames";
  EXPECT_EQ(status_of(frames + "/1/image"), 409) << "not done yet";
  EXPECT_EQ(status_of(frames + "/1/image?partial=1"), 200);
  EXPECT_EQ(status_of(frames + "/4/image?partial=1"), 404) << "a frame it does not render";
  EXPECT_EQ(status_of(frames + "/x/image"), 400);
  EXPECT_EQ(status_of(frames + "/99999999999/image"), 400);
  EXPECT_EQ(status_of("/v1/jobs/j-none/frames"), 404);
  const protocol::FrameList pending = farm.api().client().frames(id);
  ASSERT_EQ(pending.frames.size(), 3u);
  EXPECT_EQ(pending.frames[0].state, protocol::FrameState::pending);
  EXPECT_EQ(pending.frames[0].tiles.total, 4);

  const auto worker = farm.start_worker("w");
  ASSERT_EQ(farm.wait_finished(id)["state"], "completed");
  EXPECT_EQ(status_of(frames + "/2/image?format=exr"), 200);
  EXPECT_TRUE(test::same_pixels(frame_image(farm, id, 3), local_frame(scene, 3)));
  // A still's one frame is frame 0.
  const std::string still = farm.api().submit("still", 50, test::showcase(16, 16, 1, 16))["id"];
  ASSERT_EQ(farm.wait_finished(still)["state"], "completed");
  EXPECT_EQ(farm.api().client().frames(still).frames.size(), 1u);
  EXPECT_EQ(status_of("/v1/jobs/" + still + "/frames/0/image"), 200);
  EXPECT_EQ(status_of("/v1/jobs/" + still + "/frames/1/image"), 404);
}

TEST(FarmFramesTest, ACoordinatorKilledMidAnimationLosesNoFinishedFrameNorDeliveredTile) {
  const fs::path dir = test::fresh_dir("frames-kill-server");
  const json scene = turntable(160, 120, 8, 40);  // 12 tiles a frame
  constexpr int kFrames = 24;
  auto [server, port] = test::start_coordinator(dir, "127.0.0.1:0", "first.log");
  const std::string url = "http://127.0.0.1:" + std::to_string(port);
  test::JsonApi api(url);
  const std::string id = submit_frames(api, "orbit", scene, "1-" + std::to_string(kFrames));
  auto worker = std::make_unique<test::Process>(
      TESSERA_WORKER_BIN,
      std::vector<std::string>{"--server", url, "--threads", "1", "--name", "survivor",
                               "--log-level", "info"},
      dir / "survivor.log");
  ASSERT_TRUE(test::eventually([&] { return api.job(id)["frames"]["done"].get<int>() >= 3; }, 60s));
  // The frames done before the kill, as the coordinator served them.
  std::map<int, std::string> before;
  for (const protocol::FrameStatus& frame : api.client().frames(id).frames)
    if (frame.state == protocol::FrameState::done)
      before[frame.frame] =
          api.client().frame_image(id, frame.frame, *image_format_named("exr"), false);
  server->signal(SIGKILL);
  ASSERT_TRUE(server->wait_for(10s).has_value());
  ASSERT_GE(before.size(), 3u);

  auto [again, again_port] =
      test::start_coordinator(dir, "127.0.0.1:" + std::to_string(port), "second.log");
  ASSERT_EQ(again_port, port);
  // Every frame served before is done still, its image the very same file.
  const json resumed = api.job(id);
  EXPECT_GE(resumed["frames"]["done"].get<int>(), static_cast<int>(before.size()));
  ASSERT_LT(resumed["frames"]["done"].get<int>(), kFrames) << "finished before the kill";
  for (const auto& [frame, exr] : before)
    EXPECT_EQ(api.client().frame_image(id, frame, *image_format_named("exr"), false), exr)
        << "frame " << frame << " changed across the restart";
  json done;
  test::eventually(
      [&] {
        done = api.job(id);
        return done["state"] == "completed";
      },
      120s);
  ASSERT_EQ(done["state"], "completed") << done.dump();
  for (const int frame : {1, kFrames / 2, kFrames}) {
    const fs::path exr = dir / ("frame-" + std::to_string(frame) + ".exr");
    test::write_text(exr, api.client().frame_image(id, frame, *image_format_named("exr"), false));
    EXPECT_TRUE(test::same_pixels(read_image(exr), local_frame(scene, frame))) << frame;
  }
  // No tile was rendered twice: the one worker rendered exactly the job's tiles.
  worker->signal(SIGTERM);
  ASSERT_TRUE(worker->wait_for(20s).has_value());
  EXPECT_EQ(test::tiles_rendered_by(dir / "survivor.log"), kFrames * 12)
      << "see " << (dir / "survivor.log");
  // Only the camera moves: the worker built the BVH once and every later frame shared it.
  const std::string log = test::read_text(dir / "survivor.log");
  const auto count = [&](const std::string& pattern) {
    const std::regex re(pattern);
    return std::distance(std::sregex_iterator(log.begin(), log.end(), re), std::sregex_iterator());
  };
  EXPECT_EQ(count("frame [0-9]+: built in"), 1) << "see " << (dir / "survivor.log");
  EXPECT_GE(count("frame [0-9]+: ready in [0-9.]+ s, sharing the geometry of frame"), kFrames - 1)
      << "see " << (dir / "survivor.log");
  again->signal(SIGTERM);
  again->wait_for(20s);
}

}  // namespace
}  // namespace tessera
