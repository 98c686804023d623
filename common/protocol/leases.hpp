// The bodies of /v1/leases and of a claim: a lease, a tile's failure, a result's headers
// and its answer.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/protocol/field_reader.hpp"
#include "common/protocol/names.hpp"

namespace tessera::protocol {

struct LeaseTile {
  int index = 0;
  int x = 0;
  int y = 0;
  int width = 0;
  int height = 0;
};

// The answer to a claim, a heartbeat and an extension (`Lease`).
struct Lease {
  std::string id;
  std::string job_id;
  std::string scene_digest;
  int frame = 0;                 // the scene's frame the tiles are of; 0 for a still
  std::vector<LeaseTile> tiles;  // in the order to render them
  double expires_in_s = 0;

  static Lease read(const FieldReader& body);
};
nlohmann::json to_json(const Lease& lease);

// POST /v1/leases/{id}/fail.
struct TileFailure {
  // What the coordinator keeps of `error`: it ends up in the job's error and in logs.
  static constexpr std::size_t kMaxErrorChars = 1000;
  int tile = 0;
  std::string error;

  static TileFailure read(const FieldReader& body);
};
nlohmann::json to_json(const TileFailure& failure);

// PUT /v1/leases/{id}/result: the body is the tiles' pixels, one after the other, each as
// little-endian float32 RGB rows from the top; these headers say which tiles, in order.
inline constexpr std::string_view kTilesHeader = "X-Tessera-Tiles";
inline constexpr std::string_view kRaysHeader = "X-Tessera-Rays";
// Optional, with X-Tessera-Tiles: how long each tile took its worker, in microseconds (the
// coordinator's render-time histogram and the dashboard's heatmap).
inline constexpr std::string_view kRenderMicrosecondsHeader = "X-Tessera-Render-Us";
inline constexpr std::string_view kPixelsContentType = "application/octet-stream";

// "3,17,4" <-> {3, 17, 4}.
std::string number_list(std::span<const std::uint64_t> numbers);
// Nothing when the text is not whole numbers separated by commas.
std::optional<std::vector<std::uint64_t>> parse_number_list(std::string_view text);

enum class ResultStatus { accepted, duplicate };
inline constexpr NameTable<ResultStatus, 2> kResultStatusNames{{
    {ResultStatus::accepted, "accepted"},
    {ResultStatus::duplicate, "duplicate"},
}};

// The answer to a result that was taken: accepted, or every tile already delivered.
struct ResultAnswer {
  ResultStatus status = ResultStatus::accepted;

  static ResultAnswer read(const FieldReader& body);
};
nlohmann::json to_json(const ResultAnswer& answer);

}  // namespace tessera::protocol
