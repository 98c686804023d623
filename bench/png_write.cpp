// The cost of writing a render as a PNG with each zlib level and row filter that
// write_png() can use: one render of the scene, then every setting written in turn to a
// temporary file, in a rotated order each round so that none always goes first. Prints the
// median time of each and the file's size (docs/performance.md, "PNG with libpng").
//
// Usage: tessera_png_write SCENE.json WIDTH HEIGHT ROUNDS
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "bench/median.hpp"
#include "common/image/image_io.hpp"
#include "common/image/png_file.hpp"
#include "common/scene/scene_parser.hpp"
#include "tracer/local_render.hpp"

namespace {

using tessera::PngCompression;

const char* filter_name(PngCompression::Filter filter) {
  switch (filter) {
    case PngCompression::Filter::none:
      return "none";
    case PngCompression::Filter::sub:
      return "sub";
    case PngCompression::Filter::adaptive:
      return "adaptive";
  }
  return "?";
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 5) {
    std::fprintf(stderr, "usage: %s SCENE.json WIDTH HEIGHT ROUNDS\n", argv[0]);
    return 2;
  }
  try {
    nlohmann::json document = tessera::read_json_file(argv[1]);
    document["image"]["width"] = std::stoi(argv[2]);
    document["image"]["height"] = std::stoi(argv[3]);
    const int rounds = std::stoi(argv[4]);
    const tessera::Scene scene = tessera::parse_scene(document);
    const tessera::Renderer renderer(scene);
    const tessera::Image image = tessera::render_local(renderer, 0).image;
    const std::filesystem::path path = std::filesystem::temp_directory_path() /
                                       ("tessera-png-write-" + std::to_string(::getpid()) + ".png");
    const tessera::EncodedImage encoded(image, path, scene.render.output_transfer);
    const tessera::PngPixels pixels{image.width(), image.height(),
                                    static_cast<const std::uint8_t*>(encoded.content().pixels),
                                    encoded.content().srgb};

    std::vector<PngCompression> settings;
    for (const auto filter : {PngCompression::Filter::none, PngCompression::Filter::sub,
                              PngCompression::Filter::adaptive})
      for (const int level : {1, 2, 3, 4, 6}) settings.push_back({level, filter});
    std::vector<std::vector<double>> seconds(settings.size());
    std::vector<std::uintmax_t> bytes(settings.size());
    for (int round = 0; round < rounds; ++round)
      for (std::size_t k = 0; k < settings.size(); ++k) {
        const std::size_t i = (k + round) % settings.size();
        const auto start = std::chrono::steady_clock::now();
        tessera::write_png(path, pixels, settings[i]);
        seconds[i].push_back(
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
        bytes[i] = std::filesystem::file_size(path);
      }
    std::filesystem::remove(path);

    std::printf("| zlib level | filter | ms (median of %d) | bytes |\n|---:|---|---:|---:|\n",
                rounds);
    for (std::size_t i = 0; i < settings.size(); ++i)
      std::printf("| %d | %s | %.1f | %ju |\n", settings[i].zlib_level,
                  filter_name(settings[i].filter), tessera::bench::median(seconds[i]) * 1e3,
                  bytes[i]);
    return 0;
  } catch (const std::exception& error) {
    std::fprintf(stderr, "error: %s\n", error.what());
    return 1;
  }
}
