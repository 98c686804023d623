// The scene's shapes in world space, registered with Embree. Embree finds which
// primitive a ray hits; the hit itself (distance, point, normals) is then recomputed here
// in double precision from the ray's floats, so that it is exact enough for secondary
// rays and identical on every CPU whatever SIMD path Embree used.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <vector>

#include "common/scene.hpp"
#include "worker/embree_device.hpp"
#include "worker/ray.hpp"

namespace tessera {

struct SurfaceHit {
  double t = 0.0;
  Vec3 position{0.0};
  Vec3 normal{0.0};          // geometric, unit: outward for solids, as built for thin shapes
  Vec3 shading_normal{0.0};  // unit; interpolated on smooth meshes, else `normal`
  std::uint32_t object = 0;  // index into Scene::objects
};

// An ellipsoid: the object-space sphere seen through its object-to-world transform.
struct PreparedSphere {
  Vec3 center{0.0};  // object space
  double radius = 1.0;
  Mat4 object_to_world{1.0};
  Mat4 world_to_object{1.0};
};

struct PreparedPlane {
  Vec3 point{0.0};   // world space
  Vec3 normal{0.0};  // world space, unit
};

struct PreparedTriangles {
  std::vector<Vec3> positions;                          // world space
  std::vector<std::array<std::uint32_t, 3>> triangles;  // counter-clockwise seen from outside
  std::vector<Vec3> normals;                            // world space, unit; may be empty
};

std::optional<double> intersect_sphere(const PreparedSphere& sphere, const glm::vec3& origin,
                                       const glm::vec3& direction, double t_min, double t_max);
std::optional<double> intersect_plane(const PreparedPlane& plane, const glm::vec3& origin,
                                      const glm::vec3& direction, double t_min, double t_max);

class SceneGeometry {
 public:
  SceneGeometry(const Scene& scene, const EmbreeDevice& device);

  // The closest hit with 0 < t < t_max, if any.
  std::optional<SurfaceHit> intersect(const Ray& ray, float t_max) const;
  // Whether anything lies on the ray with 0 < t < t_max.
  bool occluded(const Ray& ray, float t_max) const;

 private:
  enum class Kind : std::uint8_t { sphere, plane, triangles };
  struct GeometryRecord {
    Kind kind;
    std::uint32_t index;   // into the vector of its kind
    std::uint32_t object;  // into Scene::objects
  };

  void add_sphere(const Sphere& sphere, const Mat4& transform, std::uint32_t object);
  void add_plane(const Plane& plane, const Mat4& transform, std::uint32_t object);
  void add_triangles(PreparedTriangles triangles, std::uint32_t object);
  void add_user_geometry(Kind kind, std::uint32_t index, std::uint32_t object);
  SurfaceHit finish_hit(const Ray& ray, const RTCRayHit& rayhit) const;

  const EmbreeDevice& device_;
  EmbreeScene scene_;
  std::vector<GeometryRecord> records_;  // by Embree geometry id
  // Kept at stable addresses: Embree's callbacks hold pointers to these elements.
  std::vector<std::unique_ptr<PreparedSphere>> spheres_;
  std::vector<std::unique_ptr<PreparedPlane>> planes_;
  std::vector<PreparedTriangles> triangle_sets_;
};

}  // namespace tessera
