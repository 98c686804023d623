// OpenImageIO behind the ImageFileModule boundary; the only file that includes it.
#include "common/image/image_file_module.hpp"

#include <algorithm>
#include <stdexcept>

#include <OpenImageIO/imageio.h>

#include "common/image/texture_files.hpp"

namespace tessera {
namespace {

void write(const std::string& path, const ImageFileContent& content) {
  OIIO::TypeDesc type = OIIO::TypeDesc::UINT8;
  if (content.kind == ImageFileKind::exr) type = OIIO::TypeDesc::FLOAT;
  if (content.kind == ImageFileKind::tif) type = OIIO::TypeDesc::UINT16;
  OIIO::ImageSpec spec(content.width, content.height, 3, type);
  if (content.kind == ImageFileKind::exr)
    spec.attribute("compression", content.exr_compression == ExrCompression::rle ? "rle" : "zip");
  spec.attribute("oiio:ColorSpace", content.srgb ? "sRGB" : "Linear");
  if (content.kind == ImageFileKind::jpg) spec.attribute("Compression", "jpeg:95");
  auto out = OIIO::ImageOutput::create(path);
  if (!out) throw std::runtime_error(OIIO::geterror());
  bool ok = out->open(path, spec) && out->write_image(type, content.pixels);
  ok = out->close() && ok;
  if (!ok) throw std::runtime_error(out->geterror());
}

std::vector<float> read(const std::string& path, int& width, int& height) {
  auto in = OIIO::ImageInput::open(path);
  if (!in) throw std::runtime_error(OIIO::geterror());
  const OIIO::ImageSpec& spec = in->spec();
  const std::size_t count = static_cast<std::size_t>(spec.width) * spec.height;
  std::vector<float> all(count * spec.nchannels);
  if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, all.data()))
    throw std::runtime_error(in->geterror());
  width = spec.width;
  height = spec.height;
  if (spec.nchannels == 3) return all;
  const int channels = std::min(spec.nchannels, 3);
  std::vector<float> rgb(count * 3);
  for (std::size_t i = 0; i < count; ++i)
    for (int c = 0; c < 3; ++c)
      rgb[i * 3 + c] = all[i * spec.nchannels + std::min(c, channels - 1)];
  return rgb;
}

void encode_on_calling_thread() {
  OIIO::attribute("threads", 1);
  OIIO::attribute("exr_threads", -1);  // -1: OpenEXR without a thread pool of its own
}

constexpr ImageFileModule kModule{&write, &read, &encode_on_calling_thread, &open_textures,
                                  &check_textures};

}  // namespace
}  // namespace tessera

extern "C" __attribute__((visibility("default"))) const tessera::ImageFileModule*
tessera_image_file_module() {
  return &tessera::kModule;
}
