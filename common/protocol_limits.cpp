#include "common/protocol_limits.hpp"

#include <algorithm>
#include <limits>
#include <type_traits>

#include <nlohmann/json.hpp>

namespace tessera {
namespace {

constexpr const char* kMaxResultTiles = "max_result_tiles";
constexpr const char* kMaxResultBytes = "max_result_bytes";
constexpr const char* kMaxBatchTiles = "max_batch_tiles";
constexpr const char* kMaxLeaseTiles = "max_lease_tiles";

}  // namespace

ProtocolLimits coordinator_limits(int max_tile_size) {
  ProtocolLimits limits;
  const std::size_t largest_tile = static_cast<std::size_t>(std::max(max_tile_size, 1)) *
                                   std::max(max_tile_size, 1) * 3 * sizeof(float);
  limits.max_result_bytes = std::max(limits.max_result_bytes, largest_tile);
  return limits;
}

nlohmann::json to_json(const ProtocolLimits& limits) {
  return {{kMaxResultTiles, limits.max_result_tiles},
          {kMaxResultBytes, limits.max_result_bytes},
          {kMaxBatchTiles, limits.max_batch_tiles},
          {kMaxLeaseTiles, limits.max_lease_tiles}};
}

ParsedLimits limits_from_json(const nlohmann::json& json) {
  if (!json.is_object()) return {std::nullopt, "limits: expected an object"};
  ProtocolLimits limits;
  std::string error;
  // Each limit must be there, and a whole number of at least 1: a coordinator that states
  // 0 or nothing is not one this worker can keep to.
  const auto read = [&](const char* key, auto& field) {
    using Field = std::remove_reference_t<decltype(field)>;
    if (!error.empty()) return;
    const auto it = json.find(key);
    // Signed or unsigned as JSON goes: a number parsed from text is unsigned, one built
    // in memory may be either.
    const bool whole = it != json.end() && it->is_number_integer();
    const bool positive =
        whole && (it->is_number_unsigned() || it->template get<std::int64_t>() >= 1);
    if (!positive || it->template get<std::uint64_t>() < 1 ||
        it->template get<std::uint64_t>() >
            static_cast<std::uint64_t>(std::numeric_limits<Field>::max())) {
      error = std::string("limits/") + key + ": expected a positive integer";
      return;
    }
    field = static_cast<Field>(it->template get<std::uint64_t>());
  };
  read(kMaxResultTiles, limits.max_result_tiles);
  read(kMaxResultBytes, limits.max_result_bytes);
  read(kMaxBatchTiles, limits.max_batch_tiles);
  read(kMaxLeaseTiles, limits.max_lease_tiles);
  if (!error.empty()) return {std::nullopt, error};
  return {limits, ""};
}

std::string with_thousands(std::uint64_t n) {
  std::string digits = std::to_string(n);
  for (int i = static_cast<int>(digits.size()) - 3; i > 0; i -= 3)
    digits.insert(static_cast<std::size_t>(i), ",");
  return digits;
}

std::string result_tiles_over_limit(const ProtocolLimits& limits, std::uint64_t tiles) {
  return "a result carries at most " +
         with_thousands(static_cast<std::uint64_t>(limits.max_result_tiles)) +
         " tiles; this one has " + with_thousands(tiles);
}

}  // namespace tessera
