#include "client/render_command.hpp"

#include <chrono>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <utility>

#include <nlohmann/json.hpp>

#include "client/frame_paths.hpp"
#include "client/movie_file.hpp"
#include "client/scene_input.hpp"
#include "common/image/image_io.hpp"
#include "common/mesh_files/folder_scene_files.hpp"
#include "common/scene/frame_list.hpp"
#include "common/scene/scene_frames.hpp"
#include "common/scene/scene_parser.hpp"
#include "common/scn/scn_import.hpp"
#include "common/text/printable.hpp"
#include "tracer/local_render.hpp"

namespace tessera {
namespace {

struct RenderOptions {
  std::string scene_path;
  std::string output_path;
  std::optional<int> width, height, spp, max_depth, tile_size;
  std::optional<std::string> frames;
  int threads = 0;
};

// Command-line overrides go into the document before validation, so they obey the same
// rules, and produce the same messages, as values written in the file.
void apply_overrides(nlohmann::json& document, const RenderOptions& options) {
  if (!document.is_object()) return;
  auto set = [&](const char* section, const char* key, const std::optional<int>& value) {
    if (!value) return;
    nlohmann::json& target = document[section];
    if (target.is_null()) target = nlohmann::json::object();
    if (target.is_object()) target[key] = *value;
  };
  set("image", "width", options.width);
  set("image", "height", options.height);
  set("render", "samples_per_pixel", options.spp);
  set("render", "max_depth", options.max_depth);
  set("render", "tile_size", options.tile_size);
}

int render_and_report(const RenderOptions& options, const Scene& scene,
                      const std::filesystem::path& output) {
  const auto start = std::chrono::steady_clock::now();
  const Renderer renderer(scene);
  const auto built = std::chrono::steady_clock::now();
  LocalRenderResult result;
  std::optional<EncodedImage> encoded;
  auto rendered = start;
  const auto render = [&] {
    result = render_local(renderer, options.threads);
    rendered = std::chrono::steady_clock::now();
    // Encoding needs none of OpenImageIO either.
    encoded.emplace(result.image, output, scene.render.output_transfer);
  };
  // For an EXR, TIFF or JPEG, OpenImageIO's libraries load beside the tracing rather than
  // after it. Not earlier: building the Renderer starts TBB, which opens libtbbmalloc with
  // dlopen() and would wait for the dynamic loader's lock that this load holds until it is
  // done. A PNG is written with libpng and loads none of it: loading it anyway took half
  // the CPU and half the wall time of a 1080p render (docs/performance.md, "PNG with
  // libpng").
  if (image_file_needs_module(output))
    while_loading_image_files(render);
  else
    render();
  write_image(*encoded);

  const double build_s = std::chrono::duration<double>(built - start).count();
  const double trace_s = std::chrono::duration<double>(rendered - built).count();
  const double rays_per_s = trace_s > 0 ? result.rays.total() / trace_s : 0.0;
  std::printf(
      "rendered %dx%d, %d spp, max depth %d in %.3f s (scene build %.3f s, tracing %.3f s)\n",
      scene.width, scene.height, scene.render.samples_per_pixel, scene.render.max_depth,
      build_s + trace_s, build_s, trace_s);
  std::printf("rays: %llu (%llu primary, %llu secondary, %llu shadow), %.2f Mrays/s\n",
              static_cast<unsigned long long>(result.rays.total()),
              static_cast<unsigned long long>(result.rays.primary),
              static_cast<unsigned long long>(result.rays.secondary),
              static_cast<unsigned long long>(result.rays.shadow), rays_per_s / 1e6);
  std::printf("wrote %s\n", printable(std::filesystem::absolute(output).string()).c_str());
  return 0;
}

double seconds_between(std::chrono::steady_clock::time_point from,
                       std::chrono::steady_clock::time_point to) {
  return std::chrono::duration<double>(to - from).count();
}

// The frames to render: those of --frames, else every frame when `every` (a movie, or an
// output with '#' for the number), else the first (a still from an animation).
std::vector<int> frames_to_render(const RenderOptions& options, const Animation& animation,
                                  bool every) {
  if (options.frames)
    return parse_frame_list(*options.frames, animation.first, animation.last, Limits{}.max_frames);
  if (!every) return {animation.first};
  std::vector<int> all;
  for (int frame = animation.first; frame <= animation.last; ++frame) all.push_back(frame);
  return all;
}

// Each frame rendered and written as soon as it is done; a frame whose objects are those
// of the frame before reuses its geometry (Renderer's second constructor).
int render_frames(const RenderOptions& options, SceneFrames& frames, const std::vector<int>& list,
                  const std::string& pattern) {
  std::unique_ptr<Renderer> renderer;
  Scene first = frames.take_first();
  for (const int frame : list) {
    const auto start = std::chrono::steady_clock::now();
    Scene scene =
        renderer ? frames.at(frame, renderer->scene())
                 : (frame == first.frame ? std::move(first) : frames.at(frame, std::move(first)));
    renderer = renderer ? std::make_unique<Renderer>(std::move(scene), *renderer)
                        : std::make_unique<Renderer>(std::move(scene));
    const auto built = std::chrono::steady_clock::now();
    const LocalRenderResult result = render_local(*renderer, options.threads);
    const auto rendered = std::chrono::steady_clock::now();
    const std::filesystem::path path = frame_path(pattern, frame);
    write_image(result.image, path, renderer->scene().render.output_transfer);
    std::printf("frame %d: %dx%d in %.3f s (scene build %.3f s, tracing %.3f s), wrote %s\n", frame,
                renderer->scene().width, renderer->scene().height, seconds_between(start, rendered),
                seconds_between(start, built), seconds_between(built, rendered),
                printable(std::filesystem::absolute(path).string()).c_str());
    std::fflush(stdout);
  }
  return 0;
}

// The frames rendered as PNGs into a folder of their own, then encoded into `output`.
int render_movie(const RenderOptions& options, SceneFrames& frames, const std::vector<int>& list,
                 const std::filesystem::path& ffmpeg, const std::filesystem::path& output) {
  std::optional<TemporaryFolder> dir;
  try {
    dir.emplace("tessera-frames-");
  } catch (const MovieError& e) {
    std::fprintf(stderr, "error: %s\n", printable(e.what()).c_str());
    return 1;
  }
  const std::string pattern = (dir->path() / "frame_#######.png").string();
  const double fps = frames.animation().fps;
  if (const int code = render_frames(options, frames, list, pattern); code != 0) return code;
  std::vector<std::filesystem::path> paths;
  for (const int frame : list) paths.emplace_back(frame_path(pattern, frame));
  try {
    encode_movie(ffmpeg, paths, fps, output);
  } catch (const MovieError& e) {
    std::fprintf(stderr, "error: %s\n", printable(e.what()).c_str());
    return 1;
  }
  std::printf("wrote %s: %zu frames at %g fps\n",
              printable(std::filesystem::absolute(output).string()).c_str(), list.size(), fps);
  return 0;
}

int run_render(const RenderOptions& options) {
  std::filesystem::path output = options.output_path;
  if (output.empty()) {
    const std::string stem = std::filesystem::path(options.scene_path).stem().string();
    output = stem + (options.frames ? "_####.png" : ".png");
  }
  const bool movie = is_movie_path(output);
  if (!movie && !is_supported_image_path(output)) {
    std::fprintf(stderr,
                 "error: %s: unknown image extension (use .exr, .png, .jpg or .tif, or .mp4, "
                 ".mkv or .mov for a movie)\n",
                 printable(output.string()).c_str());
    return 2;
  }
  std::filesystem::path ffmpeg;
  if (movie) {
    // Before any rendering: a missing encoder is found out in a second, not after an hour.
    try {
      ffmpeg = find_ffmpeg();
    } catch (const MovieError& e) {
      std::fprintf(stderr, "error: %s\n", printable(e.what()).c_str());
      return 2;
    }
  }
  std::string text;
  try {
    text = read_scene_text(options.scene_path, options.width, options.height);
  } catch (const ScnError& e) {
    std::fprintf(stderr, "error: %s\n", printable(e.what()).c_str());
    return 2;
  } catch (const std::exception& e) {
    // A scene file that is missing or unreadable: a usage error, as for submit.
    std::fprintf(stderr, "error: %s\n", printable(e.what()).c_str());
    return 2;
  }
  try {
    // Mesh files are named relative to the scene file. The text is freed before tracing
    // starts, not kept beside the Scene through it.
    const FolderSceneFiles files(std::filesystem::path(options.scene_path).parent_path());
    SceneFrames frames(
        std::exchange(text, {}), Limits{},
        [&](nlohmann::json& document) { apply_overrides(document, options); }, &files);
    if (movie && !frames.animation().animated) {
      std::fprintf(stderr, "error: %s: a movie needs an animated scene (\"animation\")\n",
                   printable(options.scene_path).c_str());
      return 2;
    }
    std::vector<int> list;
    try {
      list =
          frames_to_render(options, frames.animation(), movie || has_frame_number(output.string()));
    } catch (const FrameListError& e) {
      std::fprintf(stderr, "error: --frames: %s\n", printable(e.what()).c_str());
      return 2;
    }
    if (movie) return render_movie(options, frames, list, ffmpeg, output);
    if (list.size() > 1 && !has_frame_number(output.string())) {
      std::fprintf(stderr,
                   "error: %s: %zu frames need '#' in the output's name where the frame number "
                   "goes, such as out_####.png\n",
                   printable(output.string()).c_str(), list.size());
      return 2;
    }
    if (!options.frames && !frames.animation().animated)
      return render_and_report(options, frames.take_first(), output);
    return render_frames(options, frames, list, output.string());
  } catch (const SceneError& e) {
    std::fprintf(stderr, "error: %s: %s\n", printable(options.scene_path).c_str(),
                 printable(e.what()).c_str());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", printable(e.what()).c_str());
    return 1;
  }
}

}  // namespace

void add_render_command(CLI::App& app) {
  auto options = std::make_shared<RenderOptions>();
  CLI::App* render = app.add_subcommand("render", "Render a scene on this machine (no server)");
  render->add_option("scene", options->scene_path, "Scene file (JSON, or a COS 426 .scn)")
      ->required();
  render->add_option("-o,--output", options->output_path,
                     "Output image: .png, .jpg, .tif or .exr (default: SCENE's name with .png); "
                     "# for the frame number (out_####.png); .mp4, .mkv or .mov for a movie "
                     "of the frames (needs ffmpeg)");
  render->add_option("--width", options->width, "Override image.width")->check(CLI::PositiveNumber);
  render->add_option("--height", options->height, "Override image.height")
      ->check(CLI::PositiveNumber);
  render->add_option("--spp", options->spp, "Override render.samples_per_pixel");
  render->add_option("--max-depth", options->max_depth, "Override render.max_depth");
  render->add_option("--tile-size", options->tile_size, "Override render.tile_size");
  render->add_option("--frames", options->frames,
                     "Frames of an animated scene: 1-48, 1-100x2 (every second), 1,5,10-20 "
                     "(default: all when OUTPUT has # for the number, else the first)");
  render->add_option("--threads", options->threads, "Rendering threads (default: one per core)")
      ->check(CLI::NonNegativeNumber);
  render->final_callback([options] {
    const int code = run_render(*options);
    if (code != 0) throw CLI::RuntimeError(code);
  });
}

}  // namespace tessera
