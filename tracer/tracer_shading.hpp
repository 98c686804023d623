// The per-hit steps of the Whitted model, shared by Tracer::trace and Tracer::trace_packet.
// They live in a header so that both translation units inline them: a packet shades
// sixteen hits, and a call per step and per lane, with its Shading returned through memory,
// is overhead on every one (docs/performance.md has what inlining measured). Included by
// the tracer's own sources only.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "tracer/tracer.hpp"

namespace tessera::shading_detail {

// Shadow rays towards a point light stop just short of it, so a light that sits on a
// surface is not shadowed by that surface.
inline constexpr float kShadowReach = 0.99999f;

// Bounds the walk of a shadow ray through a stack of transmissive surfaces.
inline constexpr int kMaxShadowCrossings = 64;

inline bool is_zero(const Color& c) { return c.r == 0.0 && c.g == 0.0 && c.b == 0.0; }

inline double attenuate(const Attenuation& a, double distance) {
  return a.constant + a.linear * distance + a.quadratic * distance * distance;
}

inline Vec3 reflect(const Vec3& d, const Vec3& n) { return d - 2.0 * glm::dot(d, n) * n; }

// base^exponent, for the specular and spot exponents. Whole exponents, which nearly all are,
// go by repeated squaring: a handful of IEEE products, so the same bits on every CPU
// (libm's pow() picks its code by CPU, an FMA path or not, and is not correctly rounded),
// and several times cheaper. Good to about `exponent` units in the last place, 1e-12 at
// worst. 0^0 is 1, as pow() has it.
inline double power(double base, double exponent) {
  constexpr double kLargestWhole = 4096.0;
  if (!(exponent >= 0.0 && exponent <= kLargestWhole)) return std::pow(base, exponent);
  auto n = static_cast<unsigned>(exponent);
  if (static_cast<double>(n) != exponent) return std::pow(base, exponent);
  double result = 1.0;
  for (; n != 0; n >>= 1) {
    if (n & 1u) result *= base;
    base *= base;
  }
  return result;
}

// The checkerboard is sampled a little below the surface, on the side opposite its
// geometric normal: a floor lying exactly on a cell boundary (y = 0) then falls in one
// cell consistently instead of flickering between two with rounding. `inverse_size` is
// 1 / the cell's edge, worked out once per material.
inline bool in_odd_checker_cell(double inverse_size, const SurfaceHit& hit) {
  const Vec3 p = hit.position * inverse_size - 1e-4 * hit.normal;
  // The cell's indices as integers, whose parity is one bit, wherever they fit; that is
  // everywhere but at 2^52 cells and beyond, and on NaN, where std::floor takes over. (x86-64
  // without SSE4.1 has no floor instruction, and the integers cost less than four floors.)
  constexpr double kIntegral = 0x1p52;
  if (std::fabs(p.x) < kIntegral && std::fabs(p.y) < kIntegral && std::fabs(p.z) < kIntegral) {
    const auto cell = [](double v) {
      const auto truncated = static_cast<std::int64_t>(v);
      return truncated - (v < static_cast<double>(truncated) ? 1 : 0);
    };
    return ((cell(p.x) + cell(p.y) + cell(p.z)) & 1) != 0;
  }
  const double sum = std::floor(p.x) + std::floor(p.y) + std::floor(p.z);
  // An odd integer halves to a fraction (fmod does the same, slowly).
  const double half = 0.5 * sum;
  return half != std::floor(half);
}

}  // namespace tessera::shading_detail

namespace tessera {

inline int Tracer::checker_parity(const Surface& surface, const SurfaceHit& hit) {
  return surface.checker_inverse_size != 0.0 &&
         shading_detail::in_odd_checker_cell(surface.checker_inverse_size, hit);
}

inline Color Tracer::emitted_and_ambient(const Ray& ray, const SurfaceHit& hit,
                                         double travelled) const {
  const Surface& surface = surfaces_[hit.object];
  if (surface.textures != nullptr) [[unlikely]] {
    Shading shading;
    begin_shading(ray, hit, travelled, shading);
    return shading.result;
  }
  return surface.start[checker_parity(surface, hit)];
}

inline void Tracer::begin_shading(const Ray& ray, const SurfaceHit& hit, double travelled,
                                  Shading& shading) const {
  const Surface& surface = surfaces_[hit.object];
  shading.material = surface.material;
  shading.d = Vec3(ray.direction);
  shading.front = glm::dot(shading.d, hit.normal) < 0.0;
  shading.n = shading.front ? hit.shading_normal : -hit.shading_normal;  // faces the ray
  const int odd = checker_parity(surface, hit);
  shading.diffuse = surface.diffuse[odd];
  shading.specular = surface.material->specular;
  shading.result = surface.start[odd];
  shading.travelled = travelled + hit.t;
  if (surface.textures != nullptr) [[unlikely]]
    apply_textures(*surface.textures, odd, hit, shading);
}

inline double Tracer::inverse_attenuation(const PreparedLight& light, double distance) {
  return light.constant_falloff ? light.inverse_constant
                                : 1.0 / shading_detail::attenuate(light.attenuation, distance);
}

inline Tracer::LightSample Tracer::sample_light(const PreparedLight& light,
                                                const Vec3& point) const {
  LightSample sample;
  if (light.kind == PreparedLight::Kind::directional) {
    directional_sample(light, sample);
    return sample;
  }
  const Vec3 offset = light.position - point;
  const double distance = std::sqrt(glm::dot(offset, offset));
  positional_sample(light, offset, distance, 1.0 / distance, inverse_attenuation(light, distance),
                    sample);
  return sample;
}

inline void Tracer::directional_sample(const PreparedLight& light, LightSample& sample) {
  sample.to_light = -light.direction;
  sample.distance = std::numeric_limits<double>::infinity();
  sample.position = Vec3(0.0);
  sample.intensity = light.intensity;
}

// Writes into `sample` in place: built in a temporary and copied, GCC moves the struct
// through the stack in pieces that the CPU cannot forward, and stalls on every lane.
inline void Tracer::positional_sample(const PreparedLight& light, const Vec3& offset,
                                      double distance, double inverse_distance,
                                      double inverse_attenuation, LightSample& sample) {
  // Each field is stored once: a packet stores sixteen samples for every light.
  sample.position = light.position;
  sample.distance = distance;
  if (distance == 0.0) {  // a light inside the surface lights nothing
    sample.to_light = Vec3(0.0);
    sample.intensity = Color(0.0);
    return;
  }
  // One division each, then products: dividing each component costs three.
  sample.to_light = offset * inverse_distance;
  if (light.kind == PreparedLight::Kind::point) {
    sample.intensity = light.intensity * inverse_attenuation;
    return;
  }
  const double cos_angle = glm::dot(light.direction, -sample.to_light);  // D·L'
  sample.intensity = cos_angle <= 0.0 || cos_angle < light.cos_cutoff
                         ? Color(0.0)
                         : light.intensity * (shading_detail::power(cos_angle, light.exponent) *
                                              inverse_attenuation);
}

inline bool Tracer::lit_by(const Shading& shading, const LightSample& sample, double& n_dot_l) {
  n_dot_l = glm::dot(shading.n, sample.to_light);
  return n_dot_l > 0.0 && !shading_detail::is_zero(sample.intensity);
}

inline void Tracer::add_light(Shading& shading, const LightSample& sample, double n_dot_l,
                              const Color& shadow) const {
  if (shading_detail::is_zero(shadow)) return;
  const Material& material = *shading.material;
  Color specular(0.0);
  // The power is the dearest step of shading; where K_S·(V·R)^n is exactly zero anyway (no
  // specular colour, or V·R <= 0 with n > 0) it is skipped, which changes no bit.
  if (!shading_detail::is_zero(shading.specular)) {
    const Vec3 r = 2.0 * n_dot_l * shading.n - sample.to_light;
    const double v_dot_r = std::max(0.0, glm::dot(-shading.d, r));
    if (v_dot_r > 0.0 || material.shininess == 0.0)
      specular = shading.specular * shading_detail::power(v_dot_r, material.shininess);
  }
  shading.result += (shading.diffuse * n_dot_l + specular) * shadow * sample.intensity;
}

inline float Tracer::shadow_reach(const LightSample& light, const Ray& from) {
  if (!std::isfinite(light.distance)) return kInfinity;
  // The distance to the light measured along the ray: the origin was moved off the surface
  // by a few units in the last place, so this differs from the Euclidean distance only by
  // their square (and the float direction's rounding), far inside kShadowReach's margin,
  // and needs no square root.
  return shading_detail::kShadowReach *
         static_cast<float>(glm::dot(light.position - Vec3(from.origin), Vec3(from.direction)));
}

inline Ray Tracer::shadow_ray(const SurfaceHit& hit, const LightSample& light) {
  return Ray{offset_ray_origin(hit.position, hit.normal, light.to_light),
             glm::vec3(light.to_light)};
}

inline Vec3 Tracer::transmitted_direction(const Shading& shading, const SurfaceHit& hit) const {
  const Vec3& d = shading.d;
  if (!solid_[hit.object]) return d;  // thin surfaces let the ray pass unbent
  // Snell's law, entering from air or leaving into it.
  const Material& material = *shading.material;
  const Vec3& n = shading.n;
  const double eta = shading.front ? 1.0 / material.ior : material.ior;
  const double cos_i = glm::dot(-d, n);
  const double sin2_t = eta * eta * (1.0 - cos_i * cos_i);
  return sin2_t > 1.0 ? shading_detail::reflect(d, n)  // total internal reflection
                      : eta * d + (eta * cos_i - std::sqrt(1.0 - sin2_t)) * n;
}

}  // namespace tessera
