// The web dashboard's files (server/web/), built into the server: server/api/web_assets.cmake
// writes their bytes into a source of the build tree at build time.
#pragma once

#include <span>
#include <string_view>

namespace tessera {

struct WebAsset {
  std::string_view name;          // the file's name in server/web/: "app.js"
  std::string_view path;          // where it is served: "/" for index.html, "/ui/NAME" else
  std::string_view content_type;  // "application/javascript; charset=utf-8"
  std::string_view bytes;         // the file as it is
};

// Every file, in name order.
std::span<const WebAsset> web_assets();

}  // namespace tessera
