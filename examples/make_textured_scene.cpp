// Writes the textured example: a globe (a .glb whose base colour texture, a PNG painted
// here, is embedded in its binary chunk, read through TEXCOORD_0) on a tiled floor (an
// analytic plane with a PNG texture and uv_scale), beside a wooden crate (a box, one
// square of the texture per face) and a mirror ball that shows them filtered through its
// reflection. Every image is computed here, from sums of waves and hashed noise.
// Usage: tessera_make_textured_scene OUT_DIR (writes OUT_DIR/textured_globe.json,
// OUT_DIR/models/globe.glb and OUT_DIR/textures/{tiles,crate}.png).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <numbers>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/image/png_file.hpp"
#include "examples/gltf_bytes.hpp"

namespace {

using nlohmann::json;
using tessera::gltf_bytes::append;
namespace fs = std::filesystem;

constexpr double kPi = std::numbers::pi;

struct Rgb {
  double r, g, b;
};

// A value in [0, 1) from integer coordinates (the SplitMix64 finaliser).
double hash(std::int64_t x, std::int64_t y, std::uint64_t seed) {
  std::uint64_t v = static_cast<std::uint64_t>(x) * 0x9e3779b97f4a7c15ull ^
                    static_cast<std::uint64_t>(y) * 0xc2b2ae3d27d4eb4full ^ seed;
  v ^= v >> 30;
  v *= 0xbf58476d1ce4e5b9ull;
  v ^= v >> 27;
  v *= 0x94d049bb133111ebull;
  v ^= v >> 31;
  return static_cast<double>(v >> 11) * 0x1p-53;
}

// Smoothly interpolated lattice noise in [0, 1), periodic in x with period `period` cells.
double value_noise(double x, double y, int period, std::uint64_t seed) {
  const double fx = std::floor(x), fy = std::floor(y);
  const double tx = x - fx, ty = y - fy;
  const auto at = [&](double cx, double cy) {
    const auto ix = static_cast<std::int64_t>(cx);
    return hash(((ix % period) + period) % period, static_cast<std::int64_t>(cy), seed);
  };
  const double sx = tx * tx * (3 - 2 * tx), sy = ty * ty * (3 - 2 * ty);
  const double top = at(fx, fy) + sx * (at(fx + 1, fy) - at(fx, fy));
  const double bottom = at(fx, fy + 1) + sx * (at(fx + 1, fy + 1) - at(fx, fy + 1));
  return top + sy * (bottom - top);
}

double fbm(double x, double y, int period, std::uint64_t seed) {
  double sum = 0, amplitude = 0.5;
  for (int octave = 0; octave < 5; ++octave) {
    sum += amplitude * value_noise(x, y, period, seed + octave);
    x *= 2;
    y *= 2;
    period *= 2;
    amplitude *= 0.5;
  }
  return sum;
}

// An image painted by `paint(u, v)` (u right, v down, both 0 to 1), as sRGB codes.
std::vector<std::uint8_t> paint(int width, int height,
                                const std::function<Rgb(double, double)>& f) {
  std::vector<std::uint8_t> codes;
  codes.reserve(static_cast<std::size_t>(width) * height * 3);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const Rgb c = f((x + 0.5) / width, (y + 0.5) / height);
      for (const double v : {c.r, c.g, c.b})
        codes.push_back(static_cast<std::uint8_t>(std::clamp(v, 0.0, 1.0) * 255 + 0.5));
    }
  return codes;
}

void write_png(const fs::path& path, int width, int height,
               const std::vector<std::uint8_t>& codes) {
  tessera::write_png(path, {width, height, codes.data(), true});
}

Rgb mix(const Rgb& a, const Rgb& b, double t) {
  return {a.r + (b.r - a.r) * t, a.g + (b.g - a.g) * t, a.b + (b.b - a.b) * t};
}

// Terracotta tiles, 4 x 4 to the image, each its own shade, in pale grout.
Rgb tiles(double u, double v) {
  const double x = u * 4, y = v * 4;
  const double gx = x - std::floor(x), gy = y - std::floor(y);
  const double edge = std::min({gx, 1 - gx, gy, 1 - gy});
  const double shade = hash(static_cast<std::int64_t>(x), static_cast<std::int64_t>(y), 7);
  const double speckle = fbm(u * 32, v * 32, 32, 11);
  Rgb tile = mix({0.62, 0.30, 0.18}, {0.78, 0.45, 0.26}, shade);
  tile = mix(tile, {0.45, 0.22, 0.14}, 0.5 * speckle);
  const double grout = std::clamp((0.035 - edge) / 0.012, 0.0, 1.0);
  return mix(tile, {0.86, 0.83, 0.76}, grout);
}

// Planks with grain, in a darker frame.
Rgb crate(double u, double v) {
  const double plank = std::floor(v * 5);
  const double grain =
      0.5 + 0.5 * std::sin(60 * u + 9 * fbm(u * 4, v * 20, 4, 3 + plank) + plank * 1.7);
  Rgb wood = mix({0.55, 0.36, 0.19}, {0.70, 0.50, 0.29}, grain);
  wood = mix(wood, {0.42, 0.26, 0.13}, 0.35 * hash(static_cast<std::int64_t>(plank), 1, 5));
  const double gap = v * 5 - plank;
  if (gap < 0.04 || gap > 0.96) wood = mix(wood, {0.2, 0.12, 0.06}, 0.8);
  const double frame = std::min({u, 1 - u, v, 1 - v});
  if (frame < 0.09) wood = mix(wood, {0.33, 0.2, 0.1}, 0.85);
  return wood;
}

// An imagined planet: oceans, continents from noise that wraps around in longitude, ice at
// the poles. u is longitude, v runs from the north pole (0) to the south (1).
Rgb planet(double u, double v) {
  const double latitude = (0.5 - v) * kPi;
  const double land = fbm(u * 8, v * 4, 8, 21) + 0.12 * std::cos(3 * latitude);
  Rgb c = mix({0.02, 0.10, 0.30}, {0.05, 0.28, 0.55}, std::clamp((land - 0.25) * 3, 0.0, 1.0));
  if (land > 0.52) {
    const double height = std::clamp((land - 0.52) * 5, 0.0, 1.0);
    c = mix({0.16, 0.42, 0.12}, {0.58, 0.46, 0.26}, height);
  }
  const double ice =
      std::clamp((std::fabs(latitude) - 1.18 + 0.1 * fbm(u * 16, v * 8, 16, 5)) * 8, 0.0, 1.0);
  return mix(c, {0.93, 0.95, 0.97}, ice);
}

// A UV sphere of radius 1 as a .glb with positions, normals, TEXCOORD_0 and 16-bit indices,
// and the planet's PNG in the binary chunk.
std::string globe(const std::string& png) {
  constexpr int rings = 32, segments = 64;
  std::string positions, normals, uvs, indices;
  for (int i = 0; i <= rings; ++i)
    for (int j = 0; j <= segments; ++j) {
      const double lambda = kPi * (static_cast<double>(i) / rings - 0.5);
      const double phi = 2 * kPi * (static_cast<double>(j) / segments - 0.5);
      const float p[3] = {static_cast<float>(std::cos(lambda) * std::sin(phi)),
                          static_cast<float>(std::sin(lambda)),
                          static_cast<float>(std::cos(lambda) * std::cos(phi))};
      for (const float c : p) {
        append(positions, c);
        append(normals, c);
      }
      append(uvs, static_cast<float>(j) / segments);
      append(uvs, 1.0f - static_cast<float>(i) / rings);  // glTF's v runs down the image
    }
  int count = 0;
  for (int i = 0; i < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      const auto at = [](int ring, int segment) {
        return static_cast<std::uint16_t>(ring * (segments + 1) + segment);
      };
      for (const std::uint16_t k :
           {at(i, j), at(i, j + 1), at(i + 1, j + 1), at(i, j), at(i + 1, j + 1), at(i + 1, j)})
        append(indices, k);
      count += 6;
    }
  std::string bin;
  json views = json::array();
  const auto view = [&](const std::string& data) {
    while (bin.size() % 4) bin += '\0';
    views.push_back({{"buffer", 0}, {"byteOffset", bin.size()}, {"byteLength", data.size()}});
    bin += data;
    return views.size() - 1;
  };
  const int vertices = (rings + 1) * (segments + 1);
  json accessors = json::array({
      {{"bufferView", view(positions)},
       {"componentType", 5126},
       {"count", vertices},
       {"type", "VEC3"},
       {"min", {-1, -1, -1}},
       {"max", {1, 1, 1}}},
      {{"bufferView", view(normals)},
       {"componentType", 5126},
       {"count", vertices},
       {"type", "VEC3"}},
      {{"bufferView", view(uvs)}, {"componentType", 5126}, {"count", vertices}, {"type", "VEC2"}},
      {{"bufferView", view(indices)},
       {"componentType", 5123},
       {"count", count},
       {"type", "SCALAR"}},
  });
  const auto image_view = view(png);
  while (bin.size() % 4) bin += '\0';
  const json document = {
      {"asset", {{"version", "2.0"}, {"generator", "tessera examples/make_textured_scene.cpp"}}},
      {"scene", 0},
      {"scenes", {{{"nodes", {0}}}}},
      {"nodes", {{{"name", "globe"}, {"mesh", 0}, {"rotation", {0.0, 0.2588, 0.0, 0.9659}}}}},
      {"meshes",
       {{{"name", "globe"},
         {"primitives",
          {{{"attributes", {{"POSITION", 0}, {"NORMAL", 1}, {"TEXCOORD_0", 2}}},
            {"indices", 3},
            {"material", 0}}}}}}},
      {"materials",
       {{{"name", "planet"},
         {"pbrMetallicRoughness",
          {{"baseColorTexture", {{"index", 0}}},
           {"metallicFactor", 0},
           {"roughnessFactor", 0.55}}}}}},
      {"textures", {{{"source", 0}, {"sampler", 0}}}},
      {"samplers", {{{"wrapS", 10497}, {"wrapT", 33071}}}},
      {"images", {{{"bufferView", image_view}, {"mimeType", "image/png"}}}},
      {"accessors", accessors},
      {"bufferViews", views},
      {"buffers", {{{"byteLength", bin.size()}}}}};
  return tessera::gltf_bytes::glb(document.dump(), bin);
}

json scene() {
  return json::parse(R"({
    "version": 1,
    "image": {"width": 640, "height": 400},
    "camera": {"eye": [0.4, 2.4, 7.2], "look_at": [0, 0.9, 0], "fov_y": 40},
    "render": {"samples_per_pixel": 4, "max_depth": 6},
    "background": [0.55, 0.65, 0.8],
    "ambient_light": 0.25,
    "lights": [
      {"type": "point", "position": [4, 6, 5], "intensity": 0.85},
      {"type": "directional", "direction": [0.4, -1, -0.6], "intensity": [0.3, 0.3, 0.35]}
    ],
    "objects": [
      {"type": "plane", "point": [0, 0, 0], "normal": [0, 1, 0], "uv_scale": 2.5,
       "material": {"ambient": {"texture": "textures/tiles.png", "scale": 0.6},
                    "diffuse": {"texture": "textures/tiles.png"},
                    "specular": 0.15, "shininess": 60, "reflection": 0.04}},
      {"type": "mesh", "file": "models/globe.glb", "normals": "file",
       "transform": [{"translate": [0, 1.05, 0]}]},
      {"type": "box", "min": [-0.6, 0, -0.6], "max": [0.6, 1.2, 0.6],
       "transform": [{"rotate": {"axis": [0, 1, 0], "degrees": 30}}, {"translate": [-2.4, 0, -0.8]}],
       "material": {"ambient": {"texture": "textures/crate.png", "scale": 0.7},
                    "diffuse": {"texture": "textures/crate.png"}, "specular": 0.05,
                    "shininess": 10}},
      {"type": "sphere", "center": [2.3, 0.75, -0.6], "radius": 0.75,
       "material": {"ambient": 0.02, "diffuse": 0.03, "specular": 0.6, "shininess": 300,
                    "reflection": 0.85}}
    ]
  })");
}

std::string read_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: tessera_make_textured_scene OUT_DIR\n");
    return 2;
  }
  const fs::path out = argv[1];
  fs::create_directories(out / "models");
  fs::create_directories(out / "textures");
  write_png(out / "textures" / "tiles.png", 256, 256, paint(256, 256, tiles));
  write_png(out / "textures" / "crate.png", 256, 256, paint(256, 256, crate));
  const fs::path planet_png = out / "models" / "planet.png.tmp";
  write_png(planet_png, 1024, 512, paint(1024, 512, planet));
  const std::string glb = globe(read_bytes(planet_png));
  fs::remove(planet_png);
  std::ofstream(out / "models" / "globe.glb", std::ios::binary) << glb;
  std::ofstream(out / "textured_globe.json") << scene().dump(2) << '\n';
  return 0;
}
