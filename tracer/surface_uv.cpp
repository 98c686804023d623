#include "tracer/surface_uv.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace tessera {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

// atan2 from products, sums and one division, so that a texture coordinate has the same
// bits on every CPU: glibc's atan2 takes an FMA path on CPUs that have one. Good to about
// 1e-14 radians: the angle is brought into [0, π/8] (by octant, then by atan t = π/4 +
// atan((t - 1)/(t + 1))), where sixteen terms of the series suffice.
double portable_atan2(double y, double x) {
  const double ax = std::fabs(x);
  const double ay = std::fabs(y);
  if (ax == 0.0 && ay == 0.0) return 0.0;
  const bool steep = ay > ax;
  double t = steep ? ax / ay : ay / ax;  // in [0, 1]
  constexpr double kTanPiOver8 = 0.41421356237309503;
  const bool shifted = t > kTanPiOver8;
  if (shifted) t = (t - 1.0) / (t + 1.0);
  const double t2 = t * t;
  double sum = 0.0;
  for (int k = 15; k >= 0; --k) sum = (k % 2 == 0 ? 1.0 : -1.0) / (2 * k + 1) + t2 * sum;
  double angle = t * sum;
  if (shifted) angle += std::numbers::pi / 4;
  if (steep) angle = std::numbers::pi / 2 - angle;
  if (x < 0.0) angle = std::numbers::pi - angle;
  return y < 0.0 ? -angle : angle;
}

// Longitude around the y axis, 0.5 facing +z and growing towards +x, as a fraction of a
// turn; and how a point at (x, z) moves with it.
double longitude(const Vec3& p) { return 0.5 + portable_atan2(p.x, p.z) / kTwoPi; }
Vec3 along_longitude(const Vec3& p) { return kTwoPi * Vec3(p.z, 0.0, -p.x); }

SurfaceUv on_sphere(const Sphere& sphere, const Vec3& p) {
  const Vec3 q = (p - sphere.center) / sphere.radius;
  // sin φ and cos φ of the longitude are ux and uz.
  double across, sin_phi, cos_phi;
  geometry_detail::across_axis(q, across, sin_phi, cos_phi);
  const double latitude = portable_atan2(q.y, across);  // -π/2 at the south pole
  // At longitude φ = 2π(u - 0.5) and latitude λ = π(v - 0.5),
  // q = (cos λ sin φ, sin λ, cos λ cos φ); the sines and cosines are ratios of q's.
  const double length = std::sqrt(across * across + q.y * q.y);
  const double sin_lat = q.y / length;
  const double cos_lat = across / length;
  const Vec3 dpdv =
      sphere.radius * std::numbers::pi * Vec3(-sin_lat * sin_phi, cos_lat, -sin_lat * cos_phi);
  return {
      {longitude(q), 0.5 + latitude / std::numbers::pi}, sphere.radius * along_longitude(q), dpdv};
}

SurfaceUv on_plane(const Plane& plane, const Vec3& p) {
  // u along the world's x on floors and ceilings, and across walls; v along -z on floors,
  // up on walls.
  const Vec3 reference =
      std::fabs(plane.normal.y) < 0.9 ? Vec3(0.0, 1.0, 0.0) : Vec3(0.0, 0.0, -1.0);
  const Vec3 u_axis = glm::normalize(glm::cross(reference, plane.normal));
  const Vec3 v_axis = glm::cross(plane.normal, u_axis);
  const Vec3 offset = p - plane.point;
  return {
      {glm::dot(offset, u_axis) / plane.uv_scale.x, glm::dot(offset, v_axis) / plane.uv_scale.y},
      u_axis * plane.uv_scale.x,
      v_axis * plane.uv_scale.y};
}

SurfaceUv on_box(const Box& box, unsigned face, const Vec3& p) {
  // Each face's u and v axes, so that every face reads the right way round from outside:
  // for faces 0-5 (-x, +x, -y, +y, -z, +z), the axis of u and of v, each with its sign.
  struct FaceAxes {
    int u_axis, u_sign, v_axis, v_sign;
  };
  static constexpr FaceAxes axes[6] = {{2, 1, 1, 1},  {2, -1, 1, 1}, {0, 1, 2, 1},
                                       {0, 1, 2, -1}, {0, -1, 1, 1}, {0, 1, 1, 1}};
  const FaceAxes& f = axes[std::min(face, 5u)];
  const auto coordinate = [&](int axis, int sign) {
    const double t = (p[axis] - box.min[axis]) / (box.max[axis] - box.min[axis]);
    return sign > 0 ? t : 1.0 - t;
  };
  Vec3 dpdu(0.0);
  Vec3 dpdv(0.0);
  dpdu[f.u_axis] = f.u_sign * (box.max[f.u_axis] - box.min[f.u_axis]);
  dpdv[f.v_axis] = f.v_sign * (box.max[f.v_axis] - box.min[f.v_axis]);
  return {{coordinate(f.u_axis, f.u_sign), coordinate(f.v_axis, f.v_sign)}, dpdu, dpdv};
}

// A flat cap of radius r, seen from outside: u along x; v along -z on a top cap, +z on a base.
SurfaceUv on_cap(const Vec3& q, double radius, bool top) {
  const double side = top ? -1.0 : 1.0;
  return {{0.5 + q.x / (2.0 * radius), 0.5 + side * q.z / (2.0 * radius)},
          Vec3(2.0 * radius, 0.0, 0.0),
          Vec3(0.0, 0.0, side * 2.0 * radius)};
}

SurfaceUv on_cylinder(const Cylinder& cylinder, unsigned part, const Vec3& p) {
  const Vec3 q = p - cylinder.center;
  if (part != kSide) return on_cap(q, cylinder.radius, part == kTopCap);
  return {{longitude(q), q.y / cylinder.height + 0.5},
          along_longitude(q),
          Vec3(0.0, cylinder.height, 0.0)};
}

SurfaceUv on_cone(const Cone& cone, unsigned part, const Vec3& p) {
  const Vec3 q = p - cone.center;  // the apex is at height/2, the base at -height/2
  if (part != kSide) return on_cap(q, cone.radius, false);
  double across, sin_phi, cos_phi;
  geometry_detail::across_axis(q, across, sin_phi, cos_phi);
  return {{longitude(q), q.y / cone.height + 0.5},
          along_longitude(q),
          Vec3(-cone.radius * sin_phi, cone.height, -cone.radius * cos_phi)};
}

// A triangle's uv from its corners' by the hit's barycentric coordinates, which are found
// from the point itself; and the point's motion with u and v, the inverse of the uvs' map.
SurfaceUv on_triangle(const std::array<Vec3, 3>& corners, const std::array<Uv, 3>& uvs,
                      const Vec3& p) {
  const Vec3 e1 = corners[1] - corners[0];
  const Vec3 e2 = corners[2] - corners[0];
  const Vec3 to_p = p - corners[0];
  const double d11 = glm::dot(e1, e1);
  const double d12 = glm::dot(e1, e2);
  const double d22 = glm::dot(e2, e2);
  const double dp1 = glm::dot(to_p, e1);
  const double dp2 = glm::dot(to_p, e2);
  const double det = d11 * d22 - d12 * d12;
  const double b1 = det != 0.0 ? (d22 * dp1 - d12 * dp2) / det : 0.0;
  const double b2 = det != 0.0 ? (d11 * dp2 - d12 * dp1) / det : 0.0;
  const glm::dvec2 uv0(uvs[0]);
  const glm::dvec2 duv1 = glm::dvec2(uvs[1]) - uv0;
  const glm::dvec2 duv2 = glm::dvec2(uvs[2]) - uv0;
  SurfaceUv out{uv0 + b1 * duv1 + b2 * duv2, Vec3(0.0), Vec3(0.0)};
  const double uv_det = duv1.x * duv2.y - duv2.x * duv1.y;
  if (uv_det != 0.0) {
    out.dpdu = (duv2.y * e1 - duv1.y * e2) / uv_det;
    out.dpdv = (duv1.x * e2 - duv2.x * e1) / uv_det;
  }
  return out;
}

constexpr std::array<Uv, 3> kDefaultUvs{Uv(0.0f, 0.0f), Uv(1.0f, 0.0f), Uv(0.0f, 1.0f)};

}  // namespace

SurfaceUv surface_uv(const Object& object, const Mat4& world_to_object, const SurfaceHit& hit) {
  const Mat4& to_world = object.transform;
  const glm::dmat3 linear(to_world);
  if (const auto* mesh = std::get_if<Mesh>(&object.shape)) {
    // In world space, where the hit point is exact.
    const auto& t = mesh->triangles[hit.primitive];
    std::array<Vec3, 3> corners;
    std::array<Uv, 3> uvs = kDefaultUvs;
    for (int k = 0; k < 3; ++k) {
      corners[k] = Vec3(to_world * glm::dvec4(mesh->positions[t[k]], 1.0));
      if (!mesh->uvs.empty()) uvs[k] = mesh->uvs[t[k]];
    }
    return on_triangle(corners, uvs, hit.position);
  }
  if (const auto* triangle = std::get_if<Triangle>(&object.shape)) {
    std::array<Vec3, 3> corners;
    for (int k = 0; k < 3; ++k)
      corners[k] = Vec3(to_world * glm::dvec4(triangle->vertices[k], 1.0));
    return on_triangle(corners, triangle->uvs.value_or(kDefaultUvs), hit.position);
  }
  const Vec3 p(world_to_object * glm::dvec4(hit.position, 1.0));
  SurfaceUv local = std::visit(
      [&](const auto& shape) -> SurfaceUv {
        using T = std::decay_t<decltype(shape)>;
        if constexpr (std::is_same_v<T, Sphere>) return on_sphere(shape, p);
        if constexpr (std::is_same_v<T, Plane>) return on_plane(shape, p);
        if constexpr (std::is_same_v<T, Box>) return on_box(shape, hit.primitive, p);
        if constexpr (std::is_same_v<T, Cylinder>) return on_cylinder(shape, hit.primitive, p);
        if constexpr (std::is_same_v<T, Cone>) return on_cone(shape, hit.primitive, p);
        return {glm::dvec2(0.0), Vec3(0.0), Vec3(0.0)};
      },
      object.shape);
  local.dpdu = linear * local.dpdu;
  local.dpdv = linear * local.dpdv;
  return local;
}

}  // namespace tessera
