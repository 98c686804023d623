#include "common/protocol/events.hpp"

namespace tessera::protocol {
namespace {

using nlohmann::json;

template <typename T>
json or_null(const std::optional<T>& value) {
  return value ? json(*value) : json(nullptr);
}

}  // namespace

TileStatus TileStatus::read(const FieldReader& body) {
  TileStatus tile;
  tile.index = static_cast<int>(body.integer("index", 0));
  tile.frame = static_cast<int>(body.integer("frame", 0));
  tile.x = static_cast<int>(body.integer("x", 0));
  tile.y = static_cast<int>(body.integer("y", 0));
  tile.width = static_cast<int>(body.integer("width", 1));
  tile.height = static_cast<int>(body.integer("height", 1));
  const auto state = value_in(kTileViewNames, body.string("state"));
  if (!state) body.fail("state", "must be " + names_of(kTileViewNames));
  tile.state = *state;
  tile.worker = body.nullable_string("worker");
  tile.worker_name = body.nullable_string("worker_name");
  tile.render_ms = body.nullable_number("render_ms");
  tile.pixels = body.nullable_string("pixels");
  return tile;
}

json to_json(const TileStatus& tile) {
  return {{"index", tile.index},
          {"frame", tile.frame},
          {"x", tile.x},
          {"y", tile.y},
          {"width", tile.width},
          {"height", tile.height},
          {"state", name_in(kTileViewNames, tile.state)},
          {"worker", or_null(tile.worker)},
          {"worker_name", or_null(tile.worker_name)},
          {"render_ms", or_null(tile.render_ms)},
          {"pixels", or_null(tile.pixels)}};
}

TileList TileList::read(const FieldReader& body) {
  TileList list;
  list.tiles = read_array<TileStatus>(body, "tiles", &TileStatus::read);
  list.total = body.integer("total", 0);
  list.next_offset = body.nullable_integer("next_offset");
  if (list.next_offset && *list.next_offset < 0) body.fail("next_offset", "must be at least 0");
  return list;
}

json to_json(const TileList& list) {
  json tiles = json::array();
  for (const TileStatus& tile : list.tiles) tiles.push_back(to_json(tile));
  return {{"tiles", std::move(tiles)},
          {"total", list.total},
          {"next_offset", list.next_offset ? json(*list.next_offset) : json()}};
}

WorkerEvent WorkerEvent::read(const FieldReader& body) {
  WorkerEvent event;
  const auto change = value_in(kWorkerChangeNames, body.string("change"));
  if (!change) body.fail("change", "must be " + names_of(kWorkerChangeNames));
  event.change = *change;
  event.worker = Worker::read(body.object("worker"));
  return event;
}

json to_json(const WorkerEvent& event) {
  return {{"change", name_in(kWorkerChangeNames, event.change)}, {"worker", to_json(event.worker)}};
}

Resync Resync::read(const FieldReader& body) { return {body.string("reason")}; }

json to_json(const Resync& resync) { return {{"reason", resync.reason}}; }

JobRemoved JobRemoved::read(const FieldReader& body) { return {body.string("id")}; }

json to_json(const JobRemoved& removed) { return {{"id", removed.id}}; }

}  // namespace tessera::protocol
