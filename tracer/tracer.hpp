// The Whitted illumination model of the course material, evaluated recursively:
//   I = I_E + K_A·I_A + Σ_L (K_D·(N·L) + K_S·(V·R)^n)·S_L·I_L + K_R·I_R + K_T·I_T
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <vector>

#include "common/image/image_file_module.hpp"
#include "common/scene/scene.hpp"
#include "tracer/ray.hpp"
#include "tracer/scene_geometry.hpp"
#include "tracer/scene_textures.hpp"

namespace tessera {

struct RayCounts {
  std::uint64_t primary = 0;
  std::uint64_t secondary = 0;  // reflection and refraction
  std::uint64_t shadow = 0;

  std::uint64_t total() const { return primary + secondary + shadow; }
  RayCounts& operator+=(const RayCounts& other) {
    primary += other.primary;
    secondary += other.secondary;
    shadow += other.shadow;
    return *this;
  }
};

// Exported from the tracer's library member by member, as SceneGeometry is.
class Tracer {
 public:
  // All must outlive the tracer; `textures` may be null for a scene without any.
  TESSERA_TRACER_API Tracer(const Scene& scene, const SceneGeometry& geometry,
                            const SceneTextures* textures = nullptr);

  // The radiance arriving along `ray`; `depth` is the number of bounces before it, and
  // `travelled` the length of the path from the camera to the ray's origin, which sizes the
  // pixel's cone (and so the filter of the textures it meets).
  TESSERA_TRACER_API Color trace(const Ray& ray, int depth, RayCounts& counts,
                                 double travelled = 0.0) const;
  // The radiance along each active ray of a packet, `depth` bounces after the camera. The
  // packet's hits, the shadow rays of its hits towards each light, and its reflected and
  // transmitted rays go to Embree sixteen at a time; the arithmetic of each lane is
  // trace()'s own, in the same order, so a pixel gets the same bits either way. Only the
  // lanes in `keep` are shaded in full and counted: the others are traced only so that the
  // packets Embree sees never depend on which of their lanes a tile holds.
  // `travelled`: each lane's, as trace() takes it; null for rays from the camera.
  TESSERA_TRACER_API void trace_packet(const RayPacket& packet, int depth,
                                       const bool (&keep)[kPacketSize], Color (&out)[kPacketSize],
                                       RayCounts& counts, const double* travelled = nullptr) const;

 private:
  // No default values: packets hold sixteen per light, and every member is always set.
  struct LightSample {
    Vec3 to_light;    // unit, from the surface point towards the light; 0 when unlit
    double distance;  // to the light; infinite for directional lights
    Vec3 position;    // of a point or spot light
    Color intensity;  // I_L at the point, before shadowing
  };
  // A light with everything that does not depend on the shaded point worked out once.
  struct PreparedLight {
    enum class Kind : std::uint8_t { point, directional, spot } kind;
    Vec3 position{0.0};
    Vec3 direction{0.0};  // unit: where a directional or spot light shines
    Color intensity{0.0};
    Attenuation attenuation;
    double cos_cutoff = 0.0;
    double exponent = 1.0;
    // No linear or quadratic term: 1 / attenuation is the same at every distance (for
    // every finite one, bit for bit), so it is divided out once here.
    bool constant_falloff = false;
    double inverse_constant = 1.0;
  };

  // A surface point part way through being shaded.
  // Left uninitialised until begin_shading() fills it in: packets hold sixteen.
  struct Shading {
    const Material* material;
    Vec3 d;  // the ray's direction
    Vec3 n;  // the shading normal, turned to face the ray
    bool front;
    Color diffuse;
    Color specular;
    Color result;      // I_E + K_A·I_A, then each light's term as it is added
    double travelled;  // from the camera to the hit, along the path
  };

  // The textures of a textured object's material, by TexturedTerm: the index of each
  // term's image in SceneTextures (-1 where the term has none), its scale and wrap.
  struct SurfaceTextures {
    std::array<int, kTexturedTerms> image;
    std::array<Color, kTexturedTerms> scale;
    std::array<TextureWrap, kTexturedTerms> wrap;
    const Object* object;
    Mat4 world_to_object;
  };

  // What begin_shading() needs of an object's material, worked out once, so that shading a
  // hit reads one record and takes its colours by index rather than by branch: on a
  // checkerboard seen from afar, neighbouring pixels fall in cells of either parity.
  struct Surface {
    const Material* material;
    double checker_inverse_size;  // 1 / the cell's edge; 0 where there is no checker
    Color diffuse[2];             // K_D in even and in odd cells (the same without a checker)
    Color start[2];               // I_E + K_A·I_A in even and in odd cells
    const SurfaceTextures* textures = nullptr;  // where the material has any
  };

  Color shade(const Ray& ray, const SurfaceHit& hit, int depth, RayCounts& counts,
              double travelled) const;
  // 1 where the hit lies in an odd cell of its surface's checkerboard, else 0.
  static int checker_parity(const Surface& surface, const SurfaceHit& hit);
  // I_E + K_A·I_A at the hit: all there is to the colour of a hit that sends no ray on (no
  // lights, and no bounce left), which then needs nothing else begin_shading() works out.
  Color emitted_and_ambient(const Ray& ray, const SurfaceHit& hit, double travelled) const;
  // `travelled`: the path's length to the ray's origin.
  void begin_shading(const Ray& ray, const SurfaceHit& hit, double travelled,
                     Shading& shading) const;
  // The textured terms' colours at the hit, in place of the material's (tracer_textures.cpp):
  // `odd` is the hit's checker parity.
  void apply_textures(const SurfaceTextures& textures, int odd, const SurfaceHit& hit,
                      Shading& shading) const;
  // Tracer's constructor for the textures of each object's material.
  void prepare_textures(const SceneTextures* textures);
  // False when the light cannot reach the side of the surface facing the ray.
  static bool lit_by(const Shading& shading, const LightSample& sample, double& n_dot_l);
  void add_light(Shading& shading, const LightSample& sample, double n_dot_l,
                 const Color& shadow) const;
  // Where a ray refracted (or totally reflected) at the surface goes on.
  Vec3 transmitted_direction(const Shading& shading, const SurfaceHit& hit) const;
  // Adds the reflected and transmitted light.
  Color finish_shading(const Shading& shading, const SurfaceHit& hit, int depth,
                       RayCounts& counts) const;
  // 1 / (kc + kl·d + kq·d²).
  static double inverse_attenuation(const PreparedLight& light, double distance);
  LightSample sample_light(const PreparedLight& light, const Vec3& point) const;
  static void directional_sample(const PreparedLight& light, LightSample& sample);
  // A point or spot light's sample from the steps that take a square root and divisions,
  // done apart so that a packet does them for all its lanes at once:
  // `offset` = position - point, `distance` = |offset|, and their reciprocals, the second
  // of the attenuation.
  static void positional_sample(const PreparedLight& light, const Vec3& offset, double distance,
                                double inverse_distance, double inverse_attenuation,
                                LightSample& sample);
  // sample_light() for each lane where `found`, the roots and divisions in a loop of their
  // own that the compiler vectorises.
  void sample_light_packet(const PreparedLight& light, const SurfaceHit (&hits)[kPacketSize],
                           const bool (&found)[kPacketSize],
                           LightSample (&samples)[kPacketSize]) const;
  // S_L: 1 when nothing blocks the light, the product of the K_T of every transmissive
  // surface crossed, 0 behind an opaque one.
  Color shadow_factor(const SurfaceHit& hit, const LightSample& light, RayCounts& counts) const;
  // S_L once nothing opaque is known to lie on `ray`, a shadow ray that may go as far as
  // `reach`.
  Color unblocked_factor(const LightSample& light, Ray ray, float reach, RayCounts& counts) const;
  // unblocked_factor() of each active lane of `shadows` that `blocked` leaves free, into
  // `factor` (1 on the other lanes). The shadow rays of a packet's hits towards one light
  // are coherent, so the walk goes to Embree sixteen at a time, one crossing of every lane
  // per packet; each lane's arithmetic is unblocked_factor()'s own. Every lane is walked,
  // so that the packets do not depend on `keep`; the lanes in it are counted.
  void unblocked_factors(const LightSample (&samples)[kPacketSize], const RayPacket& shadows,
                         const float (&reach)[kPacketSize], const bool (&blocked)[kPacketSize],
                         const bool (&keep)[kPacketSize], Color (&factor)[kPacketSize],
                         RayCounts& counts) const;
  // How far a shadow ray starting at `from` may go towards the light.
  static float shadow_reach(const LightSample& light, const Ray& from);
  // The shadow ray from `hit` towards the light (to_light is unit already).
  static Ray shadow_ray(const SurfaceHit& hit, const LightSample& light);
  const Material& material_of(std::uint32_t object) const;

  const Scene& scene_;
  const SceneGeometry& geometry_;
  std::vector<PreparedLight> lights_;
  std::vector<bool> solid_;  // by object
  bool any_transmissive_ = false;
  std::vector<Surface> surfaces_;  // by object
  const SceneTextures* textures_ = nullptr;
  std::vector<SurfaceTextures> surface_textures_;  // of the textured objects; not resized
  // The angle between neighbouring samples' rays: a pixel's cone widens by this much per
  // unit of distance travelled.
  double spread_ = 0.0;
};

}  // namespace tessera
