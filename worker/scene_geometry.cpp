#include "worker/scene_geometry.hpp"

#include <cstring>
#include <stdexcept>

#include "worker/triangulate.hpp"
#include "worker/user_geometry.hpp"

namespace tessera {
namespace {

struct TriangleHit {
  double t, u, v;
};

// Möller–Trumbore in double: recomputes the hit Embree found, from the ray's floats.
std::optional<TriangleHit> intersect_triangle(const Vec3& v0, const Vec3& v1, const Vec3& v2,
                                              const Ray& ray) {
  const Vec3 o(ray.origin);
  const Vec3 d(ray.direction);
  const Vec3 e1 = v1 - v0;
  const Vec3 e2 = v2 - v0;
  const Vec3 p = glm::cross(d, e2);
  const double det = glm::dot(e1, p);
  if (det == 0.0) return std::nullopt;
  const double inv = 1.0 / det;
  const Vec3 s = o - v0;
  const Vec3 q = glm::cross(s, e1);
  return TriangleHit{glm::dot(e2, q) * inv, glm::dot(s, p) * inv, glm::dot(d, q) * inv};
}

}  // namespace

SceneGeometry::SceneGeometry(const Scene& scene, const EmbreeDevice& device)
    : device_(device), scene_(device) {
  for (std::uint32_t i = 0; i < scene.objects.size(); ++i) {
    const Object& object = scene.objects[i];
    std::visit(
        [&](const auto& shape) {
          using T = std::decay_t<decltype(shape)>;
          if constexpr (std::is_same_v<T, Sphere>)
            add_sphere(shape, object.transform, i);
          else if constexpr (std::is_same_v<T, Plane>)
            add_plane(shape, object.transform, i);
          else
            add_triangles(triangulate(shape, object.transform), i);
        },
        object.shape);
  }
  // Robust traversal closes the hairline cracks between neighbouring mesh triangles.
  rtcSetSceneFlags(scene_.get(), RTC_SCENE_FLAG_ROBUST);
  rtcCommitScene(scene_.get());
  device_.check("building the scene's BVH");
}

void SceneGeometry::add_user_geometry(Kind kind, std::uint32_t index, std::uint32_t object) {
  RTCGeometry geometry = rtcNewGeometry(device_.get(), RTC_GEOMETRY_TYPE_USER);
  rtcSetGeometryUserPrimitiveCount(geometry, 1);
  if (kind == Kind::sphere) {
    rtcSetGeometryUserData(geometry, spheres_[index].get());
    set_sphere_callbacks(geometry);
  } else {
    rtcSetGeometryUserData(geometry, planes_[index].get());
    set_plane_callbacks(geometry);
  }
  rtcCommitGeometry(geometry);
  const unsigned id = rtcAttachGeometry(scene_.get(), geometry);
  rtcReleaseGeometry(geometry);
  device_.check("adding a user geometry");
  if (id != records_.size()) throw std::logic_error("Embree geometry ids are not sequential");
  records_.push_back({kind, index, object});
}

void SceneGeometry::add_sphere(const Sphere& sphere, const Mat4& transform, std::uint32_t object) {
  spheres_.push_back(std::make_unique<PreparedSphere>(
      PreparedSphere{sphere.center, sphere.radius, transform, glm::inverse(transform)}));
  add_user_geometry(Kind::sphere, static_cast<std::uint32_t>(spheres_.size() - 1), object);
}

void SceneGeometry::add_plane(const Plane& plane, const Mat4& transform, std::uint32_t object) {
  const glm::dmat3 normal_matrix = glm::transpose(glm::inverse(glm::dmat3(transform)));
  planes_.push_back(
      std::make_unique<PreparedPlane>(PreparedPlane{Vec3(transform * glm::dvec4(plane.point, 1.0)),
                                                    glm::normalize(normal_matrix * plane.normal)}));
  add_user_geometry(Kind::plane, static_cast<std::uint32_t>(planes_.size() - 1), object);
}

void SceneGeometry::add_triangles(PreparedTriangles triangles, std::uint32_t object) {
  RTCGeometry geometry = rtcNewGeometry(device_.get(), RTC_GEOMETRY_TYPE_TRIANGLE);
  auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0,
                                                               RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                                               triangles.positions.size()));
  auto* indices = static_cast<unsigned*>(
      rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                              3 * sizeof(unsigned), triangles.triangles.size()));
  device_.check("allocating a triangle mesh");
  for (std::size_t i = 0; i < triangles.positions.size(); ++i)
    for (int k = 0; k < 3; ++k) vertices[3 * i + k] = static_cast<float>(triangles.positions[i][k]);
  static_assert(sizeof(triangles.triangles[0]) == 3 * sizeof(unsigned));
  std::memcpy(indices, triangles.triangles.data(),
              triangles.triangles.size() * 3 * sizeof(unsigned));
  rtcCommitGeometry(geometry);
  const unsigned id = rtcAttachGeometry(scene_.get(), geometry);
  rtcReleaseGeometry(geometry);
  device_.check("adding a triangle mesh");
  if (id != records_.size()) throw std::logic_error("Embree geometry ids are not sequential");
  triangle_sets_.push_back(std::move(triangles));
  records_.push_back(
      {Kind::triangles, static_cast<std::uint32_t>(triangle_sets_.size() - 1), object});
}

std::optional<SurfaceHit> SceneGeometry::intersect(const Ray& ray, float t_max) const {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRayHit rayhit{};
  rayhit.ray.org_x = ray.origin.x;
  rayhit.ray.org_y = ray.origin.y;
  rayhit.ray.org_z = ray.origin.z;
  rayhit.ray.dir_x = ray.direction.x;
  rayhit.ray.dir_y = ray.direction.y;
  rayhit.ray.dir_z = ray.direction.z;
  rayhit.ray.tnear = 0.0f;
  rayhit.ray.tfar = t_max;
  rayhit.ray.mask = ~0u;
  rayhit.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rayhit.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(scene_.get(), &context, &rayhit);
  if (rayhit.hit.geomID == RTC_INVALID_GEOMETRY_ID) return std::nullopt;
  return finish_hit(ray, rayhit);
}

bool SceneGeometry::occluded(const Ray& ray, float t_max) const {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRay r{};
  r.org_x = ray.origin.x;
  r.org_y = ray.origin.y;
  r.org_z = ray.origin.z;
  r.dir_x = ray.direction.x;
  r.dir_y = ray.direction.y;
  r.dir_z = ray.direction.z;
  r.tnear = 0.0f;
  r.tfar = t_max;
  r.mask = ~0u;
  rtcOccluded1(scene_.get(), &context, &r);
  return r.tfar < 0.0f;
}

SurfaceHit SceneGeometry::finish_hit(const Ray& ray, const RTCRayHit& rayhit) const {
  const GeometryRecord& record = records_[rayhit.hit.geomID];
  SurfaceHit hit;
  hit.object = record.object;
  const double inf = std::numeric_limits<double>::infinity();
  switch (record.kind) {
    case Kind::sphere: {
      const PreparedSphere& sphere = *spheres_[record.index];
      hit.t =
          intersect_sphere(sphere, ray.origin, ray.direction, 0.0, inf).value_or(rayhit.ray.tfar);
      const Vec3 o = Vec3(sphere.world_to_object * glm::dvec4(Vec3(ray.origin), 1.0));
      const Vec3 d = glm::dmat3(sphere.world_to_object) * Vec3(ray.direction);
      const Vec3 n = glm::normalize(o + hit.t * d - sphere.center);
      // Snapping the point onto the surface removes the error that o + t·d accumulates.
      hit.position =
          Vec3(sphere.object_to_world * glm::dvec4(sphere.center + sphere.radius * n, 1.0));
      hit.normal = glm::normalize(glm::transpose(glm::dmat3(sphere.world_to_object)) * n);
      hit.shading_normal = hit.normal;
      break;
    }
    case Kind::plane: {
      const PreparedPlane& plane = *planes_[record.index];
      hit.t = intersect_plane(plane, ray.origin, ray.direction, 0.0, inf).value_or(rayhit.ray.tfar);
      const Vec3 p = Vec3(ray.origin) + hit.t * Vec3(ray.direction);
      hit.position = p - glm::dot(p - plane.point, plane.normal) * plane.normal;
      hit.normal = plane.normal;
      hit.shading_normal = plane.normal;
      break;
    }
    case Kind::triangles: {
      const PreparedTriangles& set = triangle_sets_[record.index];
      const auto& tri = set.triangles[rayhit.hit.primID];
      const Vec3& v0 = set.positions[tri[0]];
      const Vec3& v1 = set.positions[tri[1]];
      const Vec3& v2 = set.positions[tri[2]];
      const TriangleHit th =
          intersect_triangle(v0, v1, v2, ray)
              .value_or(TriangleHit{rayhit.ray.tfar, rayhit.hit.u, rayhit.hit.v});
      hit.t = th.t;
      // Barycentric reconstruction keeps the point on the triangle's own plane.
      hit.position = (1.0 - th.u - th.v) * v0 + th.u * v1 + th.v * v2;
      hit.normal = glm::normalize(glm::cross(v1 - v0, v2 - v0));
      hit.shading_normal = hit.normal;
      if (!set.normals.empty()) {
        const Vec3 n = (1.0 - th.u - th.v) * set.normals[tri[0]] + th.u * set.normals[tri[1]] +
                       th.v * set.normals[tri[2]];
        if (glm::dot(n, n) > 0.0) hit.shading_normal = glm::normalize(n);
      }
      break;
    }
  }
  return hit;
}

}  // namespace tessera
