// Random identifiers and content digests for the coordinator.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

namespace tessera {

// `chars` lowercase hex digits from the OS's cryptographic generator: lease ids are
// fencing tokens, so they must not be guessable from earlier ones.
std::string random_hex(std::size_t chars);

// `count` bytes as lowercase hex, two digits each.
std::string to_hex(const unsigned char* bytes, std::size_t count);

// Lowercase hex SHA-256 of `data`.
std::string sha256_hex(std::string_view data);

}  // namespace tessera
