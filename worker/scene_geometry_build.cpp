// Building SceneGeometry: each object of the scene prepared for its exact test and
// registered with Embree, and the BVH committed.
#include "worker/scene_geometry.hpp"

#include <cmath>
#include <cstring>
#include <stdexcept>

#include "worker/analytic_shapes.hpp"
#include "worker/triangulate.hpp"

namespace tessera {

SceneGeometry::SceneGeometry(const Scene& scene, const EmbreeDevice& device,
                             OpaquePlanes opaque_planes, std::size_t compact_above, Scene* release)
    : device_(device), scene_(device) {
  for (std::uint32_t i = 0; i < scene.objects.size(); ++i) {
    const Object& object = scene.objects[i];
    const bool transmissive = transmits(scene.materials[object.material]);
    const unsigned mask = transmissive ? kTransmissiveMask : kOpaqueSolidMask;
    std::visit(
        [&](const auto& shape) {
          using T = std::decay_t<decltype(shape)>;
          if constexpr (std::is_same_v<T, Sphere>)
            add_sphere(shape, object.transform, i, mask);
          else if constexpr (std::is_same_v<T, Box>)
            add_box(shape, object.transform, i, mask);
          else if constexpr (std::is_same_v<T, Plane>)
            add_plane(shape, object.transform, i, transmissive);
          else if constexpr (std::is_same_v<T, Cylinder>)
            add_cylinder(shape, object.transform, i, mask);
          else if constexpr (std::is_same_v<T, Cone>)
            add_cone(shape, object.transform, i, mask);
          else
            add_triangles(triangles_of(shape), object.transform, i, mask, compact_above);
        },
        object.shape);
    if (release != nullptr && !scene.materials[object.material].textured()) {
      if (auto* mesh = std::get_if<Mesh>(&release->objects[i].shape)) {
        std::vector<Vec3>().swap(mesh->positions);
        std::vector<std::array<std::uint32_t, 3>>().swap(mesh->triangles);
        std::vector<Vec3>().swap(mesh->normals);
        std::vector<Uv>().swap(mesh->uvs);
      }
    }
    convex_.push_back(std::holds_alternative<Sphere>(object.shape) ||
                      std::holds_alternative<Box>(object.shape) ||
                      std::holds_alternative<Cylinder>(object.shape) ||
                      std::holds_alternative<Cone>(object.shape));
    if (transmissive) {
      // A plane has no record yet (the plane sets are added last), and no bounds anyway.
      const bool plane = std::holds_alternative<Plane>(object.shape);
      const auto [lo, hi] = plane ? std::pair(glm::vec3(-kInfinity), glm::vec3(kInfinity))
                                  : geometry_bounds(records_.back());
      transmissive_bounds_.push_back({lo, hi, i});
    }
  }
  // Every shadow ray that may reach a transmissive surface tests each box: past a few, one
  // box around them all keeps that to one test.
  if (transmissive_bounds_.size() > kListedTransmissive) {
    TransmissiveBounds all{glm::vec3(kInfinity), glm::vec3(-kInfinity), kNoObject};
    for (const TransmissiveBounds& box : transmissive_bounds_) {
      all.lo = glm::min(all.lo, box.lo);
      all.hi = glm::max(all.hi, box.hi);
    }
    transmissive_bounds_.assign(1, all);
  }
  if (!plane_sets_[1].planes.empty()) add_analytic_shape(Kind::plane, 1, 0, kTransmissiveMask);
  if (!plane_sets_[0].planes.empty()) {
    opaque_planes_geometry_ = static_cast<unsigned>(records_.size());
    if (opaque_planes == OpaquePlanes::also_in_embree)
      add_analytic_shape(Kind::plane, 0, 0, kOpaquePlaneMask);
    else
      records_.push_back({Kind::plane, 0, 0});
  }
  // Robust traversal closes the hairline cracks between neighbouring mesh triangles.
  rtcSetSceneFlags(scene_.get(), RTC_SCENE_FLAG_ROBUST);
  rtcCommitScene(scene_.get());
  device_.check("building the scene's BVH");
}

void SceneGeometry::add_analytic_shape(Kind kind, std::uint32_t index, std::uint32_t object,
                                       unsigned mask) {
  RTCGeometry geometry = rtcNewGeometry(device_.get(), RTC_GEOMETRY_TYPE_USER);
  rtcSetGeometryUserPrimitiveCount(geometry, 1);
  rtcSetGeometryMask(geometry, mask);
  if (kind == Kind::sphere) {
    rtcSetGeometryUserData(geometry, spheres_[index].get());
    set_sphere_callbacks(geometry);
  } else if (kind == Kind::box) {
    rtcSetGeometryUserData(geometry, boxes_[index].get());
    set_box_callbacks(geometry);
  } else if (kind == Kind::cylinder) {
    rtcSetGeometryUserData(geometry, cylinders_[index].get());
    set_cylinder_callbacks(geometry);
  } else if (kind == Kind::cone) {
    rtcSetGeometryUserData(geometry, cones_[index].get());
    set_cone_callbacks(geometry);
  } else {
    rtcSetGeometryUserData(geometry, &plane_sets_[index]);
    set_plane_callbacks(geometry);
  }
  rtcCommitGeometry(geometry);
  const unsigned id = rtcAttachGeometry(scene_.get(), geometry);
  rtcReleaseGeometry(geometry);
  device_.check("adding a user geometry");
  if (id != records_.size()) throw std::logic_error("Embree geometry ids are not sequential");
  records_.push_back({kind, index, object});
}

void SceneGeometry::add_sphere(const Sphere& sphere, const Mat4& transform, std::uint32_t object,
                               unsigned mask) {
  auto prepared = std::make_unique<PreparedSphere>();
  prepared->center = sphere.center;
  prepared->radius = sphere.radius;
  prepared->object_to_world = transform;
  prepared->world_to_object = glm::inverse(transform);
  // A similarity has orthogonal columns of one common length: MᵀM = s²·I.
  const glm::dmat3 linear(transform);
  const glm::dmat3 gram = glm::transpose(linear) * linear;
  const double scale2 = (gram[0][0] + gram[1][1] + gram[2][2]) / 3.0;
  bool similarity = scale2 > 0.0;
  for (int i = 0; i < 3 && similarity; ++i)
    for (int j = 0; j < 3; ++j)
      similarity = similarity && std::fabs(gram[i][j] - (i == j ? scale2 : 0.0)) <= 1e-12 * scale2;
  if (similarity) {
    prepared->world_sphere = true;
    prepared->world_center = Vec3(transform * glm::dvec4(sphere.center, 1.0));
    prepared->world_radius = sphere.radius * std::sqrt(scale2);
  }
  spheres_.push_back(std::move(prepared));
  add_analytic_shape(Kind::sphere, static_cast<std::uint32_t>(spheres_.size() - 1), object, mask);
}

void SceneGeometry::add_box(const Box& box, const Mat4& transform, std::uint32_t object,
                            unsigned mask) {
  auto prepared = std::make_unique<PreparedBox>();
  prepared->object_to_world = transform;
  prepared->world_to_object = glm::inverse(transform);
  const glm::dmat3 linear(transform);
  bool along_axes = true;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) along_axes = along_axes && (i == j || linear[i][j] == 0.0);
  if (along_axes) {
    // A scale along the axes, negative ones included, keeps the box axis-aligned.
    const Vec3 a(transform * glm::dvec4(box.min, 1.0));
    const Vec3 b(transform * glm::dvec4(box.max, 1.0));
    prepared->world_box = true;
    prepared->lo = glm::min(a, b);
    prepared->hi = glm::max(a, b);
    for (int face = 0; face < 6; ++face) {
      Vec3 n(0.0);
      n[face / 2] = face % 2 == 1 ? 1.0 : -1.0;
      prepared->face_normals[face] = n;
    }
  } else {
    prepared->lo = box.min;
    prepared->hi = box.max;
    // Normals go through the inverse transpose, which keeps an outward normal outward even
    // under a mirroring transform.
    const glm::dmat3 normal_matrix = glm::transpose(glm::inverse(linear));
    for (int face = 0; face < 6; ++face) {
      Vec3 n(0.0);
      n[face / 2] = face % 2 == 1 ? 1.0 : -1.0;
      prepared->face_normals[face] = glm::normalize(normal_matrix * n);
    }
  }
  boxes_.push_back(std::move(prepared));
  add_analytic_shape(Kind::box, static_cast<std::uint32_t>(boxes_.size() - 1), object, mask);
}

void SceneGeometry::add_cylinder(const Cylinder& cylinder, const Mat4& transform,
                                 std::uint32_t object, unsigned mask) {
  auto prepared = std::make_unique<PreparedCylinder>();
  prepared->center = cylinder.center;
  prepared->radius = cylinder.radius;
  prepared->half_height = cylinder.height / 2.0;
  prepared->object_to_world = transform;
  prepared->world_to_object = glm::inverse(transform);
  // The inverse transpose keeps an outward normal outward even under a mirroring transform.
  prepared->normal_matrix = glm::transpose(glm::dmat3(prepared->world_to_object));
  cylinders_.push_back(std::move(prepared));
  add_analytic_shape(Kind::cylinder, static_cast<std::uint32_t>(cylinders_.size() - 1), object,
                     mask);
}

void SceneGeometry::add_cone(const Cone& cone, const Mat4& transform, std::uint32_t object,
                             unsigned mask) {
  auto prepared = std::make_unique<PreparedCone>();
  prepared->apex = cone.center + Vec3(0.0, cone.height / 2.0, 0.0);
  prepared->radius = cone.radius;
  prepared->height = cone.height;
  const double slope = cone.radius / cone.height;
  prepared->slope2 = slope * slope;
  prepared->slant = std::sqrt(cone.radius * cone.radius + cone.height * cone.height);
  prepared->object_to_world = transform;
  prepared->world_to_object = glm::inverse(transform);
  prepared->normal_matrix = glm::transpose(glm::dmat3(prepared->world_to_object));
  cones_.push_back(std::move(prepared));
  add_analytic_shape(Kind::cone, static_cast<std::uint32_t>(cones_.size() - 1), object, mask);
}

void SceneGeometry::add_plane(const Plane& plane, const Mat4& transform, std::uint32_t object,
                              bool transmissive) {
  const glm::dmat3 normal_matrix = glm::transpose(glm::inverse(glm::dmat3(transform)));
  const Vec3 point(transform * glm::dvec4(plane.point, 1.0));
  const Vec3 normal = glm::normalize(normal_matrix * plane.normal);
  PlaneSet& set = plane_sets_[transmissive ? 1 : 0];
  set.planes.push_back(PreparedPlane{point, normal, glm::dot(normal, point)});
  set.objects.push_back(object);
}

void SceneGeometry::add_triangles(const ObjectTriangles& triangles, const Mat4& transform,
                                  std::uint32_t object, unsigned mask, std::size_t compact_above) {
  RTCGeometry geometry = rtcNewGeometry(device_.get(), RTC_GEOMETRY_TYPE_TRIANGLE);
  rtcSetGeometryMask(geometry, mask);
  const std::size_t vertex_count = triangles.positions.size();
  const std::size_t triangle_count = triangles.triangles.size();
  auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(
      geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), vertex_count));
  auto* indices = static_cast<std::uint32_t*>(
      rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                              3 * sizeof(std::uint32_t), triangle_count));
  device_.check("allocating a triangle mesh");
  // Each point in world space in double, then rounded once to the floats Embree intersects.
  for (std::size_t i = 0; i < vertex_count; ++i) {
    const Vec3 p(transform * glm::dvec4(triangles.positions[i], 1.0));
    for (int k = 0; k < 3; ++k) vertices[3 * i + k] = static_cast<float>(p[k]);
  }
  // A mirroring transform turns counter-clockwise into clockwise: two corners trade places.
  const glm::dmat3 linear(transform);
  const bool mirrors = glm::determinant(linear) < 0.0;
  for (std::size_t t = 0; t < triangle_count; ++t) {
    const auto& tri = triangles.triangles[t];
    indices[3 * t] = tri[0];
    indices[3 * t + 1] = mirrors ? tri[2] : tri[1];
    indices[3 * t + 2] = mirrors ? tri[1] : tri[2];
  }
  std::vector<glm::vec3> normals;
  if (!triangles.normals.empty()) {
    const glm::dmat3 normal_matrix = glm::transpose(glm::inverse(linear));
    normals.reserve(vertex_count);
    for (const Vec3& n : triangles.normals) normals.emplace_back(glm::normalize(normal_matrix * n));
  }
  rtcCommitGeometry(geometry);
  const unsigned id = rtcAttachGeometry(scene_.get(), geometry);
  rtcReleaseGeometry(geometry);  // the scene holds it, and so its buffers, from here on
  device_.check("adding a triangle mesh");
  if (id != records_.size()) throw std::logic_error("Embree geometry ids are not sequential");

  TriangleMesh mesh;
  mesh.triangle_count = triangle_count;
  const auto corner = [&](std::size_t t, int k) {
    const float* p = vertices + 3 * static_cast<std::size_t>(indices[3 * t + k]);
    return glm::vec3(p[0], p[1], p[2]);
  };
  if (triangle_count > compact_above) {
    mesh.vertices = vertices;
    mesh.indices = indices;
    mesh.vertex_normals = std::move(normals);
  } else {
    mesh.triangles.resize(triangle_count);
    if (!normals.empty()) mesh.normals.resize(triangle_count);
    for (std::size_t t = 0; t < triangle_count; ++t) {
      for (int k = 0; k < 3; ++k) mesh.triangles[t].corners[k] = corner(t, k);
      if (normals.empty()) continue;
      for (int k = 0; k < 3; ++k) mesh.normals[t].corners[k] = normals[indices[3 * t + k]];
    }
    // From the stored floats, in a pass of its own: in the loop above, GCC 12's vectoriser
    // was seen to use the doubles the floats were rounded from (a different normal, and
    // other pixels, than finish_hit() computed from the floats).
    for (MeshTriangle& triangle : mesh.triangles)
      triangle.normal =
          triangle_normal(triangle.corners[0], triangle.corners[1], triangle.corners[2]);
  }
  meshes_.push_back(std::move(mesh));
  records_.push_back({Kind::triangles, static_cast<std::uint32_t>(meshes_.size() - 1), object});
}

std::pair<glm::vec3, glm::vec3> SceneGeometry::geometry_bounds(const GeometryRecord& record) const {
  if (record.kind != Kind::triangles) {
    RTCBounds bounds{};
    RTCBoundsFunctionArguments args{};
    args.bounds_o = &bounds;
    if (record.kind == Kind::sphere) {
      args.geometryUserPtr = spheres_[record.index].get();
      sphere_bounds(&args);
    } else if (record.kind == Kind::box) {
      args.geometryUserPtr = boxes_[record.index].get();
      box_bounds(&args);
    } else if (record.kind == Kind::cylinder) {
      args.geometryUserPtr = cylinders_[record.index].get();
      cylinder_bounds(&args);
    } else {
      args.geometryUserPtr = cones_[record.index].get();
      cone_bounds(&args);
    }
    return {{bounds.lower_x, bounds.lower_y, bounds.lower_z},
            {bounds.upper_x, bounds.upper_y, bounds.upper_z}};
  }
  // A mesh: its corners are floats already, so their extremes bound it exactly.
  glm::vec3 lo(kInfinity);
  glm::vec3 hi(-kInfinity);
  const TriangleMesh& mesh = meshes_[record.index];
  for (std::size_t t = 0; t < mesh.triangle_count; ++t) {
    glm::vec3 corners[3];
    mesh_corners(mesh, t, corners);
    for (const glm::vec3& p : corners) {
      lo = glm::min(lo, p);
      hi = glm::max(hi, p);
    }
  }
  return {lo, hi};
}

}  // namespace tessera
