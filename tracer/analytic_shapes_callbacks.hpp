// What the analytic shapes' files share (analytic_shapes.cpp, analytic_shapes_quadrics.cpp):
// the rays Embree hands a callback, the callbacks themselves around each shape's test, and
// the bounds of a transformed box. Internal to the tracer.
#pragma once

#include <algorithm>
#include <cstddef>

#include <embree3/rtcore.h>

#include "tracer/scene_geometry.hpp"

namespace tessera::analytic_detail {

// Lanes base to end - 1 (at most 16) of the rays Embree handed over, each field's lanes as
// a plain array: Embree's accessors index in unsigned arithmetic, which GCC cannot prove
// free of wrap-around, and so does not vectorise.
struct Lanes {
  Lanes(const RTCRayN* ray, unsigned n, const int* valid, unsigned base, unsigned end)
      : count(end - base), valid(valid + base) {
    auto* rays = const_cast<RTCRayN*>(ray);  // the accessors take it non-const
    org_x = &RTCRayN_org_x(rays, n, base);
    org_y = &RTCRayN_org_y(rays, n, base);
    org_z = &RTCRayN_org_z(rays, n, base);
    dir_x = &RTCRayN_dir_x(rays, n, base);
    dir_y = &RTCRayN_dir_y(rays, n, base);
    dir_z = &RTCRayN_dir_z(rays, n, base);
    tnear = &RTCRayN_tnear(rays, n, base);
    tfar = &RTCRayN_tfar(rays, n, base);
  }

  std::size_t count;
  const int* valid;
  const float *org_x, *org_y, *org_z;
  const float *dir_x, *dir_y, *dir_z;
  const float *tnear, *tfar;
};

// A shape's test: the nearest hit on each valid lane with tnear < t < tfar, and which
// primitive of the geometry it is on; found[i] says whether t[i] and primitive[i] hold one.
template <typename Shape>
using Distances = void (*)(const Shape& shape, const Lanes& lanes, double (&t)[kPacketSize],
                           unsigned (&primitive)[kPacketSize], bool (&found)[kPacketSize]);

// Embree hands over up to 16 rays at once. The tests of all of them run first, in a loop of
// their own, so that their divisions and square roots overlap; the hits are recorded after.
template <typename Shape, Distances<Shape> distances>
void intersect_callback(const RTCIntersectFunctionNArguments* args) {
  const auto& shape = *static_cast<const Shape*>(args->geometryUserPtr);
  const unsigned n = args->N;
  RTCRayN* ray = RTCRayHitN_RayN(args->rayhit, n);
  RTCHitN* hit = RTCRayHitN_HitN(args->rayhit, n);
  auto* context = reinterpret_cast<HitContext*>(args->context);
  // Embree's packets hold at most 16 rays; chunks keep this right for any N all the same.
  for (unsigned base = 0; base < n; base += kPacketSize) {
    const unsigned end = std::min(n, base + kPacketSize);
    double t[kPacketSize];
    unsigned primitive[kPacketSize];
    bool found[kPacketSize];
    distances(shape, Lanes(ray, n, args->valid, base, end), t, primitive, found);
    for (unsigned i = base; i < end; ++i) {
      if (!found[i - base]) continue;
      RTCRayN_tfar(ray, n, i) = static_cast<float>(t[i - base]);
      context->t[RTCRayN_id(ray, n, i)] = t[i - base];
      RTCHitN_u(hit, n, i) = 0.0f;
      RTCHitN_v(hit, n, i) = 0.0f;
      RTCHitN_primID(hit, n, i) = primitive[i - base];
      RTCHitN_geomID(hit, n, i) = args->geomID;
      RTCHitN_instID(hit, n, i, 0) = args->context->instID[0];
    }
  }
}

template <typename Shape, Distances<Shape> distances>
void occluded_callback(const RTCOccludedFunctionNArguments* args) {
  const auto& shape = *static_cast<const Shape*>(args->geometryUserPtr);
  const unsigned n = args->N;
  for (unsigned base = 0; base < n; base += kPacketSize) {
    const unsigned end = std::min(n, base + kPacketSize);
    double t[kPacketSize];
    unsigned primitive[kPacketSize];
    bool found[kPacketSize];
    distances(shape, Lanes(args->ray, n, args->valid, base, end), t, primitive, found);
    for (unsigned i = base; i < end; ++i)
      if (found[i - base]) RTCRayN_tfar(args->ray, n, i) = -kInfinity;
  }
}

// Installs a shape's bounds, intersect and occluded callbacks; the geometry's user pointer
// must be a Shape.
template <typename Shape, Distances<Shape> distances>
void set_callbacks(RTCGeometry geometry, RTCBoundsFunction bounds) {
  rtcSetGeometryBoundsFunction(geometry, bounds, nullptr);
  rtcSetGeometryIntersectFunction(geometry, &intersect_callback<Shape, distances>);
  rtcSetGeometryOccludedFunction(geometry, &occluded_callback<Shape, distances>);
}

// Embree's box around the box from `lo` to `hi` seen through `transform`: the box around
// its transformed corners, widened so that rounding to float never cuts the surface off.
RTCBounds transformed_bounds(const Vec3& box_lo, const Vec3& box_hi, const Mat4& transform);

}  // namespace tessera::analytic_detail
