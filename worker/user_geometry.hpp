#pragma once

#include <embree3/rtcore.h>

namespace tessera {

// Install bounds, intersect and occluded callbacks; the geometry's user pointer must be a
// PreparedSphere or a PlaneSet respectively.
void set_sphere_callbacks(RTCGeometry geometry);
void set_plane_callbacks(RTCGeometry geometry);

// The box Embree is given for a sphere: its args' user pointer is a PreparedSphere.
void sphere_bounds(const RTCBoundsFunctionArguments* args);

}  // namespace tessera
