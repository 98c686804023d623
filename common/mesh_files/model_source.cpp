#include "common/mesh_files/model_source.hpp"

#include <cerrno>
#include <cstring>
#include <fstream>

namespace tessera {

void ModelSource::fail_triangles(const std::string& where, std::uint64_t claimed) const {
  throw SceneFileError(
      name, where,
      "needs at least " + std::to_string(claimed) + " triangles, more than the scene's remaining " +
          std::to_string(request->max_triangles) + " of " +
          std::to_string(request->limit_max_triangles) + " triangles (limit max_triangles)",
      "max_triangles", request->limit_max_triangles);
}

std::string ModelSource::read(std::uint64_t max_bytes) const {
  std::error_code error;
  if (std::filesystem::is_directory(path, error)) fail("", "is a directory, not a file");
  std::ifstream in(path, std::ios::binary);
  if (!in) fail("", std::string("cannot open: ") + std::strerror(errno));
  in.seekg(0, std::ios::end);
  const auto size = static_cast<std::uint64_t>(in.tellg());
  if (size > max_bytes)
    fail("", "has " + std::to_string(size) + " bytes, more than " + std::to_string(max_bytes));
  in.seekg(0);
  std::string bytes(size, '\0');
  if (!in.read(bytes.data(), static_cast<std::streamsize>(size)))
    fail("", "could not be read to its end");
  return bytes;
}

std::filesystem::path ModelSource::dependency(std::string_view reference,
                                              const std::string& where) const {
  const std::filesystem::path relative(reference);
  const auto refuse = [&] {
    fail(where, "names \"" + std::string(reference) +
                    "\", which is outside the model's own folder; a model's files must sit "
                    "beside it or below it");
  };
  if (reference.empty() || relative.is_absolute() || relative.has_root_name()) refuse();
  const std::filesystem::path normal = relative.lexically_normal();
  if (normal.empty() || *normal.begin() == "..") refuse();
  if (lookup) return lookup(normal.generic_string(), where);
  const std::filesystem::path full = bundle / normal;
  // A link inside the folder that leads out of it counts as leaving.
  std::error_code error;
  const auto real_bundle = std::filesystem::weakly_canonical(bundle, error);
  const auto real_full = std::filesystem::weakly_canonical(full, error);
  if (!error) {
    const auto inside = real_full.lexically_relative(real_bundle);
    if (inside.empty() || *inside.begin() == "..") refuse();
  }
  return full;
}

}  // namespace tessera
