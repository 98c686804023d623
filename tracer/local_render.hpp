// Renders a whole image on this machine: every tile in parallel on a TBB arena.
#pragma once

#include "common/image/image.hpp"
#include "tracer/renderer.hpp"

namespace tessera {

struct LocalRenderResult {
  Image image;
  RayCounts rays;
};

// `threads` 0 means one per core; `tile_size` 0 means the scene's render.tile_size.
TESSERA_TRACER_API LocalRenderResult render_local(const Renderer& renderer, int threads = 0,
                                                  int tile_size = 0);

}  // namespace tessera
