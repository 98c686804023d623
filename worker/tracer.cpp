#include "worker/tracer.hpp"

#include <cmath>

namespace tessera {
namespace {

// Bounds the walk of a shadow ray through a stack of transmissive surfaces.
constexpr int kMaxShadowCrossings = 64;
// Shadow rays towards a point light stop just short of it, so a light that sits on a
// surface is not shadowed by that surface.
constexpr float kShadowReach = 0.99999f;

bool is_zero(const Color& c) { return c.r == 0.0 && c.g == 0.0 && c.b == 0.0; }

double attenuate(const Attenuation& a, double distance) {
  return a.constant + a.linear * distance + a.quadratic * distance * distance;
}

Vec3 reflect(const Vec3& d, const Vec3& n) { return d - 2.0 * glm::dot(d, n) * n; }

// The checkerboard is sampled a little below the surface, on the side opposite its
// geometric normal: a floor lying exactly on a cell boundary (y = 0) then falls in one
// cell consistently instead of flickering between two with rounding.
bool in_odd_checker_cell(const Checker& checker, const SurfaceHit& hit) {
  const Vec3 p = (hit.position - (1e-4 * checker.size) * hit.normal) / checker.size;
  const double sum = std::floor(p.x) + std::floor(p.y) + std::floor(p.z);
  // An odd integer halves to a fraction (fmod does the same, slowly).
  const double half = 0.5 * sum;
  return half != std::floor(half);
}

}  // namespace

Tracer::Tracer(const Scene& scene, const SceneGeometry& geometry)
    : scene_(scene), geometry_(geometry) {
  for (const Light& light : scene.lights) {
    PreparedLight prepared{};
    if (const auto* point = std::get_if<PointLight>(&light)) {
      prepared = {PreparedLight::Kind::point, point->position, Vec3(0.0), point->intensity,
                  point->attenuation, 0.0, 1.0};
    } else if (const auto* directional = std::get_if<DirectionalLight>(&light)) {
      prepared = {PreparedLight::Kind::directional, Vec3(0.0), directional->direction,
                  directional->intensity, Attenuation{}, 0.0, 1.0};
    } else {
      const auto& spot = std::get<SpotLight>(light);
      prepared = {PreparedLight::Kind::spot, spot.position, spot.direction, spot.intensity,
                  spot.attenuation, std::cos(glm::radians(spot.cutoff_degrees)), spot.exponent};
    }
    // A light of zero intensity lights nothing, and casts no shadow rays.
    if (!is_zero(prepared.intensity)) lights_.push_back(prepared);
  }
  solid_.reserve(scene.objects.size());
  for (const Object& object : scene.objects) {
    solid_.push_back(is_solid(object));
    if (!is_zero(scene.materials[object.material].transmission)) any_transmissive_ = true;
  }
}

const Material& Tracer::material_of(std::uint32_t object) const {
  return scene_.materials[scene_.objects[object].material];
}

Color Tracer::trace(const Ray& ray, int depth, RayCounts& counts) const {
  (depth == 0 ? counts.primary : counts.secondary) += 1;
  const auto hit = geometry_.intersect(ray, kInfinity);
  if (!hit) return scene_.background;
  return shade(ray, *hit, depth, counts);
}

Tracer::LightSample Tracer::sample_light(const PreparedLight& light, const Vec3& point) const {
  LightSample sample;
  if (light.kind == PreparedLight::Kind::directional) {
    sample.to_light = -light.direction;
    sample.distance = std::numeric_limits<double>::infinity();
    sample.intensity = light.intensity;
    return sample;
  }
  sample.position = light.position;
  const Vec3 offset = light.position - point;
  sample.distance = glm::length(offset);
  if (sample.distance == 0.0) return sample;  // a light inside the surface lights nothing
  // One division each, then products: dividing each component costs three.
  sample.to_light = offset * (1.0 / sample.distance);
  if (light.kind == PreparedLight::Kind::point) {
    sample.intensity = light.intensity * (1.0 / attenuate(light.attenuation, sample.distance));
    return sample;
  }
  const double cos_angle = glm::dot(light.direction, -sample.to_light);  // D·L'
  if (cos_angle <= 0.0 || cos_angle < light.cos_cutoff) return sample;
  sample.intensity = light.intensity * (std::pow(cos_angle, light.exponent) /
                                        attenuate(light.attenuation, sample.distance));
  return sample;
}

float Tracer::shadow_reach(const LightSample& light, const Ray& from) {
  if (!std::isfinite(light.distance)) return kInfinity;
  return kShadowReach * static_cast<float>(glm::length(light.position - Vec3(from.origin)));
}

Ray Tracer::shadow_ray(const SurfaceHit& hit, const LightSample& light) {
  return Ray{offset_ray_origin(hit.position, hit.normal, light.to_light),
             glm::vec3(light.to_light)};
}

Color Tracer::shadow_factor(const SurfaceHit& hit, const LightSample& light,
                            RayCounts& counts) const {
  const Ray ray = shadow_ray(hit, light);
  const float reach = shadow_reach(light, ray);
  // Anything opaque on the way leaves the point in shadow whatever else is there.
  counts.shadow += 1;
  if (geometry_.occluded(ray, reach, kOpaqueMask)) return Color(0.0);
  return unblocked_factor(light, ray, reach, counts);
}

Color Tracer::unblocked_factor(const LightSample& light, Ray ray, float reach,
                               RayCounts& counts) const {
  if (!any_transmissive_ || !geometry_.may_meet_transmissive(ray, reach)) return Color(1.0);
  // Walk the transmissive surfaces front to back, so that the product is taken in one
  // fixed order.
  Color factor(1.0);
  for (int crossing = 0; crossing < kMaxShadowCrossings; ++crossing) {
    counts.shadow += 1;
    const auto blocker = geometry_.intersect(ray, reach, kTransmissiveMask);
    if (!blocker) return factor;
    factor *= material_of(blocker->object).transmission;
    if (is_zero(factor)) return factor;
    ray.origin = offset_ray_origin(blocker->position, blocker->normal, light.to_light);
    reach = shadow_reach(light, ray);
  }
  return factor;
}

Tracer::Shading Tracer::begin_shading(const Ray& ray, const SurfaceHit& hit) const {
  Shading shading;
  const Material& material = material_of(hit.object);
  shading.material = &material;
  shading.d = Vec3(ray.direction);
  shading.front = glm::dot(shading.d, hit.normal) < 0.0;
  shading.n = shading.front ? hit.shading_normal : -hit.shading_normal;  // faces the ray

  Color ambient = material.ambient;
  shading.diffuse = material.diffuse;
  if (material.checker && in_odd_checker_cell(*material.checker, hit)) {
    ambient = material.checker->ambient;
    shading.diffuse = material.checker->diffuse;
  }
  shading.result = material.emission + ambient * scene_.ambient_light;
  return shading;
}

bool Tracer::lit_by(const Shading& shading, const SurfaceHit& hit, const PreparedLight& light,
                    LightSample& sample, double& n_dot_l) const {
  sample = sample_light(light, hit.position);
  n_dot_l = glm::dot(shading.n, sample.to_light);
  return n_dot_l > 0.0 && !is_zero(sample.intensity);
}

void Tracer::add_light(Shading& shading, const LightSample& sample, double n_dot_l,
                       const Color& shadow) const {
  if (is_zero(shadow)) return;
  const Material& material = *shading.material;
  Color specular(0.0);
  // pow() is the dearest step of shading; where K_S·(V·R)^n is exactly zero anyway (no
  // specular colour, or V·R <= 0 with n > 0) it is skipped, which changes no bit.
  if (!is_zero(material.specular)) {
    const Vec3 r = 2.0 * n_dot_l * shading.n - sample.to_light;
    const double v_dot_r = std::max(0.0, glm::dot(-shading.d, r));
    if (v_dot_r > 0.0 || material.shininess == 0.0)
      specular = material.specular * std::pow(v_dot_r, material.shininess);
  }
  shading.result += (shading.diffuse * n_dot_l + specular) * shadow * sample.intensity;
}

Color Tracer::shade(const Ray& ray, const SurfaceHit& hit, int depth, RayCounts& counts) const {
  Shading shading = begin_shading(ray, hit);
  for (const PreparedLight& light : lights_) {
    LightSample sample;
    double n_dot_l;
    if (!lit_by(shading, hit, light, sample, n_dot_l)) continue;
    add_light(shading, sample, n_dot_l, shadow_factor(hit, sample, counts));
  }
  return finish_shading(shading, hit, depth, counts);
}

Vec3 Tracer::transmitted_direction(const Shading& shading, const SurfaceHit& hit) const {
  const Vec3& d = shading.d;
  if (!solid_[hit.object]) return d;  // thin surfaces let the ray pass unbent
  // Snell's law, entering from air or leaving into it.
  const Material& material = *shading.material;
  const Vec3& n = shading.n;
  const double eta = shading.front ? 1.0 / material.ior : material.ior;
  const double cos_i = glm::dot(-d, n);
  const double sin2_t = eta * eta * (1.0 - cos_i * cos_i);
  return sin2_t > 1.0 ? reflect(d, n)  // total internal reflection
                      : eta * d + (eta * cos_i - std::sqrt(1.0 - sin2_t)) * n;
}

Color Tracer::finish_shading(const Shading& shading, const SurfaceHit& hit, int depth,
                             RayCounts& counts) const {
  Color result = shading.result;
  if (depth >= scene_.render.max_depth) return result;
  const Material& material = *shading.material;
  const Vec3& d = shading.d;
  const Vec3& n = shading.n;
  if (!is_zero(material.reflection))
    result += material.reflection * trace(ray_from(hit, reflect(d, n)), depth + 1, counts);
  if (!is_zero(material.transmission))
    result += material.transmission *
              trace(ray_from(hit, transmitted_direction(shading, hit)), depth + 1, counts);
  return result;
}

}  // namespace tessera
