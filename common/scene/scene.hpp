// The validated scene: what the JSON scene format (docs/scene-format.md) means once
// every rule has been checked. Everything downstream trusts these values.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include <glm/glm.hpp>

#include "common/scene/animation.hpp"

namespace tessera {

using Vec3 = glm::dvec3;
using Color = glm::dvec3;  // linear RGB
using Mat4 = glm::dmat4;   // column-major, as GLM stores it

struct Checker {
  double size = 1.0;  // cell edge in world units, > 0
  Color ambient{0.0};
  Color diffuse{0.0};
};

// How a texture repeats beyond [0, 1] in u and v (docs/scene-format.md, "Textures").
enum class TextureWrap : std::uint8_t { repeat, clamp, mirror };
inline constexpr std::string_view texture_wrap_names[] = {"repeat", "clamp", "mirror"};

// An image a material reads colours from: a file on this machine, or bytes a model file
// held (a glTF's embedded image).
struct TextureImage {
  std::string name;  // as the scene or the model names it, for messages
  std::string path;  // the file; empty when `bytes` holds the image
  std::shared_ptr<const std::string> bytes;
  std::string extension;  // of `bytes`' format, such as ".png", which names the decoder
};

// A colour that varies over a surface: `scale` times the texture's linear RGB at the hit's
// uv coordinates.
struct TexturedColor {
  TextureImage image;
  Color scale{1.0};
  TextureWrap wrap = TextureWrap::repeat;
};

// The terms of a material that a texture may colour, as indices of Material::textures.
enum class TexturedTerm : std::uint8_t { emission, ambient, diffuse, specular };
inline constexpr std::size_t kTexturedTerms = 4;
inline constexpr std::string_view textured_term_names[] = {"emission", "ambient", "diffuse",
                                                           "specular"};

struct Material {
  Color emission{0.0};      // I_E
  Color ambient{0.2};       // K_A
  Color diffuse{0.8};       // K_D
  Color specular{0.0};      // K_S
  double shininess = 0.0;   // n
  Color reflection{0.0};    // K_R (the parser fills in `specular` when absent)
  Color transmission{0.0};  // K_T
  double ior = 1.0;
  std::optional<Checker> checker;
  // A term with a texture takes its colour from it, and the colour above is unused.
  std::array<std::optional<TexturedColor>, kTexturedTerms> textures;

  const std::optional<TexturedColor>& texture(TexturedTerm term) const {
    return textures[static_cast<std::size_t>(term)];
  }
  std::optional<TexturedColor>& texture(TexturedTerm term) {
    return textures[static_cast<std::size_t>(term)];
  }
  bool textured() const {
    for (const auto& t : textures)
      if (t) return true;
    return false;
  }
};

// Whether a material lets light through at all, which decides how its shapes are
// registered with Embree (tracer/scene_geometry_build.cpp).
inline bool transmits(const Material& material) {
  const Color& t = material.transmission;
  return t.r != 0.0 || t.g != 0.0 || t.b != 0.0;
}

struct Attenuation {
  double constant = 1.0;   // kc
  double linear = 0.0;     // kl
  double quadratic = 0.0;  // kq
};

struct PointLight {
  Vec3 position{0.0};
  Color intensity{1.0};
  Attenuation attenuation;
};

struct DirectionalLight {
  Vec3 direction{0.0, -1.0, 0.0};  // unit; the direction the light travels
  Color intensity{1.0};
};

struct SpotLight {
  Vec3 position{0.0};
  Vec3 direction{0.0, -1.0, 0.0};  // unit; the cone's axis, pointing away from the light
  Color intensity{1.0};
  Attenuation attenuation;
  double cutoff_degrees = 90.0;  // half-angle of the cone, in (0, 90]
  double exponent = 1.0;         // >= 0
};

using Light = std::variant<PointLight, DirectionalLight, SpotLight>;

struct Sphere {
  Vec3 center{0.0};
  double radius = 1.0;
};

struct Plane {
  Vec3 point{0.0};
  Vec3 normal{0.0, 1.0, 0.0};  // unit
  glm::dvec2 uv_scale{1.0};    // the lengths along the plane of one unit of u and of v, > 0
};

struct Box {
  Vec3 min{-1.0};
  Vec3 max{1.0};
};

// Texture coordinates: u to the right, v up the image (docs/scene-format.md).
using Uv = glm::vec2;

struct Triangle {
  std::array<Vec3, 3> vertices;
  std::optional<std::array<Vec3, 3>> normals;  // unit, per vertex
  std::optional<std::array<Uv, 3>> uvs;        // per vertex; (0,0), (1,0), (0,1) when absent
};

struct Mesh {
  std::vector<Vec3> positions;
  std::vector<std::array<std::uint32_t, 3>> triangles;  // counter-clockwise seen from outside
  std::vector<Vec3> normals;                            // empty, or one unit normal per position
  std::vector<Uv> uvs;  // empty (each triangle as a Triangle without uvs), or one per position
  bool thin = false;
};

// A solid closed cylinder. Its axis is object-space y (the convention of Princeton's COS 426
// ray tracer), through `center`: it spans center.y - height/2 to center.y + height/2 and is
// closed there by two flat caps.
struct Cylinder {
  Vec3 center{0.0};
  double radius = 1.0;  // > 0
  double height = 1.0;  // > 0
};

// A solid closed cone on the same axis: its base, a capped disc of `radius`, at
// center.y - height/2, its apex at center.y + height/2.
struct Cone {
  Vec3 center{0.0};
  double radius = 1.0;  // > 0, of the base
  double height = 1.0;  // > 0
};

using Shape = std::variant<Sphere, Plane, Box, Triangle, Mesh, Cylinder, Cone>;

struct Object {
  Shape shape;
  std::uint32_t material = 0;  // index into Scene::materials
  Mat4 transform{1.0};         // object to world; identity when the scene gives none
};

// Solid objects refract by Snell's law; thin ones let transmitted rays pass unbent.
inline bool is_solid(const Object& object) {
  if (std::holds_alternative<Sphere>(object.shape) || std::holds_alternative<Box>(object.shape) ||
      std::holds_alternative<Cylinder>(object.shape) || std::holds_alternative<Cone>(object.shape))
    return true;
  if (const auto* mesh = std::get_if<Mesh>(&object.shape)) return !mesh->thin;
  return false;
}

struct Camera {
  Vec3 eye{0.0};
  Vec3 look_at{0.0, 0.0, -1.0};
  Vec3 up{0.0, 1.0, 0.0};
  double fov_y_degrees = 45.0;
};

enum class OutputTransfer { srgb, linear };

struct RenderSettings {
  int samples_per_pixel = 1;
  int max_depth = 5;
  int tile_size = 32;
  OutputTransfer output_transfer = OutputTransfer::srgb;
};

struct Scene {
  int width = 0;
  int height = 0;
  Camera camera;
  RenderSettings render;
  Color background{0.0};
  Color ambient_light{0.1};
  std::vector<Material> materials;  // index 0 is the default material
  std::vector<Light> lights;
  std::vector<Object> objects;
  // The range and the tracks of an animated scene (the one frame 0 of a still one), and the
  // frame whose values the rest holds.
  Animation animation;
  int frame = 0;
};

// What one scene may cost. One struct so that the server can expose each as a flag.
struct Limits {
  int max_width = 16384;
  int max_height = 16384;
  std::uint64_t max_pixels = 16384ull * 16384;  // width x height
  int max_samples_per_pixel = 4096;
  int max_depth = 64;
  int max_tile_size = 4096;
  std::size_t max_objects = 100000;
  std::size_t max_lights = 1024;
  std::size_t max_materials = 10000;
  std::size_t max_triangles = 20000000;  // summed over meshes, boxes and triangles
  std::size_t max_frames = 10000;        // in an animation's range
  // Keyframe tracks in all; a submitted scene is checked at every frame of each.
  std::size_t max_tracks = 256;

  // No limit at all: for a scene already validated against the coordinator's limits.
  static Limits none();
};

}  // namespace tessera
