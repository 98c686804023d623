#include <algorithm>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>

#include <bit>
#include <chrono>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <thread>

#include <gtest/gtest.h>

#include "common/image/image.hpp"
#include "common/image/image_io.hpp"

namespace tessera {
namespace {

std::filesystem::path temp_dir() {
  auto dir =
      std::filesystem::temp_directory_path() /
      ("tessera-image-test-" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) +
       "-" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

// Whether OpenImageIO's library is mapped into this process. ctest runs each test in a
// process of its own, so a test that needs the libraries unloaded finds them so there.
bool openimageio_loaded() {
  std::ifstream maps("/proc/self/maps");
  std::string line;
  while (std::getline(maps, line))
    if (line.find("libOpenImageIO.so") != std::string::npos) return true;
  return false;
}

TEST(TilesTest, CoverTheImageExactlyOnce) {
  for (int tile_size : {1, 7, 32, 64, 1000}) {
    const auto tiles = split_into_tiles(100, 37, tile_size);
    std::vector<int> covered(100 * 37, 0);
    for (const TileRect& t : tiles) {
      EXPECT_LE(t.width, tile_size);
      EXPECT_LE(t.height, tile_size);
      for (int y = t.y; y < t.y + t.height; ++y)
        for (int x = t.x; x < t.x + t.width; ++x) covered[y * 100 + x] += 1;
    }
    EXPECT_EQ(std::set<int>(covered.begin(), covered.end()), std::set<int>{1}) << tile_size;
  }
  EXPECT_EQ(split_into_tiles(100, 37, 32).size(), 4u * 2u);
  EXPECT_EQ(split_into_tiles(100, 37, 32).back(), (TileRect{96, 32, 4, 5}));
}

TEST(TilesTest, RejectNonPositiveSizes) {
  EXPECT_THROW(split_into_tiles(0, 10, 4), std::invalid_argument);
  EXPECT_THROW(split_into_tiles(10, 10, 0), std::invalid_argument);
}

TEST(ImageTest, ANewImageIsBlackAndItsSizesAreCheckedFirst) {
  const Image image(5, 3);
  ASSERT_EQ(image.pixels().size(), 5u * 3u * 3u);
  EXPECT_TRUE(
      std::all_of(image.pixels().begin(), image.pixels().end(), [](float v) { return v == 0.0f; }));
  // Checked before anything is allocated: -1 would otherwise wrap around to 2^64 - 1 and
  // fail as an allocation instead.
  EXPECT_THROW(Image(-1, 4), std::invalid_argument);
  EXPECT_THROW(Image(4, 0, Image::Unset{}), std::invalid_argument);
  EXPECT_EQ(Image(4, 2, Image::Unset{}).pixels().size(), 24u);
}

// The VmFlags of the mapping of /proc/self/smaps that holds `address`, or "" if none does.
std::string mapping_flags(const void* address) {
  std::ifstream smaps("/proc/self/smaps");
  const auto at = reinterpret_cast<std::uintptr_t>(address);
  bool inside = false;
  for (std::string line; std::getline(smaps, line);) {
    std::uintptr_t begin = 0;
    std::uintptr_t end = 0;
    char dash = 0;
    std::istringstream fields(line);
    // A mapping's first line is "begin-end perms ...", in hexadecimal.
    if (fields >> std::hex >> begin >> dash >> end && dash == '-') inside = begin <= at && at < end;
    if (inside && line.rfind("VmFlags:", 0) == 0) return line;
  }
  return "";
}

TEST(ImageTest, ABigImagesPixelsAskForHugePages) {
  // A 1920x1080 image first touched page by page takes six thousand page faults, each
  // costly on a virtual machine; on huge pages it takes a dozen.
  const Image big(1920, 1080, Image::Unset{});
  if (!std::filesystem::exists("/sys/kernel/mm/transparent_hugepage"))
    GTEST_SKIP() << "this kernel has no transparent huge pages";
  // "hg": the mapping was advised MADV_HUGEPAGE, whether or not huge pages were free. The
  // advice covers the whole huge pages inside the buffer: the middle is one of them.
  const float* middle = big.pixels().data() + big.pixels().size() / 2;
  const std::string flags = mapping_flags(middle);
  EXPECT_NE(flags.find(" hg"), std::string::npos) << flags;
  // A small one stays on ordinary memory.
  const Image small(16, 16);
  EXPECT_EQ(mapping_flags(small.pixels().data()).find(" hg"), std::string::npos);
}

TEST(ImageTest, PastePutsTilePixelsInPlace) {
  Image image(4, 3);
  const std::vector<float> tile{1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12};  // 2x2
  image.paste({2, 1, 2, 2}, tile);
  EXPECT_EQ(image.pixel(2, 1)[0], 1.0f);
  EXPECT_EQ(image.pixel(3, 1)[2], 6.0f);
  EXPECT_EQ(image.pixel(2, 2)[0], 7.0f);
  EXPECT_EQ(image.pixel(3, 2)[2], 12.0f);
  EXPECT_EQ(image.pixel(1, 1)[0], 0.0f);
  EXPECT_THROW(image.paste({3, 1, 2, 2}, tile), std::out_of_range);
  EXPECT_THROW(image.paste({0, 0, 1, 1}, tile), std::invalid_argument);
}

TEST(ImageIoTest, ExrKeepsLinearFloatsExactlyAndUnclamped) {
  const auto dir = temp_dir();
  Image image(3, 2);
  const float values[] = {0.0f, 0.25f, 1.0f, 7.5f, 1e-6f, 123.456f};
  for (std::size_t i = 0; i < image.pixels().size(); ++i) image.pixels()[i] = values[i % 6] + i;
  write_image(image, dir / "a.exr", OutputTransfer::srgb);
  const Image back = read_image(dir / "a.exr");
  ASSERT_EQ(back.width(), 3);
  ASSERT_EQ(back.height(), 2);
  for (std::size_t i = 0; i < image.pixels().size(); ++i)
    EXPECT_EQ(back.pixels()[i], image.pixels()[i]) << i;
}

TEST(ImageIoTest, PngIsClampedAndSrgbEncoded) {
  const auto dir = temp_dir();
  Image image(4, 1);
  const float values[] = {0.5f, 2.0f, -1.0f, 0.0031308f};
  for (int x = 0; x < 4; ++x)
    for (int c = 0; c < 3; ++c) image.pixel(x, 0)[c] = values[x];
  write_image(image, dir / "a.png", OutputTransfer::srgb);
  const Image srgb = read_image(dir / "a.png");
  // 0.5 linear is 0.7354 in sRGB, code 188 of 255.
  EXPECT_FLOAT_EQ(srgb.pixel(0, 0)[0], 188.0f / 255.0f);
  EXPECT_FLOAT_EQ(srgb.pixel(1, 0)[0], 1.0f);
  EXPECT_FLOAT_EQ(srgb.pixel(2, 0)[0], 0.0f);
  EXPECT_FLOAT_EQ(srgb.pixel(3, 0)[0], 10.0f / 255.0f);  // 0.04045 on the linear segment

  write_image(image, dir / "b.png", OutputTransfer::linear);
  EXPECT_FLOAT_EQ(read_image(dir / "b.png").pixel(0, 0)[0], 128.0f / 255.0f);
}

TEST(ImageIoTest, SrgbTableGivesTheFormulasCodes) {
  // PNGs are encoded by table; it must give pow()'s codes bit for bit. Every 61st float in
  // [0, 1], and every float within 200 ulps of each point where the code steps up.
  int differing = 0;
  const auto one = std::bit_cast<std::uint32_t>(1.0f);
  for (std::uint32_t bits = 0; bits <= one; bits += 61) {
    const float v = std::bit_cast<float>(bits);
    differing += srgb8_by_table(v) != srgb8_by_formula(v);
  }
  // The steps, found by bisection on the formula alone.
  int steps = 0;
  for (int code = 1; code <= 255; ++code) {
    std::uint32_t lo = 0, hi = one;  // formula(lo) < code <= formula(hi)
    while (hi - lo > 1) {
      const std::uint32_t mid = lo + (hi - lo) / 2;
      (srgb8_by_formula(std::bit_cast<float>(mid)) >= code ? hi : lo) = mid;
    }
    ++steps;
    for (std::uint32_t near = hi - 200; near <= hi + 200 && near <= one; ++near)
      differing += srgb8_by_table(std::bit_cast<float>(near)) !=
                   srgb8_by_formula(std::bit_cast<float>(near));
  }
  EXPECT_EQ(steps, 255);
  for (float v : {-1.0f, -0.0f, 0.0f, 1.0f, 2.0f, std::numeric_limits<float>::infinity(),
                  -std::numeric_limits<float>::infinity(), std::numeric_limits<float>::quiet_NaN()})
    differing += srgb8_by_table(v) != srgb8_by_formula(v);
  EXPECT_EQ(differing, 0);
}

TEST(ImageIoTest, TiffIsSixteenBitAndJpegWorks) {
  const auto dir = temp_dir();
  Image image(2, 2);
  for (float& v : image.pixels()) v = 0.5f;
  write_image(image, dir / "a.tif", OutputTransfer::linear);
  EXPECT_FLOAT_EQ(read_image(dir / "a.tif").pixel(1, 1)[1], 32768.0f / 65535.0f);
  write_image(image, dir / "a.jpg", OutputTransfer::srgb);
  EXPECT_NEAR(read_image(dir / "a.jpg").pixel(0, 0)[0], 188.0f / 255.0f, 2.0f / 255.0f);
}

TEST(ImageIoTest, WriteIsAtomicAndLeavesNoTemporaryFiles) {
  const auto dir = temp_dir();
  Image image(2, 2);
  write_image(image, dir / "out.png", OutputTransfer::srgb);
  write_image(image, dir / "out.png", OutputTransfer::srgb);  // replaces in place
  std::vector<std::string> names;
  for (const auto& entry : std::filesystem::directory_iterator(dir))
    names.push_back(entry.path().filename().string());
  EXPECT_EQ(names, std::vector<std::string>{"out.png"});
}

TEST(ImageIoTest, EncodingNeedsNoneOfOpenImageIO) {
  if (openimageio_loaded()) GTEST_SKIP() << "OpenImageIO is loaded already (run by ctest)";
  const auto dir = temp_dir();
  Image image(3, 2);
  for (std::size_t i = 0; i < image.pixels().size(); ++i) image.pixels()[i] = 0.1f * i;
  const EncodedImage encoded(image, dir / "a.png", OutputTransfer::srgb);
  EXPECT_FALSE(openimageio_loaded());
  EXPECT_THROW(EncodedImage(image, dir / "a.bmp", OutputTransfer::srgb), std::runtime_error);

  write_image(encoded);
  write_image(image, dir / "b.png", OutputTransfer::srgb);
  const Image a = read_image(dir / "a.png"), b = read_image(dir / "b.png");
  ASSERT_EQ(a.width(), 3);
  EXPECT_TRUE(std::equal(a.pixels().begin(), a.pixels().end(), b.pixels().begin()));
  EXPECT_FLOAT_EQ(a.pixel(2, 1)[2], 255.0f / 255.0f);  // 1.7, clamped
}

TEST(ImageIoTest, TheLibrariesLoadWhileTheWorkRunsOnAThreadOfItsOwn) {
  if (openimageio_loaded()) GTEST_SKIP() << "OpenImageIO is loaded already (run by ctest)";
  // The work waits until it sees the libraries mapped, which, were they loaded only after
  // it, would never happen.
  const auto caller = std::this_thread::get_id();
  std::thread::id worker;
  bool seen = false;
  while_loading_image_files([&] {
    worker = std::this_thread::get_id();
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    while (!(seen = openimageio_loaded()) && std::chrono::steady_clock::now() < deadline)
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
  });
  EXPECT_TRUE(seen);
  EXPECT_NE(worker, caller);

  EXPECT_THROW(while_loading_image_files([] { throw std::invalid_argument("from the work"); }),
               std::invalid_argument);
}

TEST(ImageIoTest, RejectsUnknownExtensionsAndUnwritablePaths) {
  Image image(2, 2);
  EXPECT_FALSE(is_supported_image_path("a.bmp"));
  EXPECT_TRUE(is_supported_image_path("A.PNG"));
  EXPECT_THROW(write_image(image, "a.bmp", OutputTransfer::srgb), std::runtime_error);
  EXPECT_THROW(write_image(image, "/nonexistent-dir/a.png", OutputTransfer::srgb),
               std::runtime_error);
  EXPECT_THROW(read_image("/nonexistent-dir/a.png"), std::runtime_error);
}

}  // namespace
}  // namespace tessera
