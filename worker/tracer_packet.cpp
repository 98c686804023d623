// Shading the primary hits of a packet: the shadow rays of all sixteen towards one light
// make one coherent packet, the rest is Tracer::shade's own code, lane by lane.
#include "worker/tracer.hpp"

namespace tessera {

void Tracer::shade_packet(const RayPacket& packet, const SurfaceHit (&hits)[kPacketSize],
                          const bool (&found)[kPacketSize], const bool (&keep)[kPacketSize],
                          Color (&out)[kPacketSize], RayCounts& counts) const {
  Shading shading[kPacketSize];
  for (int i = 0; i < kPacketSize; ++i)
    if (found[i]) shading[i] = begin_shading(packet.rays[i], hits[i]);

  for (const PreparedLight& light : lights_) {
    LightSample samples[kPacketSize];
    double n_dot_l[kPacketSize];
    float reach[kPacketSize];
    RayPacket shadows;
    for (int i = 0; i < kPacketSize; ++i) {
      shadows.active[i] = found[i] && lit_by(shading[i], hits[i], light, samples[i], n_dot_l[i]);
      if (!shadows.active[i]) continue;
      shadows.rays[i] = shadow_ray(hits[i], samples[i]);
      reach[i] = shadow_reach(samples[i], shadows.rays[i]);
    }
    // Anything opaque on the way leaves the point in shadow whatever else is there.
    bool blocked[kPacketSize];
    geometry_.occluded(shadows, reach, kOpaqueMask, blocked);
    for (int i = 0; i < kPacketSize; ++i) {
      if (!shadows.active[i] || !keep[i]) continue;
      counts.shadow += 1;
      const Color shadow = blocked[i] ? Color(0.0)
                                      : unblocked_factor(samples[i], shadows.rays[i], reach[i], counts);
      add_light(shading[i], samples[i], n_dot_l[i], shadow);
    }
  }

  for (int i = 0; i < kPacketSize; ++i) {
    if (!keep[i]) continue;
    out[i] = found[i] ? finish_shading(shading[i], hits[i], 0, counts) : scene_.background;
  }
}

}  // namespace tessera
