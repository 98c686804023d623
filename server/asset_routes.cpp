// /v1/assets/{digest} for clients (PUT uploads, GET and HEAD look) and
// /v1/scene-assets/{digest} for workers (GET fetches). An upload streams to the disk
// through a BodySink, a mebibyte at a time, written on the blocking pool: the network's
// threads neither hold the body nor wait on the disk.
#include "common/protocol/assets.hpp"
#include "common/protocol/paths.hpp"
#include "server/access.hpp"
#include "server/api_json.hpp"
#include "server/api_routes.hpp"
#include "server/asset_store.hpp"
#include "server/worker_identity.hpp"

namespace tessera {
namespace {

constexpr std::string_view kPrefix = "sha256:";

// The 64 hex digits of "sha256:<64 hex digits>", or nothing.
std::optional<std::string> digest_of(const HttpRequest& request) {
  const std::string& text = request.params.at("digest");
  if (!text.starts_with(kPrefix) || !is_sha256_hex(std::string_view(text).substr(kPrefix.size())))
    return std::nullopt;
  return text.substr(kPrefix.size());
}

HttpResponse bad_digest(const HttpRequest& request) {
  return error_response(400, "invalid_digest",
                        "an asset is named \"sha256:\" and 64 lower-case hex digits, got \"" +
                            request.params.at("digest") + "\"");
}

class UploadSink : public BodySink {
 public:
  UploadSink(std::unique_ptr<AssetStore::Upload> upload, ApiContext& context)
      : upload_(std::move(upload)), context_(context) {}

  void write(std::string piece, std::function<void(bool)> done) override {
    context_.run_disk(
        [this, piece = std::move(piece), done = std::move(done)] { done(upload_->write(piece)); });
  }
  AssetStore::Upload& upload() { return *upload_; }

 private:
  std::unique_ptr<AssetStore::Upload> upload_;
  ApiContext& context_;
};

void put_asset(ApiContext& context, HttpRequest&& request, Respond respond) {
  const auto digest = digest_of(request);
  auto sink = std::static_pointer_cast<UploadSink>(request.body_sink);
  if (!digest || !sink) return respond(bad_digest(request));
  context.run_disk([&context, sink, digest = *digest, respond = std::move(respond)] {
    std::string actual;
    switch (context.assets->commit(sink->upload(), digest, &actual)) {
      case AssetStore::Committed::added:
        return respond(body_response(201, protocol::AssetStored{"sha256:" + digest, true}));
      case AssetStore::Committed::already_held:
        return respond(body_response(200, protocol::AssetStored{"sha256:" + digest, false}));
      case AssetStore::Committed::wrong_digest:
        return respond(error_response(400, "digest_mismatch",
                                      "the body's SHA-256 is sha256:" + actual +
                                          ", not sha256:" + digest + "; nothing was stored"));
      case AssetStore::Committed::failed:
        return respond(error_response(507, "insufficient_storage",
                                      "the coordinator could not store the asset"));
    }
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
      context.assets->max_bytes(), role_client, "application/octet-stream",
      [&context](const HttpRequest& head) -> std::shared_ptr<BodySink> {
        // A malformed digest is answered before its body is read.
        if (!digest_of(head)) return nullptr;
        return std::make_shared<UploadSink>(context.assets->begin_upload(), context);
      });
  // GET, and HEAD through it: whether the coordinator has the asset, and its bytes.
  router.add(
      "GET", asset,
      [&context](HttpRequest&& request, Respond respond) { respond(asset_file(context, request)); },
      std::nullopt, role_client);
  router.add(
      "GET", std::string(protocol::route::scene_asset),
      [&context](HttpRequest&& request, Respond respond) {
        if (auto refused = check_any_worker(context.scheduler, request))
          return respond(std::move(*refused));
        respond(asset_file(context, request));
      },
      std::nullopt, role_worker);
}

}  // namespace tessera
