// The server-sent events of GET /v1/events and GET /v1/jobs/{id}/events, and the tile list
// of GET /v1/jobs/{id}/tiles (docs/api.md, "Events"). A job event's data is a JobStatus.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/protocol/field_reader.hpp"
#include "common/protocol/names.hpp"
#include "common/protocol/workers.hpp"

namespace tessera::protocol {

// The event types, as the `event:` field names them.
namespace event {
inline constexpr std::string_view job = "job";
inline constexpr std::string_view job_removed = "job_removed";
inline constexpr std::string_view worker = "worker";
inline constexpr std::string_view tile = "tile";
inline constexpr std::string_view resync = "resync";
}  // namespace event

// The header a client resumes a stream with: the id of the last event it has.
inline constexpr std::string_view kLastEventIdHeader = "Last-Event-ID";

// failed: its last attempt failed, and it waits to go out again.
enum class TileView { pending, rendering, done, failed };
inline constexpr NameTable<TileView, 4> kTileViewNames{{
    {TileView::pending, "pending"},
    {TileView::rendering, "rendering"},
    {TileView::done, "done"},
    {TileView::failed, "failed"},
}};

// One tile of a job (`TileStatus`): an item of GET /v1/jobs/{id}/tiles, and the data of a
// "tile" event, which carries the pixels of a tile done.
struct TileStatus {
  int index = 0;  // of the job's tiles: frame after frame, each frame's tiles alike
  int frame = 0;  // the scene's frame it is of
  int x = 0;
  int y = 0;
  int width = 0;
  int height = 0;
  TileView state = TileView::pending;
  std::optional<std::string> worker;  // rendering: its worker; done: who rendered it
  std::optional<std::string> worker_name;
  std::optional<double> render_ms;  // done: as its worker timed it
  // A tile event of a tile done: width x height x 3 bytes of 8-bit RGB, coded as the job's
  // PNG is (sRGB unless the scene asks for linear), rows from the top, in base64.
  std::optional<std::string> pixels;

  static TileStatus read(const FieldReader& body);
};
nlohmann::json to_json(const TileStatus& tile);

// The most tiles one GET /v1/jobs/{id}/tiles answers, and what it answers unasked.
inline constexpr std::size_t kMaxTilesPage = 10'000;

// A page of a job's tiles: from the query's offset on, in index order.
struct TileList {
  std::vector<TileStatus> tiles;
  std::int64_t total = 0;                   // the job's tiles, every frame's
  std::optional<std::int64_t> next_offset;  // the next page's offset; none after the last

  static TileList read(const FieldReader& body);
};
nlohmann::json to_json(const TileList& list);

enum class WorkerChange { joined, changed, left, lost, removed };
inline constexpr NameTable<WorkerChange, 5> kWorkerChangeNames{{
    {WorkerChange::joined, "joined"},
    {WorkerChange::changed, "changed"},
    {WorkerChange::left, "left"},
    {WorkerChange::lost, "lost"},
    {WorkerChange::removed, "removed"},
}};

// The data of a "worker" event (`WorkerEvent`).
struct WorkerEvent {
  WorkerChange change = WorkerChange::changed;
  Worker worker;

  static WorkerEvent read(const FieldReader& body);
};
nlohmann::json to_json(const WorkerEvent& event);

// The data of a "resync" event (`Resync`): the stream missed events; reload what it shows.
struct Resync {
  std::string reason;

  static Resync read(const FieldReader& body);
};
nlohmann::json to_json(const Resync& resync);

// The data of a "job_removed" event (`JobRemoved`).
struct JobRemoved {
  std::string id;

  static JobRemoved read(const FieldReader& body);
};
nlohmann::json to_json(const JobRemoved& removed);

}  // namespace tessera::protocol
