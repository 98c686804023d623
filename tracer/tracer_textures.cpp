// Textured materials: a hit's uv on its surface, the pixel's cone there as a footprint in
// the texture, and the colours of the textured terms looked up over that footprint.
//
// The cone: neighbouring samples' rays leave the camera `spread_` radians apart, so a
// sample stands for a disc of diameter spread_ · d at distance d along its path; through
// reflections and refractions the path's whole length counts, the surfaces' curvature
// being left aside (the ray cones of Akenine-Möller et al., Ray Tracing Gems, ch. 20, at
// their simplest). On the surface the disc becomes an ellipse: its width across the ray,
// and stretched by 1 / cos θ along it.
#include <cmath>

#include "tracer/surface_uv.hpp"
#include "tracer/tracer.hpp"
#include "tracer/tracer_shading.hpp"

namespace tessera {
namespace {

// The footprint of a cone `width` wide meeting the surface with normal `n` along `d`, in
// the texture's coordinates by way of the surface's dp/du and dp/dv.
TextureFootprint footprint(const SurfaceUv& surface, const Vec3& d, const Vec3& n, double width) {
  TextureFootprint at{static_cast<float>(surface.uv.x),
                      static_cast<float>(1.0 - surface.uv.y),
                      0.0f,
                      0.0f,
                      0.0f,
                      0.0f};
  // The least-squares inverse of [dp/du dp/dv], for vectors in the tangent plane.
  const double e = glm::dot(surface.dpdu, surface.dpdu);
  const double f = glm::dot(surface.dpdu, surface.dpdv);
  const double g = glm::dot(surface.dpdv, surface.dpdv);
  const double det = e * g - f * f;
  if (!(det > 1e-30 * e * g) || !(width > 0.0) || !std::isfinite(width)) return at;
  const double cos_theta = std::max(std::fabs(glm::dot(d, n)), 1e-3);
  Vec3 across = glm::cross(d, n);
  const double across_length = glm::length(across);
  // Head on, every direction in the plane is across: any perpendicular of n will do.
  across =
      across_length > 1e-9
          ? across / across_length
          : glm::normalize(glm::cross(std::fabs(n.x) < 0.9 ? Vec3(1, 0, 0) : Vec3(0, 1, 0), n));
  const Vec3 along = glm::cross(n, across) * (width / cos_theta);
  across *= width;
  const auto to_uv = [&](const Vec3& x) {
    const double pu = glm::dot(surface.dpdu, x);
    const double pv = glm::dot(surface.dpdv, x);
    return glm::dvec2((g * pu - f * pv) / det, (e * pv - f * pu) / det);
  };
  const glm::dvec2 dx = to_uv(across);
  const glm::dvec2 dy = to_uv(along);
  // t runs down the image, v up it.
  at.dsdx = static_cast<float>(dx.x);
  at.dtdx = static_cast<float>(-dx.y);
  at.dsdy = static_cast<float>(dy.x);
  at.dtdy = static_cast<float>(-dy.y);
  return at;
}

}  // namespace

void Tracer::prepare_textures(const SceneTextures* textures) {
  textures_ = textures;
  const RenderSettings& render = scene_.render;
  spread_ = 2.0 * std::tan(glm::radians(scene_.camera.fov_y_degrees) / 2.0) / scene_.height /
            std::sqrt(static_cast<double>(render.samples_per_pixel));
  if (textures == nullptr) return;
  // Reserved whole: surfaces_ point into it.
  std::size_t textured = 0;
  for (const Object& object : scene_.objects)
    textured += scene_.materials[object.material].textured() ? 1 : 0;
  surface_textures_.reserve(textured);
  for (std::size_t i = 0; i < scene_.objects.size(); ++i) {
    const Object& object = scene_.objects[i];
    const Material& material = scene_.materials[object.material];
    if (!material.textured()) continue;
    SurfaceTextures& out = surface_textures_.emplace_back();
    for (std::size_t term = 0; term < kTexturedTerms; ++term) {
      const auto& texture = material.textures[term];
      out.image[term] = texture ? static_cast<int>(textures->index_of(texture->image)) : -1;
      out.scale[term] = texture ? texture->scale : Color(0.0);
      out.wrap[term] = texture ? texture->wrap : TextureWrap::repeat;
    }
    out.object = &object;
    out.world_to_object = glm::inverse(object.transform);
    surfaces_[i].textures = &out;
  }
}

void Tracer::apply_textures(const SurfaceTextures& textures, int odd, const SurfaceHit& hit,
                            Shading& shading) const {
  const SurfaceUv surface = surface_uv(*textures.object, textures.world_to_object, hit);
  const TextureFootprint at =
      footprint(surface, shading.d, hit.normal, spread_ * shading.travelled);
  Color colours[kTexturedTerms];
  for (std::size_t term = 0; term < kTexturedTerms; ++term) {
    if (textures.image[term] < 0) continue;
    float rgb[3];
    textures_->sampler().sample(static_cast<std::size_t>(textures.image[term]), textures.wrap[term],
                                at, rgb);
    colours[term] = textures.scale[term] * Color(rgb[0], rgb[1], rgb[2]);
  }
  const auto has = [&](TexturedTerm term) {
    return textures.image[static_cast<std::size_t>(term)] >= 0;
  };
  const auto colour = [&](TexturedTerm term) { return colours[static_cast<std::size_t>(term)]; };
  const Material& material = *shading.material;
  if (has(TexturedTerm::emission) || has(TexturedTerm::ambient)) {
    const Color emission =
        has(TexturedTerm::emission) ? colour(TexturedTerm::emission) : material.emission;
    const Color ambient =
        has(TexturedTerm::ambient)
            ? colour(TexturedTerm::ambient)
            : (odd != 0 && material.checker ? material.checker->ambient : material.ambient);
    shading.result = emission + ambient * scene_.ambient_light;
  }
  if (has(TexturedTerm::diffuse)) shading.diffuse = colour(TexturedTerm::diffuse);
  if (has(TexturedTerm::specular)) shading.specular = colour(TexturedTerm::specular);
}

}  // namespace tessera
