#include "tracer/tracer.hpp"

#include <cmath>

#include "tracer/tracer_shading.hpp"

namespace tessera {
namespace {

using shading_detail::is_zero;
using shading_detail::kMaxShadowCrossings;
using shading_detail::reflect;

}  // namespace

Tracer::Tracer(const Scene& scene, const SceneGeometry& geometry, const SceneTextures* textures)
    : scene_(scene), geometry_(geometry) {
  for (const Light& light : scene.lights) {
    PreparedLight prepared{};
    if (const auto* point = std::get_if<PointLight>(&light)) {
      prepared = {PreparedLight::Kind::point,
                  point->position,
                  Vec3(0.0),
                  point->intensity,
                  point->attenuation,
                  0.0,
                  1.0};
    } else if (const auto* directional = std::get_if<DirectionalLight>(&light)) {
      prepared = {PreparedLight::Kind::directional,
                  Vec3(0.0),
                  directional->direction,
                  directional->intensity,
                  Attenuation{},
                  0.0,
                  1.0};
    } else {
      const auto& spot = std::get<SpotLight>(light);
      prepared = {PreparedLight::Kind::spot,
                  spot.position,
                  spot.direction,
                  spot.intensity,
                  spot.attenuation,
                  std::cos(glm::radians(spot.cutoff_degrees)),
                  spot.exponent};
    }
    prepared.constant_falloff =
        prepared.attenuation.linear == 0.0 && prepared.attenuation.quadratic == 0.0;
    prepared.inverse_constant = 1.0 / prepared.attenuation.constant;
    // A light of zero intensity lights nothing, and casts no shadow rays.
    if (!is_zero(prepared.intensity)) lights_.push_back(prepared);
  }
  solid_.reserve(scene.objects.size());
  for (const Object& object : scene.objects) {
    solid_.push_back(is_solid(object));
    if (!is_zero(scene.materials[object.material].transmission)) any_transmissive_ = true;
  }
  surfaces_.reserve(scene.objects.size());
  for (const Object& object : scene.objects) {
    const Material& material = scene.materials[object.material];
    Surface surface{&material, 0.0, {material.diffuse, material.diffuse}, {}};
    const Color* ambient[2] = {&material.ambient, &material.ambient};
    if (material.checker) {
      surface.checker_inverse_size = 1.0 / material.checker->size;
      surface.diffuse[1] = material.checker->diffuse;
      ambient[1] = &material.checker->ambient;
    }
    // The very sum shading made per hit before, so every pixel keeps its bits.
    for (int odd = 0; odd < 2; ++odd)
      surface.start[odd] = material.emission + *ambient[odd] * scene.ambient_light;
    surfaces_.push_back(surface);
  }
  prepare_textures(textures);
}

const Material& Tracer::material_of(std::uint32_t object) const {
  return *surfaces_[object].material;
}

Color Tracer::trace(const Ray& ray, int depth, RayCounts& counts, double travelled) const {
  (depth == 0 ? counts.primary : counts.secondary) += 1;
  const auto hit = geometry_.intersect(ray, kInfinity);
  if (!hit) return scene_.background;
  return shade(ray, *hit, depth, counts, travelled);
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
    // Often nothing transmissive is left ahead, as when the ray has just left the one glass
    // sphere on its way: the box tests say so, and spare the query that would find nothing.
    if (!geometry_.may_meet_transmissive(ray, reach,
                                         geometry_.left_for_good(*blocker, light.to_light)))
      return factor;
  }
  return factor;
}

Color Tracer::shade(const Ray& ray, const SurfaceHit& hit, int depth, RayCounts& counts,
                    double travelled) const {
  if (lights_.empty() && depth >= scene_.render.max_depth)
    return emitted_and_ambient(ray, hit, travelled);
  Shading shading;
  begin_shading(ray, hit, travelled, shading);
  for (const PreparedLight& light : lights_) {
    const LightSample sample = sample_light(light, hit.position);
    double n_dot_l;
    if (!lit_by(shading, sample, n_dot_l)) continue;
    add_light(shading, sample, n_dot_l, shadow_factor(hit, sample, counts));
  }
  return finish_shading(shading, hit, depth, counts);
}

Color Tracer::finish_shading(const Shading& shading, const SurfaceHit& hit, int depth,
                             RayCounts& counts) const {
  Color result = shading.result;
  if (depth >= scene_.render.max_depth) return result;
  const Material& material = *shading.material;
  const Vec3& d = shading.d;
  const Vec3& n = shading.n;
  if (!is_zero(material.reflection))
    result += material.reflection *
              trace(ray_from(hit, reflect(d, n)), depth + 1, counts, shading.travelled);
  if (!is_zero(material.transmission))
    result += material.transmission * trace(ray_from(hit, transmitted_direction(shading, hit)),
                                            depth + 1, counts, shading.travelled);
  return result;
}

}  // namespace tessera
