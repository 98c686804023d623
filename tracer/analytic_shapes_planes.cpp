// The planes' tests that run outside Embree: the opaque planes of a packet, on all lanes at
// once, and of a single ray the same way (see OpaquePlanes).
#include <algorithm>
#include <cstddef>

#include "tracer/analytic_shapes.hpp"
#include "tracer/scene_geometry.hpp"

namespace tessera {

namespace {

// Where the ray's line meets the plane, in units of its direction: infinite or NaN when
// they are parallel. It takes scalars so that the packets' loop over lanes vectorises; the
// sums go in glm::dot's order.
[[gnu::always_inline]] inline double plane_quotient(const PreparedPlane& plane, double ox,
                                                    double oy, double oz, double dx, double dy,
                                                    double dz) {
  const double denominator = dx * plane.normal.x + dy * plane.normal.y + dz * plane.normal.z;
  const double numerator =
      plane.offset - (ox * plane.normal.x + oy * plane.normal.y + oz * plane.normal.z);
  return numerator / denominator;
}

// The nearest plane on each lane with valid[i] == -1 of sixteen rays that start at t = 0,
// for any of Embree's ray layouts of sixteen.
template <typename Rays>
void nearest_of_planes(const PlaneSet& set, const Rays& rays, const int (&valid)[16],
                       double (&t)[16], int (&plane)[16]) {
  // In arrays of its own, so that the compiler need not allow for the outputs overlapping
  // the rays.
  double nearest[16];
  int index[16];
  for (int i = 0; i < 16; ++i) {
    nearest[i] = kInfinity;
    index[i] = -1;
  }
  // plane_distance() (analytic_shapes.cpp) from t_min = 0 to the nearest plane so far, without its
  // branches, so that the sixteen lanes go two to an instruction. Its sign test only spares a
  // division: t > 0 holds exactly when numerator and denominator have one strict sign and the
  // quotient did not underflow, and a zero denominator gives an infinite or NaN t, which
  // fails t > 0 or t < nearest. So each lane gets plane_distance()'s very answer, the first
  // of equally near planes included.
  for (std::size_t p = 0; p < set.planes.size(); ++p) {
    const PreparedPlane& candidate = set.planes[p];
    for (int i = 0; i < 16; ++i) {
      const double t_plane = plane_quotient(candidate, rays.org_x[i], rays.org_y[i], rays.org_z[i],
                                            rays.dir_x[i], rays.dir_y[i], rays.dir_z[i]);
      const bool nearer = (valid[i] == -1) & (t_plane > 0.0) & (t_plane < nearest[i]);
      nearest[i] = nearer ? t_plane : nearest[i];
      index[i] = nearer ? static_cast<int>(p) : index[i];
    }
  }
  std::copy(nearest, nearest + 16, t);
  std::copy(index, index + 16, plane);
}

}  // namespace

void planes_occlude(const PlaneSet& set, const RTCRay16& rays, const int (&valid)[16],
                    bool (&blocked)[16]) {
  // Some plane lies between 0 and tfar exactly when the nearest one does.
  double t[16];
  int plane[16];
  nearest_of_planes(set, rays, valid, t, plane);
  for (int i = 0; i < 16; ++i) blocked[i] = (plane[i] >= 0) & (t[i] < rays.tfar[i]);
}

void nearest_planes(const PlaneSet& set, const RTCRayHit16& rayhit, const int (&valid)[16],
                    double (&t)[16], int (&plane)[16]) {
  nearest_of_planes(set, rayhit.ray, valid, t, plane);
}

int nearest_plane(const PlaneSet& set, const glm::vec3& origin, const glm::vec3& direction,
                  double& t) {
  // nearest_of_planes() for one lane.
  double nearest = kInfinity;
  int index = -1;
  for (std::size_t p = 0; p < set.planes.size(); ++p) {
    const double t_plane = plane_quotient(set.planes[p], origin.x, origin.y, origin.z, direction.x,
                                          direction.y, direction.z);
    if ((t_plane > 0.0) & (t_plane < nearest)) {
      nearest = t_plane;
      index = static_cast<int>(p);
    }
  }
  t = nearest;
  return index;
}

}  // namespace tessera
