// Building SceneGeometry: each object of the scene prepared for its exact test and
// registered with Embree, and the BVH committed.
#include "tracer/scene_geometry.hpp"

#include <cmath>
#include <cstring>
#include <stdexcept>

#include "tracer/analytic_shapes.hpp"
#include "tracer/mesh_bvh.hpp"
#include "tracer/triangulate.hpp"

namespace tessera {

namespace {

// The float nearest `x` on its side: `below` for a lower bound.
float rounded_outward(double x, bool below) {
  const auto f = static_cast<float>(x);
  if (below ? static_cast<double>(f) > x : static_cast<double>(f) < x)
    return std::nextafter(f, below ? -kInfinity : kInfinity);
  return f;
}

}  // namespace

SceneGeometry::SceneGeometry(const Scene& scene, const EmbreeDevice& device,
                             OpaquePlanes opaque_planes, std::size_t compact_above, Scene* release,
                             const SceneGeometry* previous)
    : device_(device), scene_(device) {
  for (std::uint32_t i = 0; i < scene.objects.size(); ++i) {
    const Object& object = scene.objects[i];
    const bool transmissive = transmits(scene.materials[object.material]);
    const unsigned mask = transmissive ? kTransmissiveMask : kOpaqueSolidMask;
    // A mesh of its own BVH, placed: as the frame before built it, or built here. The frame
    // before's is kept even by a frame that does not place it, for the frames after.
    std::shared_ptr<const MeshBvh> own;
    if (previous != nullptr && i < previous->mesh_bvhs_.size()) own = previous->mesh_bvhs_[i];
    const auto* mesh = std::get_if<Mesh>(&object.shape);
    const bool placed = mesh != nullptr && object.transform != Mat4(1.0) &&
                        (own != nullptr || mesh->triangles.size() >= kInstancedMeshTriangles);
    if (placed && own == nullptr)
      own = std::make_shared<const MeshBvh>(device_, triangles_of(*mesh), compact_above);
    if (own != nullptr) {
      if (mesh_bvhs_.size() <= i) mesh_bvhs_.resize(i + 1);
      mesh_bvhs_[i] = own;
    }
    if (placed) {
      add_placed_mesh(std::move(own), object.transform, i, mask);
    } else {
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
    }
    // A later frame that builds its geometry again (its objects moved, or a material's
    // transmission is keyframed) reads the whole scene again (Animation::changes_objects()).
    if (release != nullptr && !scene.materials[object.material].textured()) {
      if (auto* released = std::get_if<Mesh>(&release->objects[i].shape)) {
        std::vector<Vec3>().swap(released->positions);
        std::vector<std::array<std::uint32_t, 3>>().swap(released->triangles);
        std::vector<Vec3>().swap(released->normals);
        std::vector<Uv>().swap(released->uvs);
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
  TriangleGeometry built = new_triangle_geometry(device_, triangles, transform, compact_above);
  rtcSetGeometryMask(built.geometry, mask);
  rtcCommitGeometry(built.geometry);
  const unsigned id = rtcAttachGeometry(scene_.get(), built.geometry);
  rtcReleaseGeometry(built.geometry);  // the scene holds it, and so its buffers, from here on
  device_.check("adding a triangle mesh");
  if (id != records_.size()) throw std::logic_error("Embree geometry ids are not sequential");
  meshes_.push_back(std::move(built.mesh));
  records_.push_back({Kind::triangles, static_cast<std::uint32_t>(meshes_.size() - 1), object});
}

void SceneGeometry::add_placed_mesh(std::shared_ptr<const MeshBvh> bvh, const Mat4& transform,
                                    std::uint32_t object, unsigned mask) {
  RTCGeometry instance = rtcNewGeometry(device_.get(), RTC_GEOMETRY_TYPE_INSTANCE);
  rtcSetGeometryInstancedScene(instance, bvh->scene());
  rtcSetGeometryTimeStepCount(instance, 1);
  // Embree finds which triangle a ray meets through the float transform; the hit itself is
  // rebuilt from the double one (finish_hit()).
  float columns[12];
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 3; ++r) columns[3 * c + r] = static_cast<float>(transform[c][r]);
  rtcSetGeometryTransform(instance, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, columns);
  rtcSetGeometryMask(instance, mask);
  rtcCommitGeometry(instance);
  const unsigned id = rtcAttachGeometry(scene_.get(), instance);
  rtcReleaseGeometry(instance);
  device_.check("placing a mesh");
  if (id != records_.size()) throw std::logic_error("Embree geometry ids are not sequential");

  PlacedMesh placed;
  placed.object_to_world = transform;
  placed.world_to_object = glm::inverse(transform);
  placed.normal_matrix = glm::transpose(glm::dmat3(placed.world_to_object));
  placed.bvh = bvh;
  placed_meshes_.push_back(std::move(placed));
  records_.push_back(
      {Kind::placed_mesh, static_cast<std::uint32_t>(placed_meshes_.size() - 1), object});
}

std::pair<glm::vec3, glm::vec3> SceneGeometry::geometry_bounds(const GeometryRecord& record) const {
  if (record.kind == Kind::placed_mesh) {
    // The box of the mesh's object-space box, its corners placed in double and then
    // rounded outwards.
    const PlacedMesh& placed = placed_meshes_[record.index];
    const glm::vec3& a = placed.bvh->lo();
    const glm::vec3& b = placed.bvh->hi();
    Vec3 lo(kInfinity);
    Vec3 hi(-kInfinity);
    for (int corner = 0; corner < 8; ++corner) {
      const Vec3 p((corner & 1) ? b.x : a.x, (corner & 2) ? b.y : a.y, (corner & 4) ? b.z : a.z);
      const Vec3 q(placed.object_to_world * glm::dvec4(p, 1.0));
      lo = glm::min(lo, q);
      hi = glm::max(hi, q);
    }
    glm::vec3 flo, fhi;
    for (int k = 0; k < 3; ++k) {
      flo[k] = rounded_outward(lo[k], true);
      fhi[k] = rounded_outward(hi[k], false);
    }
    return {flo, fhi};
  }
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
  return mesh_bounds(meshes_[record.index]);
}

}  // namespace tessera
