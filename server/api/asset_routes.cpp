// /v1/assets/{digest} for clients (PUT uploads, GET and HEAD look) and
// /v1/scene-assets/{digest} for workers (GET fetches). An upload streams to the disk
// through a BodySink, a mebibyte at a time, written on the blocking pool: the network's
// threads neither hold the body nor wait on the disk.
#include <deque>
#include <mutex>

#include "common/protocol/asset_digest.hpp"
#include "common/protocol/assets.hpp"
#include "common/protocol/paths.hpp"
#include "server/api/access.hpp"
#include "server/api/api_json.hpp"
#include "server/api/api_routes.hpp"
#include "server/api/asset_store.hpp"
#include "server/api/worker_identity.hpp"

namespace tessera {
namespace {

// The 64 hex digits of the digest the path names, or nothing.
std::optional<std::string> digest_of(const HttpRequest& request) {
  const auto digest = protocol::AssetDigest::parse(request.params.at("digest"));
  if (!digest) return std::nullopt;
  return digest->hex();
}

HttpResponse bad_digest(const HttpRequest& request) {
  return error_response(400, "invalid_digest",
                        "an asset is named " + std::string(protocol::AssetDigest::kForm) +
                            ", got \"" + request.params.at("digest") + "\"");
}

// Pieces are written in order by one task at a time on the disk pool, while the session
// reads the next: the sink takes a piece at once while fewer than kQueued wait, so the
// network and the disk work side by side with at most that many mebibytes held.
class UploadSink : public BodySink, public std::enable_shared_from_this<UploadSink> {
 public:
  UploadSink(std::unique_ptr<AssetStore::Upload> upload, ApiContext& context)
      : upload_(std::move(upload)), context_(context) {}

  void write(std::string piece, std::function<void(bool)> done) override {
    std::unique_lock lock(mutex_);
    if (failed_) {
      lock.unlock();
      return done(false);  // the disk refused an earlier piece: stop reading the body
    }
    queue_.push_back(std::move(piece));
    start_writing();
    if (queue_.size() < kQueued) {
      lock.unlock();
      return done(true);
    }
    waiting_ = std::move(done);  // told once the writer has made room
  }

  // Calls `then` (on the disk pool, or here) once every piece taken is written: with
  // whether all were.
  void when_written(std::function<void(bool)> then) {
    std::unique_lock lock(mutex_);
    if (writing_) {
      written_ = std::move(then);
      return;
    }
    const bool ok = !failed_;
    lock.unlock();
    then(ok);
  }
  AssetStore::Upload& upload() { return *upload_; }

 private:
  static constexpr std::size_t kQueued = 2;

  void start_writing() {  // with mutex_ held
    if (writing_ || queue_.empty()) return;
    writing_ = true;
    context_.run_disk([self = shared_from_this()] { self->write_queued(); });
  }

  void write_queued() {
    std::unique_lock lock(mutex_);
    while (!queue_.empty()) {
      std::string piece = std::move(queue_.front());
      queue_.pop_front();
      lock.unlock();
      const bool ok = failed_ ? false : upload_->write(piece);
      lock.lock();
      if (!ok) {
        failed_ = true;
        queue_.clear();
      }
      if (waiting_ && (queue_.size() < kQueued || failed_)) {
        auto resume = std::move(waiting_);
        waiting_ = nullptr;
        const bool taken = !failed_;
        lock.unlock();
        resume(taken);
        lock.lock();
      }
    }
    writing_ = false;
    auto then = std::move(written_);
    written_ = nullptr;
    const bool ok = !failed_;
    lock.unlock();
    if (then) then(ok);
  }

  std::unique_ptr<AssetStore::Upload> upload_;
  ApiContext& context_;
  std::mutex mutex_;
  std::deque<std::string> queue_;
  bool writing_ = false;
  bool failed_ = false;
  std::function<void(bool)> waiting_;  // the session's, for a piece taken once there is room
  std::function<void(bool)> written_;  // put_asset's, once the queue is written
};

HttpResponse stored(ApiContext& context, UploadSink& sink, const std::string& digest) {
  std::string actual;
  switch (context.assets->commit(sink.upload(), digest, &actual)) {
    case AssetStore::Committed::added:
      return body_response(
          201, protocol::AssetStored{protocol::AssetDigest::of_hex(digest).text(), true});
    case AssetStore::Committed::already_held:
      return body_response(
          200, protocol::AssetStored{protocol::AssetDigest::of_hex(digest).text(), false});
    case AssetStore::Committed::wrong_digest:
      return error_response(400, "digest_mismatch",
                            "the body's SHA-256 is sha256:" + actual + ", not sha256:" + digest +
                                "; nothing was stored");
    case AssetStore::Committed::failed:
      break;
  }
  return error_response(507, "insufficient_storage", "the coordinator could not store the asset");
}

void put_asset(ApiContext& context, HttpRequest&& request, Respond respond) {
  const auto digest = digest_of(request);
  auto sink = std::static_pointer_cast<UploadSink>(request.body_sink);
  if (!digest || !sink) return respond(bad_digest(request));
  sink->when_written([&context, sink, digest = *digest, respond = std::move(respond)](bool ok) {
    if (!ok)
      return respond(
          error_response(507, "insufficient_storage", "the coordinator could not store the asset"));
    context.run_disk(
        [&context, sink, digest, respond] { respond(stored(context, *sink, digest)); });
  });
}

HttpResponse asset_file(ApiContext& context, const HttpRequest& request) {
  const auto digest = digest_of(request);
  if (!digest) return bad_digest(request);
  const auto path = context.assets->find(*digest);
  if (!path) return error_response(404, "not_found", "no asset sha256:" + *digest);
  HttpResponse response(200, "application/octet-stream", "");
  response.file = path->string();
  return response;
}

}  // namespace

void add_asset_routes(Router& router, ApiContext& context) {
  if (!context.assets) return;
  const std::string asset(protocol::route::asset);
  router.add(
      "PUT", asset,
      [&context](HttpRequest&& request, Respond respond) {
        put_asset(context, std::move(request), std::move(respond));
      },
      RouteOptions{}
          .with_body_limit(context.assets->max_bytes())
          .with_role(role_client)
          .with_content_type("application/octet-stream")
          .with_sink([&context](const HttpRequest& head) -> std::shared_ptr<BodySink> {
            // A malformed digest is answered before its body is read.
            if (!digest_of(head)) return nullptr;
            return std::make_shared<UploadSink>(context.assets->begin_upload(), context);
          }));
  // GET, and HEAD through it: whether the coordinator has the asset, and its bytes.
  router.add(
      "GET", asset,
      [&context](HttpRequest&& request, Respond respond) { respond(asset_file(context, request)); },
      RouteOptions{}.with_role(role_client));
  router.add(
      "GET", std::string(protocol::route::scene_asset),
      [&context](HttpRequest&& request, Respond respond) {
        if (auto refused = check_any_worker(context.scheduler, request))
          return respond(std::move(*refused));
        respond(asset_file(context, request));
      },
      RouteOptions{}.with_role(role_worker));
}

}  // namespace tessera
