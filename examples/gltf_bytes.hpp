// The bytes of glTF files, for the programs that write them: the glTF example's generator,
// the mesh-file benchmark and the tests. Not part of Tessera itself, which only reads glTF.
#pragma once

#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>

namespace tessera::gltf_bytes {

// `value`'s bytes as this (little-endian x86-64) machine holds them, as glTF stores them.
template <typename T>
void append(std::string& out, T value) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  out.append(bytes, sizeof(T));
}

// RFC 4648 base64 with padding, for a buffer embedded as a data: URI.
inline std::string base64(std::string_view bytes) {
  static constexpr char digits[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (std::size_t i = 0; i < bytes.size(); i += 3) {
    std::uint32_t n = static_cast<unsigned char>(bytes[i]) << 16;
    if (i + 1 < bytes.size()) n |= static_cast<unsigned char>(bytes[i + 1]) << 8;
    if (i + 2 < bytes.size()) n |= static_cast<unsigned char>(bytes[i + 2]);
    out += digits[(n >> 18) & 63];
    out += digits[(n >> 12) & 63];
    out += i + 1 < bytes.size() ? digits[(n >> 6) & 63] : '=';
    out += i + 2 < bytes.size() ? digits[n & 63] : '=';
  }
  return out;
}

// A .glb: the 12-byte header, then the JSON chunk (padded with spaces) and the BIN chunk
// (padded with zeros), each with its length and type.
inline std::string glb(std::string json, std::string bin) {
  while (json.size() % 4) json += ' ';
  while (bin.size() % 4) bin += '\0';
  std::string out;
  append(out, std::uint32_t{0x46546C67});  // "glTF"
  append(out, std::uint32_t{2});
  append(out, static_cast<std::uint32_t>(12 + 8 + json.size() + 8 + bin.size()));
  append(out, static_cast<std::uint32_t>(json.size()));
  append(out, std::uint32_t{0x4E4F534A});  // "JSON"
  out += json;
  append(out, static_cast<std::uint32_t>(bin.size()));
  append(out, std::uint32_t{0x004E4942});  // "BIN"
  return out + bin;
}

}  // namespace tessera::gltf_bytes
