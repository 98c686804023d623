// An asset's name, on the wire and in scenes: "sha256:" and the 64 lower-case hex digits of
// the SHA-256 of its bytes. The one place that spells the form: everything else parses and
// prints it through AssetDigest.
#pragma once

#include <optional>
#include <set>
#include <string>
#include <string_view>

namespace tessera::protocol {

class AssetDigest {
 public:
  // What an error names when a text is not a digest.
  static constexpr std::string_view kForm = "\"sha256:\" and 64 lower-case hex digits";

  // "sha256:HEX" exactly; nothing for anything else (upper case, short, a prefix missing).
  static std::optional<AssetDigest> parse(std::string_view text);
  // From the 64 hex digits alone, as a file's SHA-256 is computed; std::invalid_argument
  // when they are not 64 lower-case hex digits.
  static AssetDigest of_hex(std::string_view hex);

  const std::string& hex() const { return hex_; }
  std::string text() const;  // "sha256:HEX"
  // A short name for messages and file names: "sha256:" and the first 12 digits.
  std::string short_text() const;

  friend bool operator==(const AssetDigest&, const AssetDigest&) = default;

 private:
  explicit AssetDigest(std::string hex) : hex_(std::move(hex)) {}
  std::string hex_;
};

// 64 lower-case hex digits.
bool is_sha256_hex(std::string_view text);

// The hex digits of every digest named anywhere in `text` (a scene's JSON, say), each once.
std::set<std::string> digests_named_in(std::string_view text);

}  // namespace tessera::protocol
