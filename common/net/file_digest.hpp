// SHA-256 digests of assets' bytes, as the coordinator names assets: on the client, which
// uploads a scene's files, and on the worker, which checks what it caches.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>

namespace tessera {

// Lower-case hex SHA-256 of `bytes`.
std::string bytes_sha256(std::string_view bytes);
// The same of a file's bytes, read a mebibyte at a time; "" when it cannot be read.
std::string file_sha256(const std::filesystem::path& path);

}  // namespace tessera
