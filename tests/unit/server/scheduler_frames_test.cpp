// Jobs of many frames: one pool of tiles, frames in order, a lease within one frame, each
// frame's image as soon as it is whole, a frame failing alone, and a restart that keeps
// every finished frame.
#include <algorithm>
#include <filesystem>
#include <functional>
#include <map>
#include <set>

#include <gtest/gtest.h>

#include "tests/unit/server/scheduler_fixture.hpp"

namespace tessera::test {
namespace {

constexpr int kSize = 16;
constexpr int kTile = 8;  // 4 tiles a frame

// The image of a frame whose every tile was delivered with `seed`.
Image expected_frame(float seed) {
  Image image(kSize, kSize);
  for (const TileRect& rect : split_into_tiles(kSize, kSize, kTile))
    image.paste(rect, tile_pixels(rect, seed));
  return image;
}

class SchedulerFramesTest : public SchedulerTest {
 protected:
  JobRecord submit_frames(std::vector<int> frames) {
    return s().submit("animation", 50, scene_of(kSize, kSize, kTile), "{\"frames\": 1}",
                      std::move(frames));
  }
  // Claims and delivers leases, each with its frame's number as the seed, until `done`.
  void deliver_until(const std::string& worker_id, const std::function<bool()>& done,
                     int max_tiles = 100) {
    for (int guard = 0; guard < 100 && !done(); ++guard) {
      const auto lease = s().claim(worker_id, max_tiles);
      ASSERT_TRUE(lease);
      ASSERT_EQ(deliver(*lease, static_cast<float>(lease->frame)), ResultOutcome::accepted);
    }
    ASSERT_TRUE(done());
  }
  std::map<int, protocol::FrameState> frame_states(const std::string& job_id) {
    std::map<int, protocol::FrameState> states;
    const std::vector<FrameRecord> frames = *s().frames(job_id);
    for (const FrameRecord& frame : frames) states[frame.frame] = frame.state;
    return states;
  }
};

TEST_F(SchedulerFramesTest, FramesGoOutInOrderEachLeaseWithinOneFrame) {
  const std::string w = worker();
  const JobRecord job = submit_frames({3, 5, 7});
  EXPECT_EQ(job.tiles_total, 12);
  EXPECT_EQ(job.frames->list, "3-7x2");
  EXPECT_EQ(job.current_frame, 3);
  std::vector<int> frames_leased;
  while (s().job(job.id)->state != JobState::completed) {
    // As many tiles as it likes: the lease still stops at the end of its frame.
    const auto lease = s().claim(w, 100);
    ASSERT_TRUE(lease);
    std::set<int> slots;
    for (const LeaseTileRecord& tile : lease->tiles) slots.insert(tile.index / 4);
    EXPECT_EQ(slots.size(), 1u) << "a lease spans frames";
    EXPECT_EQ(lease->frame, 3 + 2 * *slots.begin());
    frames_leased.push_back(lease->frame);
    ASSERT_EQ(deliver(*lease, static_cast<float>(lease->frame)), ResultOutcome::accepted);
  }
  EXPECT_TRUE(std::is_sorted(frames_leased.begin(), frames_leased.end()));
  const JobRecord done = *s().job(job.id);
  EXPECT_EQ(done.frames_done, 3);
  EXPECT_FALSE(done.current_frame);
  s().wait_for_images();
  for (const int frame : {3, 5, 7}) {
    const auto image = s().assemble_frame(job.id, frame);
    ASSERT_TRUE(image);
    EXPECT_TRUE(same_bits(image->pixels(), expected_frame(static_cast<float>(frame)).pixels()))
        << "frame " << frame << " holds another frame's tiles";
    EXPECT_TRUE(s().frame_image_file(job.id, frame)) << frame;
  }
  EXPECT_FALSE(s().assemble_frame(job.id, 4)) << "a frame the job does not render";
  // The job's own image is its first frame's.
  EXPECT_TRUE(same_bits(s().assemble(job.id)->pixels(), expected_frame(3).pixels()));
}

TEST_F(SchedulerFramesTest, AnExtensionAddsTilesOfItsLeasesFrameOnly) {
  const std::string w = worker();
  const JobRecord job = submit_frames({1, 2});
  const auto lease = s().claim(w, 2);
  ASSERT_TRUE(lease);
  ASSERT_EQ(lease->tiles.size(), 2u);
  const auto more = s().extend(lease->id, 100);
  ASSERT_TRUE(more);
  EXPECT_EQ(more->tiles.size(), 2u) << "the rest of frame 1, and none of frame 2";
  for (const LeaseTileRecord& tile : more->tiles) EXPECT_LT(tile.index, 4);
  const auto none = s().extend(lease->id, 100);
  ASSERT_TRUE(none);
  EXPECT_TRUE(none->tiles.empty());
}

TEST_F(SchedulerFramesTest, EachFrameIsWholeAsSoonAsItsLastTileLands) {
  const std::string w = worker();
  const JobRecord job = submit_frames({1, 2});
  deliver_until(w, [&] { return s().job(job.id)->frames_done == 1; });
  EXPECT_EQ(s().job(job.id)->state, JobState::running);
  EXPECT_EQ(s().job(job.id)->current_frame, 2);
  EXPECT_EQ(frame_states(job.id),
            (std::map<int, protocol::FrameState>{{1, protocol::FrameState::done},
                                                 {2, protocol::FrameState::pending}}));
  s().wait_for_images();
  EXPECT_TRUE(s().frame_image_file(job.id, 1)) << "frame 1's file waits for the job";
  EXPECT_FALSE(s().frame_image_file(job.id, 2));
  EXPECT_TRUE(same_bits(s().assemble_frame(job.id, 1)->pixels(), expected_frame(1).pixels()));
}

TEST_F(SchedulerFramesTest, AFrameWhoseTileFailsForGoodFailsAloneAndTheJobEndsFailed) {
  config_.max_tile_attempts = 1;
  reopen();
  const std::string w = worker();
  const JobRecord job = submit_frames({1, 2, 3});
  deliver_until(w, [&] { return s().job(job.id)->frames_done == 1; });
  const auto lease = s().claim(w, 1);
  ASSERT_TRUE(lease);
  ASSERT_EQ(lease->frame, 2);
  s().fail_tile(lease->id, lease->tiles.front().index, "out of memory");
  JobRecord now = *s().job(job.id);
  EXPECT_EQ(now.state, JobState::running) << "the job goes on with its other frames";
  EXPECT_EQ(now.failed_frames, std::vector<int>{2});
  EXPECT_EQ(now.current_frame, 3);
  // Frame 2's other tiles no longer go out: every lease from now on is of frame 3.
  while (s().job(job.id)->state == JobState::running) {
    const auto next = s().claim(w, 1);
    ASSERT_TRUE(next);
    EXPECT_EQ(next->frame, 3);
    ASSERT_EQ(deliver(*next, 3.0f), ResultOutcome::accepted);
  }
  now = *s().job(job.id);
  EXPECT_EQ(now.state, JobState::failed);
  EXPECT_NE(now.error.find("1 of 3 frames failed: 2"), std::string::npos) << now.error;
  EXPECT_NE(now.error.find("out of memory"), std::string::npos) << now.error;
  EXPECT_EQ(now.frames_done, 2);
  const auto frames = *s().frames(job.id);
  ASSERT_EQ(frames.size(), 3u);
  EXPECT_EQ(frames[1].state, protocol::FrameState::failed);
  EXPECT_NE(frames[1].error.find("out of memory"), std::string::npos) << frames[1].error;
  // The frames done keep their images although the job failed.
  s().wait_for_images();
  EXPECT_TRUE(s().frame_image_file(job.id, 1));
  EXPECT_TRUE(s().frame_image_file(job.id, 3));
  EXPECT_TRUE(same_bits(s().assemble_frame(job.id, 3)->pixels(), expected_frame(3).pixels()));

  // A retry renders the failed frame again, and the job completes.
  ASSERT_EQ(s().retry(job.id).result, ControlOutcome::Result::done);
  EXPECT_TRUE(s().job(job.id)->failed_frames.empty());
  deliver_until(w, [&] { return s().job(job.id)->state == JobState::completed; });
  s().wait_for_images();
  EXPECT_TRUE(same_bits(s().assemble_frame(job.id, 2)->pixels(), expected_frame(2).pixels()));
  EXPECT_TRUE(s().frame_image_file(job.id, 2));
}

TEST_F(SchedulerFramesTest, TheLastFrameFailingEndsTheJobAtOnce) {
  config_.max_tile_attempts = 1;
  reopen();
  const std::string w = worker();
  const JobRecord job = submit_frames({1, 2});
  deliver_until(w, [&] { return s().job(job.id)->frames_done == 1; });
  const auto lease = s().claim(w, 1);
  ASSERT_TRUE(lease);
  s().fail_tile(lease->id, lease->tiles.front().index, "broke");
  const JobRecord now = *s().job(job.id);
  EXPECT_EQ(now.state, JobState::failed);
  EXPECT_NE(now.error.find("1 of 2 frames failed: 2"), std::string::npos) << now.error;
  EXPECT_EQ(now.tiles_rendering, 0);
}

TEST_F(SchedulerFramesTest, ARestartKeepsEveryFinishedFrameAndDeliveredTile) {
  const std::string w = worker();
  const JobRecord job = submit_frames({0, 1, 2});
  deliver_until(w, [&] { return s().job(job.id)->frames_done == 1; });
  const auto lease = s().claim(w, 1);
  ASSERT_TRUE(lease);
  ASSERT_EQ(deliver(*lease, 1.0f), ResultOutcome::accepted);
  s().wait_for_images();
  reopen();
  const JobRecord now = *s().job(job.id);
  EXPECT_EQ(now.frames_done, 1);
  EXPECT_EQ(now.tiles_done, 5);
  EXPECT_EQ(now.current_frame, 1);
  EXPECT_EQ(now.frames->list, "0-2");
  EXPECT_TRUE(s().frame_image_file(job.id, 0));
  EXPECT_TRUE(same_bits(s().assemble_frame(job.id, 0)->pixels(), expected_frame(0).pixels()));
  const std::string again = worker("again");
  deliver_until(again, [&] { return s().job(job.id)->state == JobState::completed; });
  s().wait_for_images();
  for (const int frame : {0, 1, 2})
    EXPECT_TRUE(
        same_bits(s().assemble_frame(job.id, frame)->pixels(), expected_frame(frame).pixels()))
        << frame;
}

TEST_F(SchedulerFramesTest, ACanceledAnimationKeepsItsFramesDone) {
  const std::string w = worker();
  const JobRecord job = submit_frames({1, 2});
  deliver_until(w, [&] { return s().job(job.id)->frames_done == 1; });
  ASSERT_EQ(s().cancel(job.id), CancelOutcome::canceled);
  s().wait_for_images();
  EXPECT_TRUE(s().frame_image_file(job.id, 1));
  reopen();
  EXPECT_TRUE(s().frame_image_file(job.id, 1)) << "pruned at start-up";
  ASSERT_EQ(s().remove(job.id), RemoveOutcome::removed);
  s().wait_for_images();
  EXPECT_FALSE(std::filesystem::exists(dir_ / "images" / (job.id + ".f1.exr")));
}

// Priority works across frames as across a still's tiles: a job of higher priority takes
// the next claim, and an animation's extension stops while one waits.
TEST_F(SchedulerFramesTest, PriorityAndPauseWorkAcrossFrames) {
  const std::string w = worker();
  const JobRecord low = submit_frames({1, 2, 3});
  const auto first = s().claim(w, 2);
  ASSERT_TRUE(first);
  EXPECT_EQ(first->job_id, low.id);
  const JobRecord high =
      s().submit("urgent", 90, scene_of(kSize, kSize, kTile), "{\"urgent\": 1}", {7, 8});
  const auto more = s().extend(first->id, 10);
  ASSERT_TRUE(more);
  EXPECT_TRUE(more->tiles.empty()) << "the animation's lease grew past a job of higher priority";
  ASSERT_EQ(deliver(*first, 1.0f), ResultOutcome::accepted);
  const auto next = s().claim(w, 100);
  ASSERT_TRUE(next);
  EXPECT_EQ(next->job_id, high.id);
  EXPECT_EQ(next->frame, 7);
  ASSERT_EQ(deliver(*next, 7.0f), ResultOutcome::accepted);
  // Paused, the urgent job gives way, and the animation takes up where it was.
  ASSERT_EQ(s().pause(high.id).result, ControlOutcome::Result::done);
  const auto back = s().claim(w, 100);
  ASSERT_TRUE(back);
  EXPECT_EQ(back->job_id, low.id);
  EXPECT_EQ(back->frame, 1) << "the rest of frame 1 first";
}

TEST_F(SchedulerFramesTest, AStillIsOneFrameZeroWithItsImageWhereItWas) {
  const std::string w = worker();
  const JobRecord job = submit(kSize, kSize, kTile);
  EXPECT_FALSE(job.frames->animated());
  EXPECT_EQ(job.frames->numbers, std::vector<int>{0});
  finish(job.id, w);
  s().wait_for_images();
  EXPECT_TRUE(std::filesystem::exists(dir_ / "images" / (job.id + ".exr")));
  EXPECT_EQ(s().frame_image_file(job.id, 0), s().image_file(job.id));
}

}  // namespace
}  // namespace tessera::test
