// The Whitted illumination model of the course material, evaluated recursively:
//   I = I_E + K_A·I_A + Σ_L (K_D·(N·L) + K_S·(V·R)^n)·S_L·I_L + K_R·I_R + K_T·I_T
#pragma once

#include <cstdint>

#include "common/scene.hpp"
#include "worker/ray.hpp"
#include "worker/scene_geometry.hpp"

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

class Tracer {
 public:
  // Both must outlive the tracer.
  Tracer(const Scene& scene, const SceneGeometry& geometry);

  // The radiance arriving along `ray`; `depth` is the number of bounces before it.
  Color trace(const Ray& ray, int depth, RayCounts& counts) const;

 private:
  struct LightSample {
    Vec3 to_light{0.0};    // unit, from the surface point towards the light
    double distance = 0;   // to the light; infinite for directional lights
    Color intensity{0.0};  // I_L at the point, before shadowing
  };

  Color shade(const Ray& ray, const SurfaceHit& hit, int depth, RayCounts& counts) const;
  LightSample sample_light(const Light& light, const Vec3& point) const;
  // S_L: 1 when nothing blocks the light, the product of the K_T of every transmissive
  // surface crossed, 0 behind an opaque one.
  Color shadow_factor(const SurfaceHit& hit, const LightSample& light, RayCounts& counts) const;
  const Material& material_of(std::uint32_t object) const;

  const Scene& scene_;
  const SceneGeometry& geometry_;
  std::vector<bool> solid_;  // by object
  bool any_transmissive_ = false;
};

}  // namespace tessera
