// The tracer sixteen rays at a time: a packet's hits, their shadow rays towards each light,
// and their reflected and transmitted rays each make one packet for Embree. Lane by lane,
// the arithmetic is Tracer::trace's own, in the same order.
#include "tracer/tracer.hpp"

#include "tracer/tracer_shading.hpp"

namespace tessera {

using shading_detail::is_zero;
using shading_detail::kMaxShadowCrossings;
using shading_detail::reflect;

void Tracer::trace_packet(const RayPacket& packet, int depth, const bool (&keep)[kPacketSize],
                          Color (&out)[kPacketSize], RayCounts& counts,
                          const double* travelled) const {
  SurfaceHit hits[kPacketSize];
  bool found[kPacketSize];
  geometry_.intersect(packet, hits, found);
  Shading shading[kPacketSize];
  // Every ray leaving a hit starts at one of two points, moved off the surface to the one
  // side or the other: worked out once here rather than once per light, and not at all
  // where no ray leaves (no lights, and the last bounce).
  const bool rays_leave = !lights_.empty() || depth < scene_.render.max_depth;
  glm::vec3 lifted[2][kPacketSize];
  for (int i = 0; i < kPacketSize; ++i) {
    if (packet.active[i] & keep[i]) (depth == 0 ? counts.primary : counts.secondary) += 1;
    if (!found[i]) continue;
    const double before = travelled != nullptr ? travelled[i] : 0.0;
    if (!rays_leave) {
      shading[i].result = emitted_and_ambient(packet.ray(i), hits[i], before);
      continue;
    }
    begin_shading(packet.ray(i), hits[i], before, shading[i]);
    lifted[0][i] = offset_ray_origin(hits[i].position, hits[i].normal, 1.0f);
    lifted[1][i] = offset_ray_origin(hits[i].position, hits[i].normal, -1.0f);
  }
  auto leaving = [&](int i, const Vec3& direction) {
    return lifted[side_towards(hits[i].normal, direction) < 0.0f ? 1 : 0][i];
  };

  for (const PreparedLight& light : lights_) {
    LightSample samples[kPacketSize];
    double n_dot_l[kPacketSize];
    float reach[kPacketSize] = {};  // every lane's is read (may_meet_transmissive())
    RayPacket shadows;
    sample_light_packet(light, hits, found, samples);
    for (int i = 0; i < kPacketSize; ++i)
      shadows.active[i] = found[i] && lit_by(shading[i], samples[i], n_dot_l[i]);
    for (int i = 0; i < kPacketSize; ++i) {
      if (!shadows.active[i]) continue;
      // shadow_ray(), from the point already moved off the surface.
      const Ray ray{leaving(i, samples[i].to_light), glm::vec3(samples[i].to_light)};
      shadows.set(i, ray);
      reach[i] = shadow_reach(samples[i], ray);
    }
    // Anything opaque on the way leaves the point in shadow whatever else is there.
    bool blocked[kPacketSize];
    geometry_.occluded(shadows, reach, kOpaqueMask, blocked);
    Color shadow[kPacketSize];
    unblocked_factors(samples, shadows, reach, blocked, keep, shadow, counts);
    for (int i = 0; i < kPacketSize; ++i) {
      if (!(shadows.active[i] & keep[i])) continue;
      counts.shadow += 1;
      add_light(shading[i], samples[i], n_dot_l[i], blocked[i] ? Color(0.0) : shadow[i]);
    }
  }

  for (int i = 0; i < kPacketSize; ++i)
    if (packet.active[i]) out[i] = found[i] ? shading[i].result : scene_.background;
  if (depth >= scene_.render.max_depth) return;

  // I_R, then I_T, added in that order as finish_shading() does: each lane with a non-zero
  // coefficient sends a ray in the direction given, and what comes back is weighted by it.
  auto bounce = [&](Color Material::*coefficient, auto direction) {
    RayPacket rays;
    bool any = false;
    double along[kPacketSize];
    for (int i = 0; i < kPacketSize; ++i) {
      rays.active[i] = found[i] && !is_zero(shading[i].material->*coefficient);
      along[i] = rays.active[i] ? shading[i].travelled : 0.0;
      if (!rays.active[i]) continue;
      // ray_from(), from the point already moved off the surface.
      const Vec3 towards = direction(i);
      rays.set(i, Ray{leaving(i, towards), glm::vec3(glm::normalize(towards))});
      any = true;
    }
    if (!any) return;
    Color incoming[kPacketSize];
    trace_packet(rays, depth + 1, keep, incoming, counts, along);
    for (int i = 0; i < kPacketSize; ++i)
      if (rays.active[i]) out[i] += shading[i].material->*coefficient * incoming[i];
  };
  bounce(&Material::reflection, [&](int i) { return reflect(shading[i].d, shading[i].n); });
  bounce(&Material::transmission,
         [&](int i) { return transmitted_direction(shading[i], hits[i]); });
}

void Tracer::unblocked_factors(const LightSample (&samples)[kPacketSize], const RayPacket& shadows,
                               const float (&reach)[kPacketSize],
                               const bool (&blocked)[kPacketSize], const bool (&keep)[kPacketSize],
                               Color (&factor)[kPacketSize], RayCounts& counts) const {
  for (int i = 0; i < kPacketSize; ++i) factor[i] = Color(1.0);
  if (!any_transmissive_) return;
  RayPacket walk;
  float walk_reach[kPacketSize] = {};
  std::uint32_t left[kPacketSize];
  for (int i = 0; i < kPacketSize; ++i) left[i] = kNoObject;
  bool any = false;
  geometry_.may_meet_transmissive(shadows, reach, left, walk.active);
  for (int i = 0; i < kPacketSize; ++i) {
    walk.active[i] = walk.active[i] & !blocked[i];
    if (!walk.active[i]) continue;
    walk.set(i, shadows.ray(i));
    walk_reach[i] = reach[i];
    any = true;
  }
  for (int crossing = 0; any && crossing < kMaxShadowCrossings; ++crossing) {
    SurfaceHit blockers[kPacketSize];
    bool found[kPacketSize];
    geometry_.intersect(walk, walk_reach, kTransmissiveMask, blockers, found);
    any = false;
    for (int i = 0; i < kPacketSize; ++i) {
      if (!walk.active[i]) continue;
      if (keep[i]) counts.shadow += 1;
      if (found[i]) factor[i] *= material_of(blockers[i].object).transmission;
      walk.active[i] = found[i] && !is_zero(factor[i]);
      if (!walk.active[i]) continue;
      walk.set_origin(
          i, offset_ray_origin(blockers[i].position, blockers[i].normal, samples[i].to_light));
      walk_reach[i] = shadow_reach(samples[i], walk.ray(i));
      left[i] = geometry_.left_for_good(blockers[i], samples[i].to_light);
    }
    // The lanes with nothing transmissive left ahead stop here, as unblocked_factor()'s do.
    bool may[kPacketSize];
    geometry_.may_meet_transmissive(walk, walk_reach, left, may);
    for (int i = 0; i < kPacketSize; ++i) {
      walk.active[i] = walk.active[i] & may[i];
      any = any | walk.active[i];
    }
  }
}

void Tracer::sample_light_packet(const PreparedLight& light, const SurfaceHit (&hits)[kPacketSize],
                                 const bool (&found)[kPacketSize],
                                 LightSample (&samples)[kPacketSize]) const {
  if (light.kind == PreparedLight::Kind::directional) {
    for (int i = 0; i < kPacketSize; ++i)
      if (found[i]) directional_sample(light, samples[i]);
    return;
  }
  // sample_light()'s very operations, regrouped: the squared distances, then the roots and
  // reciprocals of all sixteen lanes in one branch-free loop (two lanes to an SSE2
  // instruction), then the rest. A lane without a hit gets a harmless unit offset.
  Vec3 offset[kPacketSize];
  double squared[kPacketSize];
  for (int i = 0; i < kPacketSize; ++i) {
    offset[i] = found[i] ? light.position - hits[i].position : Vec3(1.0, 0.0, 0.0);
    squared[i] = glm::dot(offset[i], offset[i]);
  }
  double distance[kPacketSize];
  double inverse_distance[kPacketSize];
  double inverse_attenuation[kPacketSize];
  for (int i = 0; i < kPacketSize; ++i) {
    distance[i] = std::sqrt(squared[i]);
    inverse_distance[i] = 1.0 / distance[i];
  }
  // The falloff's test is the same for every lane, so GCC takes it out of the loop.
  for (int i = 0; i < kPacketSize; ++i)
    inverse_attenuation[i] = Tracer::inverse_attenuation(light, distance[i]);
  for (int i = 0; i < kPacketSize; ++i)
    if (found[i])
      positional_sample(light, offset[i], distance[i], inverse_distance[i], inverse_attenuation[i],
                        samples[i]);
}

}  // namespace tessera
