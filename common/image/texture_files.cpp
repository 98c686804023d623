// A scene's textures through OpenImageIO: each image decoded to linear float RGB, written as
// a tiled, mip-mapped OpenEXR file (ImageBufAlgo::make_texture, what maketx does) in a
// folder of its own, and looked up through a TextureSystem of the scene's own.
//
// Why files: the TextureSystem reads its mip levels tile by tile through its cache, from
// files; writing each texture once as one is what lets it filter any image with bounded
// memory, the same way for a PNG, a JPEG or an EXR.
#include "common/image/texture_files.hpp"

#include <stdlib.h>

#include <array>
#include <atomic>
#include <cmath>
#include <filesystem>
#include <mutex>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <unordered_map>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/texture.h>

namespace tessera {
namespace {

[[noreturn]] void fail(const TextureImage& image, const std::string& why) {
  throw std::runtime_error("texture " + image.name + ": " + why);
}

// An image's file, or its bytes through a proxy that lives as long as the reader.
struct OpenedImage {
  std::unique_ptr<OIIO::Filesystem::IOMemReader> proxy;
  std::unique_ptr<OIIO::ImageInput> input;
};

OpenedImage open_image(const TextureImage& image) {
  OpenedImage opened;
  if (image.bytes) {
    opened.proxy =
        std::make_unique<OIIO::Filesystem::IOMemReader>(image.bytes->data(), image.bytes->size());
    OIIO::ImageSpec config;
    // The name's extension chooses the decoder; the bytes come through the proxy, which
    // some decoders take from the hint rather than the argument.
    void* proxy = opened.proxy.get();
    config.attribute("oiio:ioproxy", OIIO::TypeDesc::PTR, &proxy);
    opened.input =
        OIIO::ImageInput::open("embedded" + image.extension, &config, opened.proxy.get());
  } else {
    opened.input = OIIO::ImageInput::open(image.path);
  }
  if (!opened.input) {
    std::string why = OIIO::geterror();
    if (why.empty()) why = "is not an image that can be read";
    fail(image, why);
  }
  const OIIO::ImageSpec& spec = opened.input->spec();
  if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0 || spec.depth > 1)
    fail(image, "has no pixels, or is a volume");
  const auto pixels =
      static_cast<std::uint64_t>(spec.width) * static_cast<std::uint64_t>(spec.height);
  if (pixels > kMaxTexturePixels) {
    fail(image, "has " + std::to_string(spec.width) + " x " + std::to_string(spec.height) +
                    " pixels, more than the " + std::to_string(kMaxTexturePixels) +
                    " a texture may have");
  }
  return opened;
}

// Whether the file's values are sRGB-encoded: integer images are (PNG and JPEG files are
// written so), unless the file says it is linear; floating-point images (EXR, HDR) are
// linear.
bool srgb_encoded(const OIIO::ImageSpec& spec) {
  const OIIO::TypeDesc::BASETYPE base = static_cast<OIIO::TypeDesc::BASETYPE>(spec.format.basetype);
  if (base == OIIO::TypeDesc::FLOAT || base == OIIO::TypeDesc::HALF ||
      base == OIIO::TypeDesc::DOUBLE)
    return false;
  const std::string space = spec.get_string_attribute("oiio:ColorSpace");
  return !OIIO::Strutil::iequals(space, "linear") && !OIIO::Strutil::iequals(space, "scene_linear");
}

// The sRGB transfer function's inverse (IEC 61966-2-1), in double and then rounded: libm's
// pow may differ by CPU in its last bit, which rounding to float hides all but never.
float srgb_to_linear(float v) {
  const double x = v;
  return static_cast<float>(x <= 0.04045 ? x / 12.92 : std::pow((x + 0.055) / 1.055, 2.4));
}

// The image as linear float RGB: one channel is grey; alpha and any others are dropped.
OIIO::ImageBuf linear_rgb(const TextureImage& image) {
  OpenedImage opened = open_image(image);
  const OIIO::ImageSpec spec = opened.input->spec();
  const std::size_t count = static_cast<std::size_t>(spec.width) * spec.height;
  std::vector<float> all(count * spec.nchannels);
  if (!opened.input->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, all.data()))
    fail(image, opened.input->geterror());
  const bool srgb = srgb_encoded(spec);
  const int channels = std::min(spec.nchannels, 3);
  OIIO::ImageBuf rgb(OIIO::ImageSpec(spec.width, spec.height, 3, OIIO::TypeDesc::FLOAT));
  std::vector<float> out(count * 3);
  for (std::size_t i = 0; i < count; ++i)
    for (int c = 0; c < 3; ++c) {
      const float v = all[i * spec.nchannels + std::min(c, channels - 1)];
      out[i * 3 + c] = srgb ? srgb_to_linear(v) : v;
    }
  rgb.set_pixels(OIIO::ROI::All(), OIIO::TypeDesc::FLOAT, out.data());
  return rgb;
}

OIIO::TextureOpt::Wrap wrap_mode(TextureWrap wrap) {
  switch (wrap) {
    case TextureWrap::clamp:
      return OIIO::TextureOpt::WrapClamp;
    case TextureWrap::mirror:
      return OIIO::TextureOpt::WrapMirror;
    case TextureWrap::repeat:
      break;
  }
  return OIIO::TextureOpt::WrapPeriodic;
}

class OiioTextureSampler : public TextureSampler {
 public:
  explicit OiioTextureSampler(const std::vector<TextureImage>& images) {
    // Every header first, so that nothing is decoded for a scene that asks too much.
    check_textures(images);
    folder_ = make_folder();
    try {
      std::vector<std::string> files;
      for (std::size_t i = 0; i < images.size(); ++i) {
        const std::string file = (folder_ / (std::to_string(i) + ".exr")).string();
        write_mip_map(images[i], file);
        files.push_back(file);
      }
      system_ = OIIO::TextureSystem::create(false);
      system_->attribute("automip", 0);
      system_->attribute("autotile", 0);
      OIIO::TextureSystem::Perthread* setup = thread_info();
      for (std::size_t i = 0; i < files.size(); ++i) {
        OIIO::TextureSystem::TextureHandle* handle =
            system_->get_texture_handle(OIIO::ustring(files[i]), setup);
        if (handle == nullptr) fail(images[i], system_->geterror());
        handles_.push_back(handle);
      }
    } catch (...) {
      release();
      throw;
    }
  }
  ~OiioTextureSampler() override { release(); }
  OiioTextureSampler(const OiioTextureSampler&) = delete;
  OiioTextureSampler& operator=(const OiioTextureSampler&) = delete;

  void sample(std::size_t index, TextureWrap wrap, const TextureFootprint& at,
              float (&rgb)[3]) const override {
    OIIO::TextureOpt options;
    options.swrap = options.twrap = wrap_mode(wrap);
    // Bilinear within a level, so that a magnified texture shows its texels' bilinear
    // blend (the default, bicubic when magnified, would not).
    options.interpmode = OIIO::TextureOpt::InterpBilinear;
    if (!system_->texture(handles_[index], system_->get_perthread_info(thread_info()), options,
                          at.s, at.t, at.dsdx, at.dtdx, at.dsdy, at.dtdy, 3, rgb))
      rgb[0] = rgb[1] = rgb[2] = 0.0f;  // its file went away under the render: black
  }

 private:
  static std::filesystem::path make_folder() {
    std::filesystem::path pattern =
        std::filesystem::temp_directory_path() / "tessera-textures-XXXXXX";
    std::string name = pattern.string();
    if (mkdtemp(name.data()) == nullptr)
      throw std::runtime_error("cannot make a folder for textures in " +
                               std::filesystem::temp_directory_path().string());
    return name;
  }

  static void write_mip_map(const TextureImage& image, const std::string& file) {
    const OIIO::ImageBuf rgb = linear_rgb(image);
    OIIO::ImageSpec config;
    config.tile_width = 64;
    config.tile_height = 64;
    config.tile_depth = 1;
    config.set_format(OIIO::TypeDesc::FLOAT);
    config.attribute("maketx:filtername", "box");
    config.attribute("maketx:fixnan", "box3");
    config.attribute("compression", "none");
    std::ostringstream log;
    if (!OIIO::ImageBufAlgo::make_texture(OIIO::ImageBufAlgo::MakeTxTexture, rgb, file, config,
                                          &log))
      fail(image, "could not be made into a mip-map: " + OIIO::geterror());
  }

  // This thread's record of its lookups in this sampler's system. OpenImageIO would keep
  // one in thread-local storage of its own, which it tears down as each thread ends: for
  // TBB's threads, which outlive every scene, that was after the system was destroyed, into
  // freed memory (an assertion or a crash at exit). So each thread gets one made here,
  // found again through a thread-local cache of the last few samplers it used (by a number
  // no other sampler has, never by address), and all are destroyed with the system.
  OIIO::TextureSystem::Perthread* thread_info() const {
    struct Entry {
      std::uint64_t sampler = 0;
      OIIO::TextureSystem::Perthread* info = nullptr;
    };
    constexpr std::size_t kCached = 4;
    thread_local std::array<Entry, kCached> cache{};
    thread_local std::size_t next = 0;
    for (const Entry& entry : cache)
      if (entry.sampler == id_) return entry.info;
    OIIO::TextureSystem::Perthread* info = nullptr;
    {
      const std::lock_guard lock(mutex_);
      auto& mine = infos_[std::this_thread::get_id()];
      if (mine == nullptr) mine = system_->create_thread_info();
      info = mine;
    }
    cache[next] = {id_, info};
    next = (next + 1) % kCached;
    return info;
  }

  static std::uint64_t new_id() {
    static std::atomic<std::uint64_t> last{0};
    return ++last;
  }

  void release() {
    if (system_ != nullptr) {
      for (const auto& [thread, info] : infos_) system_->destroy_thread_info(info);
      infos_.clear();
      OIIO::TextureSystem::destroy(system_, true);
    }
    system_ = nullptr;
    std::error_code error;
    if (!folder_.empty()) std::filesystem::remove_all(folder_, error);
  }

  std::filesystem::path folder_;
  OIIO::TextureSystem* system_ = nullptr;
  std::vector<OIIO::TextureSystem::TextureHandle*> handles_;
  const std::uint64_t id_ = new_id();
  mutable std::mutex mutex_;
  mutable std::unordered_map<std::thread::id, OIIO::TextureSystem::Perthread*> infos_;
};

}  // namespace

std::unique_ptr<TextureSampler> open_textures(const std::vector<TextureImage>& images) {
  return std::make_unique<OiioTextureSampler>(images);
}

void check_textures(const std::vector<TextureImage>& images) {
  std::uint64_t pixels = 0;
  for (const TextureImage& image : images) {
    const OpenedImage opened = open_image(image);  // the spec lives as long as its reader
    const OIIO::ImageSpec& spec = opened.input->spec();
    pixels += static_cast<std::uint64_t>(spec.width) * static_cast<std::uint64_t>(spec.height);
  }
  if (pixels > kMaxSceneTexturePixels)
    throw std::runtime_error("the scene's textures have " + std::to_string(pixels) +
                             " pixels together, more than the " +
                             std::to_string(kMaxSceneTexturePixels) + " a scene's may have");
}

}  // namespace tessera
