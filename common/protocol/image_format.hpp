// The image file formats Tessera writes, each named once: its name in the API
// (?format=png), its file extensions and its media type.
#pragma once

#include <algorithm>
#include <array>
#include <cctype>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

#include "common/text/ascii_case.hpp"
#include "common/text/or_list.hpp"

namespace tessera {

enum class ImageFileKind { exr, png, jpg, tif, unknown };

struct ImageFormat {
  ImageFileKind kind;
  std::string_view name;          // in the API's ?format= and on the command line
  std::string_view extension;     // of the files written, with its dot
  std::string_view alias;         // another extension read as the same format ("" for none)
  std::string_view content_type;  // the HTTP media type
};

inline constexpr std::array<ImageFormat, 4> kImageFormats{{
    {ImageFileKind::png, "png", ".png", "", "image/png"},
    {ImageFileKind::exr, "exr", ".exr", "", "image/x-exr"},
    {ImageFileKind::jpg, "jpg", ".jpg", ".jpeg", "image/jpeg"},
    {ImageFileKind::tif, "tif", ".tif", ".tiff", "image/tiff"},
}};

inline const ImageFormat* image_format_named(std::string_view name) {
  for (const ImageFormat& format : kImageFormats)
    if (format.name == name) return &format;
  return nullptr;
}

// By the path's extension, in any case; nullptr for none of them.
inline const ImageFormat* image_format_of_path(const std::filesystem::path& path) {
  const std::string ext = ascii_lower(path.extension().string());
  for (const ImageFormat& format : kImageFormats)
    if (!ext.empty() && (ext == format.extension || ext == format.alias)) return &format;
  return nullptr;
}

// "png, exr, jpg or tif", for messages; with `dots`, ".png, .exr, .jpg or .tif".
inline std::string image_format_names(bool dots = false) {
  std::array<std::string_view, kImageFormats.size()> names;
  for (std::size_t i = 0; i < names.size(); ++i)
    names[i] = dots ? kImageFormats[i].extension : kImageFormats[i].name;
  return or_list(names);
}

}  // namespace tessera
