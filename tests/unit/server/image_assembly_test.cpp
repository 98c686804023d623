// ImageAssembly on its own, over a real Store: tiles durable before a job's canvas exists
// come into it from the store, later ones are pasted, and a completed job's image file
// holds every tile; an ended job's image comes from the store; a removed job's file goes.
#include "server/farm/image_assembly.hpp"
#include "server/farm/sqlite_store.hpp"

#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <future>
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "tests/unit/server/test_dir.hpp"

#include "common/image/image_io.hpp"

namespace tessera {
namespace {

constexpr int kSize = 64;
constexpr int kTile = 16;  // 16 tiles

std::vector<float> pixels_of(const TileRect& rect) {
  std::vector<float> pixels;
  for (int y = rect.y; y < rect.y + rect.height; ++y)
    for (int x = rect.x; x < rect.x + rect.width; ++x)
      for (int c = 0; c < 3; ++c)
        pixels.push_back(static_cast<float>(x * 3 + y * 1000 + c) + 0.25f);
  return pixels;
}

bool same_bits(const Image& a, const Image& b) {
  return a.pixels().size() == b.pixels().size() &&
         std::memcmp(a.pixels().data(), b.pixels().data(), a.pixels().size_bytes()) == 0;
}

class ImageAssemblyTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = test::fresh_test_dir("tessera-image-assembly-test");
    store_ = std::make_unique<SqliteStore>(dir_);
    thread_ = std::make_unique<StoreThread>(*store_);
    images_ = std::make_unique<ImageAssembly>(
        dir_, *thread_, [this](const std::string&, const std::string& error) { failed_ = error; });
    auto rects =
        std::make_shared<const std::vector<TileRect>>(split_into_tiles(kSize, kSize, kTile));
    frame_ = std::make_shared<Frame>(
        Frame{kSize, kSize, rects, "j-1", 0, static_cast<int>(rects->size())});
    for (const TileRect& rect : *frame_->tiles) tiles_.push_back(pixels_of(rect));
    JobRow row;
    row.id = "j-1";
    row.state = "running";
    row.width = kSize;
    row.height = kSize;
    row.tile_size = kTile;
    row.scene_digest = "d";
    thread_->wait(thread_->write([row](Store& store) { store.insert_job(row, "{}"); }));
    images_->add("j-1", frame_);
  }
  void TearDown() override {
    images_.reset();
    thread_.reset();
    store_.reset();
    std::filesystem::remove_all(dir_);
  }

  // Stores tile `index` as the Scheduler does, and tells the assembly once it is durable.
  void deliver(int index, bool last = false) {
    ResultRow row;
    row.job_id = "j-1";
    row.lease_id = "l-" + std::to_string(index);
    row.worker_id = "w";
    row.tiles = {index};
    row.rays = {1};
    const std::span<const float> pixels = tiles_[index];
    const StoreTicket ticket = thread_->write([row, pixels](Store& store) {
      const std::span<const float> parts[] = {pixels};
      store.insert_result(row, parts);
    });
    thread_->after(ticket, [this, index, pixels, last](const std::string& error) {
      ASSERT_EQ(error, "");
      images_->stored("j-1", {{index, pixels}}, last);
    });
    thread_->wait(ticket);
  }
  std::shared_ptr<const Image> assembled() {
    std::promise<std::shared_ptr<const Image>> image;
    images_->assemble("j-1", [&](std::shared_ptr<const Image> made) { image.set_value(made); });
    return image.get_future().get();
  }
  Image expected(int tiles) const {
    Image image(kSize, kSize);
    for (int i = 0; i < tiles; ++i) image.paste((*frame_->tiles)[i], tiles_[i]);
    return image;
  }

  std::filesystem::path dir_;
  std::unique_ptr<SqliteStore> store_;
  std::unique_ptr<StoreThread> thread_;
  std::unique_ptr<ImageAssembly> images_;
  std::shared_ptr<Frame> frame_;
  std::vector<std::vector<float>> tiles_;
  std::string failed_;
};

TEST_F(ImageAssemblyTest, TilesBeforeAndAfterTheCanvasAllReachTheImageFile) {
  const int count = static_cast<int>(frame_->tiles->size());
  // The first tiles ask for the canvas; those stored while it is made come from the store.
  for (int i = 0; i < count / 2; ++i) deliver(i);
  images_->wait_for_images();  // the canvas is in place
  EXPECT_TRUE(same_bits(*assembled(), expected(count / 2)));
  for (int i = count / 2; i < count; ++i) deliver(i, i == count - 1);
  images_->completed("j-1");
  images_->wait_for_images();
  ASSERT_TRUE(images_->image_file("j-1"));
  EXPECT_TRUE(same_bits(read_image(*images_->image_file("j-1")), expected(count)));
  EXPECT_EQ(failed_, "");
}

TEST_F(ImageAssemblyTest, AJobCompletedByItsFirstTilesIsWrittenFromTheStore) {
  for (int i = 0; i < static_cast<int>(frame_->tiles->size()); ++i) deliver(i, true);
  images_->completed("j-1");
  images_->wait_for_images();
  ASSERT_TRUE(images_->image_file("j-1"));
  EXPECT_TRUE(same_bits(read_image(*images_->image_file("j-1")),
                        expected(static_cast<int>(tiles_.size()))));
}

TEST_F(ImageAssemblyTest, AnEndedJobIsAssembledFromTheStoreAndARemovedOnesFileGoes) {
  for (int i = 0; i < 5; ++i) deliver(i);
  images_->wait_for_images();
  images_->ended("j-1");
  EXPECT_FALSE(images_->image_file("j-1"));
  EXPECT_TRUE(same_bits(*assembled(), expected(5)));

  images_->add("j-2", frame_, ImageAssembly::Stage::completed);
  images_->completed("j-2");  // nothing stored: a black image, written all the same
  images_->wait_for_images();
  ASSERT_TRUE(images_->image_file("j-2"));
  const std::filesystem::path file = *images_->image_file("j-2");
  images_->removed("j-2");
  EXPECT_FALSE(std::filesystem::exists(file));
  EXPECT_FALSE(images_->image_file("j-2"));
}

}  // namespace
}  // namespace tessera
