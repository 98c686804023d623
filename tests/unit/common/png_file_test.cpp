// PNGs written with libpng (common/image/png_file.hpp) through write_image(): the codes that come
// back through OpenImageIO, the colour chunks, the errors, and that no PNG opens the
// image-file module.
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <csignal>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "common/image/image.hpp"
#include "common/image/image_io.hpp"
#include "common/image/png_file.hpp"

extern char** environ;

namespace tessera {
namespace {

namespace fs = std::filesystem;

fs::path fresh_dir() {
  const auto* test = ::testing::UnitTest::GetInstance()->current_test_info();
  const fs::path dir = fs::temp_directory_path() /
                       ("tessera-png-test-" + std::to_string(::getpid()) + "-" + test->name());
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::vector<std::string> names_in(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir)) names.push_back(entry.path().filename());
  std::sort(names.begin(), names.end());
  return names;
}

std::string file_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream bytes;
  bytes << in.rdbuf();
  return bytes.str();
}

// A PNG's chunks by type (the last of each), after its 8-byte signature.
std::map<std::string, std::string> chunks_of(const std::string& png) {
  std::map<std::string, std::string> chunks;
  for (std::size_t at = 8; at + 12 <= png.size();) {
    const auto byte = [&](std::size_t i) {
      return static_cast<std::uint32_t>(std::uint8_t(png[i]));
    };
    const std::uint32_t length =
        byte(at) << 24 | byte(at + 1) << 16 | byte(at + 2) << 8 | byte(at + 3);
    chunks[png.substr(at + 4, 4)] = png.substr(at + 8, length);
    at += 12 + length;
  }
  return chunks;
}

std::uint32_t big_endian(const std::string& bytes, std::size_t at) {
  std::uint32_t value = 0;
  for (std::size_t i = at; i < at + 4; ++i) value = value << 8 | std::uint8_t(bytes[i]);
  return value;
}

// Every kind of value a render can hold, then a spread over [0, 1] that crosses many code
// steps, in all three channels at different places.
Image test_pattern() {
  constexpr float inf = std::numeric_limits<float>::infinity();
  std::vector<float> values{-1.0f,      -0.0f,    0.0f,    1e-7f,
                            0.0031308f, 0.04045f, 0.2f,    0.5f,
                            0.999f,     1.0f,     1.0001f, 1.5f,
                            1e9f,       inf,      -inf,    std::numeric_limits<float>::quiet_NaN(),
                            -1e-30f};
  for (int i = 0; i <= 1000; ++i) values.push_back(static_cast<float>(i) / 1000.0f);
  const int width = 32;
  const int height = static_cast<int>((values.size() + width - 1) / width);
  Image image(width, height);
  for (std::size_t i = 0; i < image.pixels().size(); ++i)
    image.pixels()[i] = values[(i * 7 + i / 3) % values.size()];
  return image;
}

int expected_linear_code(float v) {
  if (std::isnan(v)) return 0;
  return static_cast<int>(std::lround(std::clamp(v, 0.0f, 1.0f) * 255.0f));
}

TEST(PngFileTest, CodesReadBackExactlyThroughOpenImageIO) {
  const fs::path dir = fresh_dir();
  const Image image = test_pattern();
  write_image(image, dir / "srgb.png", OutputTransfer::srgb);
  write_image(image, dir / "linear.png", OutputTransfer::linear);
  const Image srgb = read_image(dir / "srgb.png");
  const Image linear = read_image(dir / "linear.png");
  ASSERT_EQ(srgb.width(), image.width());
  ASSERT_EQ(srgb.height(), image.height());
  ASSERT_EQ(linear.width(), image.width());
  int wrong_srgb = 0, wrong_linear = 0;
  for (std::size_t i = 0; i < image.pixels().size(); ++i) {
    const float v = image.pixels()[i];
    const int srgb_code = static_cast<int>(std::lround(srgb.pixels()[i] * 255.0f));
    const int linear_code = static_cast<int>(std::lround(linear.pixels()[i] * 255.0f));
    if (srgb_code != srgb8_by_formula(v)) {
      ++wrong_srgb;
      ADD_FAILURE() << "sRGB: value " << v << " came back as code " << srgb_code << ", not "
                    << int(srgb8_by_formula(v));
    }
    if (linear_code != expected_linear_code(v)) {
      ++wrong_linear;
      ADD_FAILURE() << "linear: value " << v << " came back as code " << linear_code;
    }
  }
  EXPECT_EQ(wrong_srgb, 0);
  EXPECT_EQ(wrong_linear, 0);
  // Spot checks worked out by hand: 0.5 is 0.7354 in sRGB, code 188; linear 128.
  Image half(1, 1);
  half.pixels()[0] = half.pixels()[1] = half.pixels()[2] = 0.5f;
  write_image(half, dir / "half.png", OutputTransfer::srgb);
  EXPECT_EQ(std::lround(read_image(dir / "half.png").pixels()[0] * 255.0f), 188);
  write_image(half, dir / "half.png", OutputTransfer::linear);
  EXPECT_EQ(std::lround(read_image(dir / "half.png").pixels()[0] * 255.0f), 128);
}

TEST(PngFileTest, HoldsExactlyTheEncodedCodes) {
  // The file's pixels are EncodedImage's bytes, whatever libpng's settings.
  const fs::path dir = fresh_dir();
  const Image image = test_pattern();
  const EncodedImage encoded(image, dir / "a.png", OutputTransfer::srgb);
  const auto* codes = static_cast<const std::uint8_t*>(encoded.content().pixels);
  for (const auto filter : {PngCompression::Filter::none, PngCompression::Filter::sub,
                            PngCompression::Filter::adaptive})
    for (const int level : {0, 1, 9}) {
      write_png(dir / "a.png", PngPixels{image.width(), image.height(), codes, true},
                PngCompression{level, filter});
      const Image back = read_image(dir / "a.png");
      int differing = 0;
      for (std::size_t i = 0; i < back.pixels().size(); ++i)
        differing += std::lround(back.pixels()[i] * 255.0f) != codes[i];
      EXPECT_EQ(differing, 0) << "level " << level << ", filter " << int(filter);
    }
}

TEST(PngFileTest, SrgbChunkOnlyForSrgbCodes) {
  const fs::path dir = fresh_dir();
  Image image(3, 2);
  write_image(image, dir / "srgb.png", OutputTransfer::srgb);
  write_image(image, dir / "linear.png", OutputTransfer::linear);
  const std::string srgb_file = file_bytes(dir / "srgb.png");
  ASSERT_EQ(srgb_file.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  const auto srgb = chunks_of(srgb_file);
  const auto linear = chunks_of(file_bytes(dir / "linear.png"));
  // IHDR: 3 × 2, 8 bits, colour type 2 (RGB), no interlacing.
  ASSERT_EQ(srgb.count("IHDR"), 1u);
  EXPECT_EQ(big_endian(srgb.at("IHDR"), 0), 3u);
  EXPECT_EQ(big_endian(srgb.at("IHDR"), 4), 2u);
  EXPECT_EQ(srgb.at("IHDR").substr(8), std::string("\x08\x02\x00\x00\x00", 5));
  EXPECT_EQ(srgb.count("sRGB"), 1u);
  EXPECT_EQ(srgb.count("cHRM"), 1u);
  ASSERT_EQ(srgb.count("gAMA"), 1u);
  EXPECT_EQ(big_endian(srgb.at("gAMA"), 0), 45455u);  // 1/2.2, what the sRGB chunk implies
  EXPECT_EQ(linear.count("sRGB"), 0u);
  EXPECT_EQ(linear.count("cHRM"), 0u);
  ASSERT_EQ(linear.count("gAMA"), 1u);
  EXPECT_EQ(big_endian(linear.at("gAMA"), 0), 100000u);  // gamma 1: linear
  EXPECT_EQ(linear.count("IEND"), 1u);
}

// Whether the image-file module, or OpenImageIO by any road, is mapped into this process.
bool module_mapped() {
  std::ifstream maps("/proc/self/maps");
  for (std::string line; std::getline(maps, line);)
    if (line.find("libtessera_image_files") != std::string::npos ||
        line.find("libOpenImageIO.so") != std::string::npos)
      return true;
  return false;
}

constexpr const char* kFreshProcess = "TESSERA_PNG_TEST_FRESH_PROCESS";

TEST(PngFileTest, WritingOneOpensNoModule) {
  // The tests share one process, where another may have opened the module already, so this
  // one runs itself again alone, in a fresh process of this program.
  if (std::getenv(kFreshProcess) == nullptr) {
    std::string self = fs::read_symlink("/proc/self/exe");
    std::string filter = "--gtest_filter=PngFile.WritingOneOpensNoModule";
    std::vector<char*> argv{self.data(), filter.data(), nullptr};
    std::vector<std::string> environment{std::string(kFreshProcess) + "=1"};
    for (char** variable = environ; *variable != nullptr; ++variable)
      environment.emplace_back(*variable);
    std::vector<char*> envp;
    for (std::string& variable : environment) envp.push_back(variable.data());
    envp.push_back(nullptr);
    pid_t child = 0;
    ASSERT_EQ(::posix_spawn(&child, self.c_str(), nullptr, nullptr, argv.data(), envp.data()), 0);
    int status = 0;
    ASSERT_EQ(::waitpid(child, &status, 0), child);
    EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0)
        << "the test failed in its own process (its output is above)";
    return;
  }
  ASSERT_FALSE(image_file_module_loaded());
  ASSERT_FALSE(module_mapped());
  const fs::path dir = fresh_dir();
  const Image image = test_pattern();
  write_image(image, dir / "a.png", OutputTransfer::srgb);
  write_image(EncodedImage(image, dir / "b.PNG", OutputTransfer::linear));
  EXPECT_FALSE(image_file_module_loaded());
  EXPECT_FALSE(module_mapped());
  EXPECT_FALSE(image_file_needs_module("x.png"));
  EXPECT_TRUE(image_file_needs_module("x.exr"));
  EXPECT_TRUE(image_file_needs_module("x.jpg"));
  EXPECT_TRUE(image_file_needs_module("x.tif"));
  // The check can see the module: an EXR opens it.
  write_image(image, dir / "c.exr", OutputTransfer::linear);
  EXPECT_TRUE(image_file_module_loaded());
  EXPECT_TRUE(module_mapped());
}

TEST(PngFileTest, AnUnwritablePathIsNamedInTheError) {
  const fs::path dir = fresh_dir();
  const Image image(4, 4);
  const auto error_of = [&](const fs::path& path) -> std::string {
    try {
      write_image(image, path, OutputTransfer::srgb);
    } catch (const std::runtime_error& e) {
      return e.what();
    }
    return "(no error)";
  };
  EXPECT_EQ(error_of("/nonexistent-dir/a.png"),
            "cannot write /nonexistent-dir/a.png: No such file or directory");
  std::ofstream(dir / "file") << "not a directory";
  EXPECT_EQ(error_of(dir / "file" / "a.png"),
            "cannot write " + (dir / "file" / "a.png").string() + ": Not a directory");
  EXPECT_EQ(names_in(dir), std::vector<std::string>{"file"});
}

TEST(PngFileTest, AFailedWriteKeepsTheOldFileAndLeavesNoTemporary) {
  // Writes fail past a file size limit (EFBIG, with SIGXFSZ ignored): a big image fails in
  // the middle, inside libpng, and a tiny one only when fclose() flushes it.
  const fs::path dir = fresh_dir();
  Image big(512, 512);
  std::uint32_t state = 12345;
  for (float& v : big.pixels()) {  // noise, which does not compress below the limit
    state = state * 1664525u + 1013904223u;
    v = static_cast<float>(state >> 8) / static_cast<float>(1u << 24);
  }
  const Image tiny(2, 2);
  write_image(tiny, dir / "a.png", OutputTransfer::srgb);
  const std::string old_bytes = file_bytes(dir / "a.png");

  rlimit old_limit{};
  ASSERT_EQ(::getrlimit(RLIMIT_FSIZE, &old_limit), 0);
  const auto old_handler = std::signal(SIGXFSZ, SIG_IGN);
  std::string big_error = "(no error)", tiny_error = "(no error)";
  const auto write_under = [&](rlim_t bytes, const Image& image, std::string& error) {
    rlimit limit = old_limit;
    limit.rlim_cur = bytes;
    ::setrlimit(RLIMIT_FSIZE, &limit);
    try {
      write_image(image, dir / "a.png", OutputTransfer::srgb);
    } catch (const std::runtime_error& e) {
      error = e.what();
    }
    ::setrlimit(RLIMIT_FSIZE, &old_limit);
  };
  write_under(64 * 1024, big, big_error);
  write_under(0, tiny, tiny_error);
  std::signal(SIGXFSZ, old_handler);

  const std::string expected = "cannot write " + (dir / "a.png").string() + ": File too large";
  EXPECT_EQ(big_error, expected);
  EXPECT_EQ(tiny_error, expected);
  EXPECT_EQ(file_bytes(dir / "a.png"), old_bytes);
  EXPECT_EQ(names_in(dir), std::vector<std::string>{"a.png"});
}

TEST(PngFileTest, LibpngsOwnErrorsBecomeExceptions) {
  const fs::path dir = fresh_dir();
  const std::uint8_t codes[3] = {1, 2, 3};
  try {
    write_png(dir / "a.png", PngPixels{0, 1, codes, true});  // libpng refuses a zero width
    ADD_FAILURE() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()).rfind("libpng: ", 0), 0u) << e.what();
  }
  try {
    write_png(dir / "b.png", PngPixels{1, 1, codes, true}, PngCompression{42});  // zlib refuses
    ADD_FAILURE() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()).rfind("libpng: ", 0), 0u) << e.what();
  }
}

}  // namespace
}  // namespace tessera
