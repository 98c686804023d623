// The analytic shapes (spheres, boxes, planes, cylinders and cones), which Embree traces
// through callbacks as user geometry: their bounds, and their exact intersections.
#pragma once

#include <embree3/rtcore.h>
#include <glm/vec3.hpp>

namespace tessera {

// Install bounds, intersect and occluded callbacks; the geometry's user pointer must be a
// PreparedSphere, a PreparedBox, a PlaneSet, a PreparedCylinder or a PreparedCone
// respectively.
void set_sphere_callbacks(RTCGeometry geometry);
void set_box_callbacks(RTCGeometry geometry);
void set_plane_callbacks(RTCGeometry geometry);
void set_cylinder_callbacks(RTCGeometry geometry);
void set_cone_callbacks(RTCGeometry geometry);

// The bounds Embree is given for a sphere, a box, a cylinder or a cone: its args' user
// pointer is a PreparedSphere, a PreparedBox, a PreparedCylinder or a PreparedCone.
void sphere_bounds(const RTCBoundsFunctionArguments* args);
void box_bounds(const RTCBoundsFunctionArguments* args);
void cylinder_bounds(const RTCBoundsFunctionArguments* args);
void cone_bounds(const RTCBoundsFunctionArguments* args);

struct PlaneSet;
// Which of the lanes with valid[i] == -1 one of the planes blocks between 0 and tfar (the
// rays must start at tnear = 0, as packets here do): the answer the plane set's occluded
// callback would give.
void planes_occlude(const PlaneSet& set, const RTCRay16& rays, const int (&valid)[16],
                    bool (&blocked)[16]);
// The nearest of the planes, if any, on each lane with valid[i] == -1 of a packet with
// unbounded rays: the distance and the plane's index in the set (-1 and infinity where
// none), as the plane set's intersect callback would find them.
void nearest_planes(const PlaneSet& set, const RTCRayHit16& rayhit, const int (&valid)[16],
                    double (&t)[16], int (&plane)[16]);
// The same for one ray: the plane's index (-1 if none) and its distance in `t`.
int nearest_plane(const PlaneSet& set, const glm::vec3& origin, const glm::vec3& direction,
                  double& t);

}  // namespace tessera
