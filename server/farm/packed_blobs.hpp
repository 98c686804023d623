// Lists of numbers stored as one blob: packed little-endian values (tile indexes int32,
// rays int64), as the store keeps them.
#pragma once

#include <cstddef>
#include <cstring>
#include <span>
#include <vector>

namespace tessera {

template <typename T>
std::span<const std::byte> bytes_of(const std::vector<T>& values) {
  return std::as_bytes(std::span(values));
}

// Unpacks a blob of packed little-endian values; trailing bytes short of a whole value are
// dropped (load()'s caller then finds the counts do not match).
template <typename T>
std::vector<T> unpack(std::span<const std::byte> bytes) {
  std::vector<T> values(bytes.size() / sizeof(T));
  if (!values.empty()) std::memcpy(values.data(), bytes.data(), values.size() * sizeof(T));
  return values;
}

}  // namespace tessera
