#include "common/protocol/limits.hpp"

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

nlohmann::json protocol::to_json(const ProtocolLimits& limits) {
  return {{kMaxResultTiles, limits.max_result_tiles},
          {kMaxResultBytes, limits.max_result_bytes},
          {kMaxBatchTiles, limits.max_batch_tiles},
          {kMaxLeaseTiles, limits.max_lease_tiles}};
}

ProtocolLimits protocol::read_limits(const FieldReader& json) {
  // Each within its field's type, so that no coordinator's number wraps around here.
  const auto read = [&](const char* key, auto& field) {
    using Field = std::remove_reference_t<decltype(field)>;
    const std::uint64_t most = std::min<std::uint64_t>(std::numeric_limits<Field>::max(),
                                                       std::numeric_limits<std::int64_t>::max());
    field = static_cast<Field>(json.integer(key, 1, static_cast<std::int64_t>(most)));
  };
  ProtocolLimits limits;
  read(kMaxResultTiles, limits.max_result_tiles);
  read(kMaxResultBytes, limits.max_result_bytes);
  read(kMaxBatchTiles, limits.max_batch_tiles);
  read(kMaxLeaseTiles, limits.max_lease_tiles);
  return limits;
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
