// Writes the glTF example: a carousel of gems on a disc inside a ribbon, as a .gltf whose
// buffer is embedded as base64, with a node hierarchy (the carousel turns its children),
// a fan (the disc), a strip (the ribbon), 8-bit indices (the gems) and the materials the
// metallic-roughness mapping covers (gold, glass through KHR_materials_transmission and
// KHR_materials_ior, a lamp through KHR_materials_emissive_strength); then a scene that
// names it. Usage: tessera_make_gltf_scene OUT_DIR (writes OUT_DIR/gltf_carousel.json and
// OUT_DIR/models/carousel.gltf).
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "examples/gltf_bytes.hpp"

namespace {

using nlohmann::json;

// The buffer and its views and accessors, filled one array at a time.
struct Builder {
  std::string bytes;
  json views = json::array();
  json accessors = json::array();

  int add(const std::string& data, int component_type, int count, const char* type) {
    while (bytes.size() % 4) bytes += '\0';
    views.push_back({{"buffer", 0}, {"byteOffset", bytes.size()}, {"byteLength", data.size()}});
    bytes += data;
    accessors.push_back({{"bufferView", views.size() - 1},
                         {"componentType", component_type},
                         {"count", count},
                         {"type", type}});
    return static_cast<int>(accessors.size() - 1);
  }

  int points(const std::vector<float>& xyz) {
    std::string data(reinterpret_cast<const char*>(xyz.data()), xyz.size() * sizeof(float));
    const int index = add(data, 5126, static_cast<int>(xyz.size() / 3), "VEC3");
    json min = {1e30, 1e30, 1e30}, max = {-1e30, -1e30, -1e30};
    for (std::size_t i = 0; i < xyz.size(); ++i) {
      min[i % 3] = std::min(min[i % 3].get<double>(), double(xyz[i]));
      max[i % 3] = std::max(max[i % 3].get<double>(), double(xyz[i]));
    }
    accessors[index]["min"] = min;
    accessors[index]["max"] = max;
    return index;
  }
};

json material(const char* name, std::vector<double> base, double metallic, double roughness) {
  return {
      {"name", name},
      {"pbrMetallicRoughness",
       {{"baseColorFactor", base}, {"metallicFactor", metallic}, {"roughnessFactor", roughness}}}};
}

json model() {
  Builder b;
  // An octahedron, counter-clockwise seen from outside, with 8-bit indices.
  const int gem_positions = b.points({0, 1, 0, 1, 0, 0, 0, 0, 1, -1, 0, 0, 0, 0, -1, 0, -1, 0});
  const std::string gem_indices = {0, 2, 1, 0, 3, 2, 0, 4, 3, 0, 1, 4,
                                   5, 1, 2, 5, 2, 3, 5, 3, 4, 5, 4, 1};
  const int gem_triangles = b.add(gem_indices, 5121, 24, "SCALAR");
  // The disc as a fan around its centre, and the ribbon as a strip, both without indices.
  constexpr int segments = 48;
  std::vector<float> disc = {0, 0, 0}, ribbon;
  for (int k = 0; k <= segments; ++k) {
    const double a = 2 * std::numbers::pi * k / segments;
    // Clockwise seen from above, so that the fan's triangles face up.
    disc.insert(disc.end(), {float(3 * std::cos(-a)), 0, float(3 * std::sin(-a))});
    for (const float y : {0.f, 0.35f})
      ribbon.insert(ribbon.end(), {float(3 * std::cos(a)), y, float(3 * std::sin(a))});
  }
  const int disc_positions = b.points(disc);
  const int ribbon_positions = b.points(ribbon);

  json nodes = json::array();
  json children = json::array();
  nodes.push_back({{"name", "carousel"},
                   {"rotation", {0, std::sin(0.15), 0, std::cos(0.15)}},
                   {"children", children}});
  const auto child = [&](json node) {
    nodes.push_back(std::move(node));
    nodes[0]["children"].push_back(nodes.size() - 1);
  };
  child({{"name", "disc"}, {"mesh", 1}});
  child({{"name", "ribbon"}, {"mesh", 2}});
  for (int k = 0; k < 8; ++k) {
    const double a = 2 * std::numbers::pi * k / 8;
    child({{"name", "gem " + std::to_string(k)},
           {"mesh", k % 2 == 0 ? 0 : 3},
           {"translation", {2.1 * std::cos(a), 0.55, 2.1 * std::sin(a)}},
           {"rotation", {0, std::sin(a / 2), 0, std::cos(a / 2)}},
           {"scale", {0.4, 0.55, 0.4}}});
  }
  child({{"name", "lamp"},
         {"mesh", 4},
         {"matrix", {0.5, 0, 0, 0, 0, 0.5, 0, 0, 0, 0, 0.5, 0, 0, 1.3, 0, 1}}});

  const auto gem = [&](int material) {
    return json{{"primitives",
                 {{{"attributes", {{"POSITION", gem_positions}}},
                   {"indices", gem_triangles},
                   {"material", material}}}}};
  };
  json glass = material("glass", {0.92, 0.96, 1.0, 1}, 0, 0);
  glass["extensions"] = {{"KHR_materials_transmission", {{"transmissionFactor", 1.0}}},
                         {"KHR_materials_ior", {{"ior", 1.5}}}};
  json lamp = material("lamp", {0.2, 0.2, 0.2, 1}, 0, 0.8);
  lamp["emissiveFactor"] = {1.0, 0.6, 0.3};
  lamp["extensions"] = {{"KHR_materials_emissive_strength", {{"emissiveStrength", 2.5}}}};
  while (b.bytes.size() % 4) b.bytes += '\0';
  return {{"asset", {{"version", "2.0"}, {"generator", "tessera examples/make_gltf_scene.cpp"}}},
          {"extensionsUsed",
           {"KHR_materials_transmission", "KHR_materials_ior", "KHR_materials_emissive_strength"}},
          {"scene", 0},
          {"scenes", {{{"nodes", {0}}}}},
          {"nodes", nodes},
          {"meshes",
           {gem(0),
            {{"primitives",
              {{{"attributes", {{"POSITION", disc_positions}}}, {"mode", 6}, {"material", 2}}}}},
            {{"primitives",
              {{{"attributes", {{"POSITION", ribbon_positions}}}, {"mode", 5}, {"material", 3}}}}},
            gem(1),
            gem(4)}},
          {"materials",
           {material("gold", {1.0, 0.78, 0.34, 1}, 1, 0.15), glass,
            material("floor", {0.3, 0.36, 0.45, 1}, 0, 0.6),
            material("band", {0.65, 0.1, 0.08, 1}, 0, 0.35), lamp}},
          {"accessors", b.accessors},
          {"bufferViews", b.views},
          {"buffers",
           {{{"byteLength", b.bytes.size()},
             {"uri",
              "data:application/octet-stream;base64," + tessera::gltf_bytes::base64(b.bytes)}}}}};
}

json scene() {
  return json::parse(R"({
    "version": 1,
    "image": {"width": 640, "height": 400},
    "camera": {"eye": [0, 3.6, 7.2], "look_at": [0, 0.5, 0], "fov_y": 42},
    "render": {"samples_per_pixel": 4, "max_depth": 8},
    "background": [0.04, 0.05, 0.08],
    "ambient_light": 0.12,
    "lights": [
      {"type": "point", "position": [3, 6, 5], "intensity": [0.9, 0.85, 0.8]},
      {"type": "spot", "position": [-4, 5, 2], "direction": [0.7, -1, -0.3],
       "intensity": [0.4, 0.5, 0.8], "cutoff": 35}
    ],
    "objects": [
      {"type": "plane", "point": [0, -0.01, 0], "normal": [0, 1, 0],
       "material": {"diffuse": [0.5, 0.5, 0.52], "checker": {"size": 1, "diffuse": [0.2, 0.2, 0.24]}}},
      {"type": "mesh", "file": "models/carousel.gltf"}
    ]
  })");
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: tessera_make_gltf_scene OUT_DIR\n");
    return 2;
  }
  const std::filesystem::path out = argv[1];
  std::filesystem::create_directories(out / "models");
  std::ofstream(out / "models" / "carousel.gltf") << model().dump(1) << '\n';
  std::ofstream(out / "gltf_carousel.json") << scene().dump(2) << '\n';
  return 0;
}
