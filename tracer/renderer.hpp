// A scene made ready to render: Embree device and BVH built once, after which any
// rectangle of the image can be rendered, from any thread, in any order.
#pragma once

#include <memory>
#include <span>

#include "common/image/image.hpp"
#include "common/scene/scene.hpp"
#include "tracer/camera.hpp"
#include "tracer/embree_device.hpp"
#include "tracer/scene_geometry.hpp"
#include "tracer/scene_textures.hpp"
#include "tracer/tracer.hpp"

namespace tessera {

// How a Renderer keeps its scene's meshes.
struct RendererOptions {
  std::size_t compact_above = kCompactMeshTriangles;  // SceneGeometry's; tests lower it
  // False: the arrays of untextured meshes are freed once Embree holds them, and scene()
  // has them empty (SceneGeometry's `release`). True, for a caller that builds more
  // geometry from scene(): the benchmark's bare Embree loop, the tests.
  bool keep_meshes = false;
};

class TESSERA_TRACER_API Renderer {
 public:
  explicit Renderer(Scene scene, const RendererOptions& options = {});
  // Another frame of `previous`'s animated scene. When the objects are the same (no track
  // lies in them, and each is as transmissive as before) it shares `previous`'s Embree
  // scene, building nothing: a camera, a light or a colour that moves costs no BVH.
  // Otherwise it builds a BVH of its own over its objects, in which each mesh of its own
  // BVH (MeshBvh) is placed again with the frame's transform: moving a big mesh costs no
  // rebuild of it either. The textures are always shared.
  Renderer(Scene scene, const Renderer& previous, const RendererOptions& options = {});

  const Scene& scene() const { return scene_; }
  const SceneGeometry& geometry() const { return built_->geometry; }
  // Whether this renderer uses the geometry `other` built (or built it for `other`).
  bool shares_geometry_with(const Renderer& other) const { return built_ == other.built_; }
  // Whether this renderer's geometry places a mesh BVH (MeshBvh) that `other` holds too.
  bool shares_meshes_with(const Renderer& other) const;
  const PinholeCamera& camera() const { return camera_; }
  const Tracer& tracer() const { return tracer_; }

  // Renders `tile` into `out` (tile.width * tile.height RGB float triples, row-major).
  // A pixel's value depends only on the scene and the pixel's coordinates.
  RayCounts render_tile(const TileRect& tile, std::span<float> out) const;
  // The same into rows `row_stride` floats apart, such as the tile's place in a whole image:
  // `out` starts at the tile's first pixel and reaches at least to its last.
  RayCounts render_tile(const TileRect& tile, std::span<float> out, std::size_t row_stride) const;

 private:
  // What every frame of an animation shares: Embree's device, on which the meshes' own
  // BVHs are built, and the decoded textures.
  struct Common {
    explicit Common(const Scene& scene) : textures(scene) {}
    EmbreeDevice device;
    SceneTextures textures;
  };
  // What a frame of an animation may share with the next.
  struct Built {
    Built(Scene& scene, std::shared_ptr<const Common> common, const RendererOptions& options,
          const SceneGeometry* previous = nullptr);
    std::shared_ptr<const Common> common;  // first, so that it outlives the geometry
    SceneGeometry geometry;
  };

  Scene scene_;
  std::shared_ptr<const Built> built_;
  Tracer tracer_;
  PinholeCamera camera_;
};

}  // namespace tessera
