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

Ray make_ray(const SurfaceHit& hit, const Vec3& direction) {
  return Ray{offset_ray_origin(hit.position, hit.normal, direction),
             glm::vec3(glm::normalize(direction))};
}

// The checkerboard is sampled a little below the surface, on the side opposite its
// geometric normal: a floor lying exactly on a cell boundary (y = 0) then falls in one
// cell consistently instead of flickering between two with rounding.
bool in_odd_checker_cell(const Checker& checker, const SurfaceHit& hit) {
  const Vec3 p = (hit.position - (1e-4 * checker.size) * hit.normal) / checker.size;
  const double sum = std::floor(p.x) + std::floor(p.y) + std::floor(p.z);
  return std::fmod(std::fabs(sum), 2.0) == 1.0;
}

}  // namespace

Tracer::Tracer(const Scene& scene, const SceneGeometry& geometry)
    : scene_(scene), geometry_(geometry) {
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

Tracer::LightSample Tracer::sample_light(const Light& light, const Vec3& point) const {
  LightSample sample;
  if (const auto* directional = std::get_if<DirectionalLight>(&light)) {
    sample.to_light = -directional->direction;
    sample.distance = std::numeric_limits<double>::infinity();
    sample.intensity = directional->intensity;
    return sample;
  }
  const Vec3 position = std::holds_alternative<PointLight>(light)
                            ? std::get<PointLight>(light).position
                            : std::get<SpotLight>(light).position;
  const Vec3 offset = position - point;
  sample.distance = glm::length(offset);
  if (sample.distance == 0.0) return sample;  // a light inside the surface lights nothing
  sample.to_light = offset / sample.distance;
  if (const auto* point_light = std::get_if<PointLight>(&light)) {
    sample.intensity =
        point_light->intensity / attenuate(point_light->attenuation, sample.distance);
    return sample;
  }
  const auto& spot = std::get<SpotLight>(light);
  const double cos_angle = glm::dot(spot.direction, -sample.to_light);  // D·L'
  if (cos_angle <= 0.0 || cos_angle < std::cos(glm::radians(spot.cutoff_degrees))) return sample;
  sample.intensity = spot.intensity * std::pow(cos_angle, spot.exponent) /
                     attenuate(spot.attenuation, sample.distance);
  return sample;
}

Color Tracer::shadow_factor(const SurfaceHit& hit, const LightSample& light,
                            RayCounts& counts) const {
  Ray ray = make_ray(hit, light.to_light);
  const bool finite = std::isfinite(light.distance);
  auto reach = [&](const Ray& from) {
    if (!finite) return kInfinity;
    return kShadowReach * static_cast<float>(glm::length(
                              hit.position + light.distance * light.to_light - Vec3(from.origin)));
  };
  if (!any_transmissive_) {
    counts.shadow += 1;
    return geometry_.occluded(ray, reach(ray)) ? Color(0.0) : Color(1.0);
  }
  // Walk front to back so that the product is taken in one fixed order.
  Color factor(1.0);
  for (int crossing = 0; crossing < kMaxShadowCrossings; ++crossing) {
    counts.shadow += 1;
    const auto blocker = geometry_.intersect(ray, reach(ray));
    if (!blocker) return factor;
    factor *= material_of(blocker->object).transmission;
    if (is_zero(factor)) return factor;
    ray.origin = offset_ray_origin(blocker->position, blocker->normal, light.to_light);
  }
  return factor;
}

Color Tracer::shade(const Ray& ray, const SurfaceHit& hit, int depth, RayCounts& counts) const {
  const Material& material = material_of(hit.object);
  const Vec3 d(ray.direction);
  const bool front = glm::dot(d, hit.normal) < 0.0;
  const Vec3 n = front ? hit.shading_normal : -hit.shading_normal;  // faces the ray
  const Vec3 v = -d;

  Color ambient = material.ambient;
  Color diffuse = material.diffuse;
  if (material.checker && in_odd_checker_cell(*material.checker, hit)) {
    ambient = material.checker->ambient;
    diffuse = material.checker->diffuse;
  }

  Color result = material.emission + ambient * scene_.ambient_light;
  for (const Light& light : scene_.lights) {
    const LightSample sample = sample_light(light, hit.position);
    const double n_dot_l = glm::dot(n, sample.to_light);
    if (n_dot_l <= 0.0 || is_zero(sample.intensity)) continue;
    const Color shadow = shadow_factor(hit, sample, counts);
    if (is_zero(shadow)) continue;
    const Vec3 r = 2.0 * n_dot_l * n - sample.to_light;
    const double v_dot_r = std::max(0.0, glm::dot(v, r));
    const Color specular = material.specular * std::pow(v_dot_r, material.shininess);
    result += (diffuse * n_dot_l + specular) * shadow * sample.intensity;
  }

  if (depth >= scene_.render.max_depth) return result;
  if (!is_zero(material.reflection))
    result += material.reflection * trace(make_ray(hit, reflect(d, n)), depth + 1, counts);
  if (!is_zero(material.transmission)) {
    Vec3 transmitted = d;  // thin surfaces let the ray pass unbent
    if (solid_[hit.object]) {
      // Snell's law, entering from air or leaving into it.
      const double eta = front ? 1.0 / material.ior : material.ior;
      const double cos_i = glm::dot(v, n);
      const double sin2_t = eta * eta * (1.0 - cos_i * cos_i);
      transmitted = sin2_t > 1.0 ? reflect(d, n)  // total internal reflection
                                 : eta * d + (eta * cos_i - std::sqrt(1.0 - sin2_t)) * n;
    }
    result += material.transmission * trace(make_ray(hit, transmitted), depth + 1, counts);
  }
  return result;
}

}  // namespace tessera
