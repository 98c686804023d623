#include "common/protocol/asset_digest.hpp"

#include <algorithm>
#include <stdexcept>

namespace tessera::protocol {
namespace {

constexpr std::string_view kPrefix = "sha256:";

}  // namespace

bool is_sha256_hex(std::string_view text) {
  return text.size() == 64 && std::all_of(text.begin(), text.end(), [](char c) {
           return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f');
         });
}

std::optional<AssetDigest> AssetDigest::parse(std::string_view text) {
  if (!text.starts_with(kPrefix) || !is_sha256_hex(text.substr(kPrefix.size())))
    return std::nullopt;
  return AssetDigest(std::string(text.substr(kPrefix.size())));
}

AssetDigest AssetDigest::of_hex(std::string_view hex) {
  if (!is_sha256_hex(hex))
    throw std::invalid_argument("not a SHA-256 in 64 lower-case hex digits: " + std::string(hex));
  return AssetDigest(std::string(hex));
}

std::string AssetDigest::text() const { return std::string(kPrefix) + hex_; }

std::string AssetDigest::short_text() const { return std::string(kPrefix) + hex_.substr(0, 12); }

std::set<std::string> digests_named_in(std::string_view text) {
  std::set<std::string> digests;
  for (std::size_t at = text.find(kPrefix); at != std::string_view::npos;
       at = text.find(kPrefix, at + kPrefix.size())) {
    const std::string_view hex = text.substr(at + kPrefix.size(), 64);
    if (is_sha256_hex(hex)) digests.emplace(hex);
  }
  return digests;
}

}  // namespace tessera::protocol
