#include "common/protocol/leases.hpp"

#include <algorithm>
#include <limits>

namespace tessera::protocol {
namespace {

using nlohmann::json;

int whole(const FieldReader& body, std::string_view key) {
  return static_cast<int>(body.integer(key, 0, std::numeric_limits<int>::max()));
}

}  // namespace

Lease Lease::read(const FieldReader& body) {
  Lease lease;
  lease.id = body.string("id");
  lease.job_id = body.string("job_id");
  lease.scene_digest = body.string("scene_digest");
  lease.frame = whole(body, "frame");
  lease.tiles = read_array<LeaseTile>(body, "tiles", [](const FieldReader& tile) {
    return LeaseTile{whole(tile, "index"), whole(tile, "x"), whole(tile, "y"), whole(tile, "width"),
                     whole(tile, "height")};
  });
  lease.expires_in_s = body.number("expires_in_s");
  return lease;
}

json to_json(const Lease& lease) {
  json tiles = json::array();
  for (const LeaseTile& t : lease.tiles)
    tiles.push_back(
        {{"index", t.index}, {"x", t.x}, {"y", t.y}, {"width", t.width}, {"height", t.height}});
  return {
      {"id", lease.id},       {"job_id", lease.job_id},    {"scene_digest", lease.scene_digest},
      {"frame", lease.frame}, {"tiles", std::move(tiles)}, {"expires_in_s", lease.expires_in_s}};
}

TileFailure TileFailure::read(const FieldReader& body) {
  TileFailure failure;
  failure.tile = static_cast<int>(
      body.integer("tile", std::numeric_limits<int>::min(), std::numeric_limits<int>::max()));
  failure.error = body.string("error").substr(0, kMaxErrorChars);
  return failure;
}

json to_json(const TileFailure& failure) {
  return {{"tile", failure.tile}, {"error", failure.error}};
}

std::string number_list(std::span<const std::uint64_t> numbers) {
  std::string text;
  for (const std::uint64_t n : numbers) {
    if (!text.empty()) text += ',';
    text += std::to_string(n);
  }
  return text;
}

std::optional<std::vector<std::uint64_t>> parse_number_list(std::string_view text) {
  std::vector<std::uint64_t> numbers;
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t end = std::min(text.find(',', start), text.size());
    const std::string_view item = text.substr(start, end - start);
    // At most 19 digits: every such number fits in 64 bits.
    if (item.empty() || item.size() > 19 || item.find_first_not_of("0123456789") != item.npos)
      return std::nullopt;
    numbers.push_back(std::stoull(std::string(item)));
    start = end + 1;
  }
  return numbers;
}

ResultAnswer ResultAnswer::read(const FieldReader& body) {
  const auto status = value_in(kResultStatusNames, body.string("status"));
  if (!status) body.fail("status", "must be " + names_of(kResultStatusNames));
  return {*status};
}

json to_json(const ResultAnswer& answer) {
  return {{"status", name_in(kResultStatusNames, answer.status)}};
}

}  // namespace tessera::protocol
