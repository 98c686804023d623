// One model file being read: its bytes, the name the scene calls it by (for messages), and
// the folder its own files (an MTL, a .bin, textures) must stay inside.
#pragma once

#include <charconv>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <string_view>

#include "common/scene/scene_files.hpp"

namespace tessera {

struct ModelSource {
  std::filesystem::path path;    // the model file on disk
  std::string name;              // as the scene names it
  std::filesystem::path bundle;  // the folder the model's own references resolve in
  const MeshFileRequest* request = nullptr;
  // Where the model's own files are when they are not in a folder (an asset's bundle): from
  // a name, lexically normal and inside the bundle, to its file. Unset: `bundle` / name.
  std::function<std::filesystem::path(const std::string& name, const std::string& where)> lookup;

  [[noreturn]] void fail(const std::string& where, const std::string& detail) const {
    throw SceneFileError(name, where, detail);
  }
  // More triangles than the scene may still have: `claimed` is what the file says it has.
  [[noreturn]] void fail_triangles(const std::string& where, std::uint64_t claimed) const;

  // The whole file, refused above `max_bytes`.
  std::string read(std::uint64_t max_bytes = std::uint64_t{1} << 34) const;
  // A file the model names, which must resolve inside `bundle`: an absolute name, a ".."
  // that climbs out of it, or a link that leads out, is an error at `where`.
  std::filesystem::path dependency(std::string_view reference, const std::string& where) const;
};

inline std::string line_at(std::size_t line) { return "line " + std::to_string(line); }

// The numbers of a text format, as std::from_chars reads them (no locale, no leading '+').
template <typename T>
std::optional<T> parse_number(std::string_view token) {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  T value{};
  const auto [end, error] = std::from_chars(token.data(), token.data() + token.size(), value);
  if (error != std::errc() || end != token.data() + token.size()) return std::nullopt;
  return value;
}

Model read_obj(const ModelSource& source);
Model read_gltf(const ModelSource& source);
Model read_ply(const ModelSource& source);
Model read_off(const ModelSource& source);

}  // namespace tessera
