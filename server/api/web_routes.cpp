// The web dashboard: its page and the files the page loads, public routes that carry no data
// (the page asks the API for everything, with the user's token). The page picks its view from
// location.pathname, so the paths of its views answer with the page too.
#include <stdexcept>
#include <string>

#include "common/protocol/paths.hpp"
#include "server/api_routes.hpp"
#include "server/web_assets.hpp"

namespace tessera {
namespace {

// What every answer of these routes carries: the page may load its own script and style
// only, connect to this origin only, be framed by nobody, and leak no address onwards.
const HttpResponse::Headers& page_headers() {
  static const HttpResponse::Headers headers = {
      {"Content-Security-Policy",
       "default-src 'none'; script-src 'self'; style-src 'self'; img-src 'self' blob: data:; "
       "connect-src 'self'; base-uri 'none'; form-action 'none'; frame-ancestors 'none'"},
      {"X-Content-Type-Options", "nosniff"},
      {"Referrer-Policy", "no-referrer"},
      {"Cache-Control", "no-cache"},
  };
  return headers;
}

const WebAsset& asset_at(std::string_view path) {
  for (const WebAsset& asset : web_assets())
    if (asset.path == path) return asset;
  throw std::logic_error("the web dashboard has no file served at " + std::string(path));
}

void serve(Router& router, std::string_view pattern, const WebAsset& asset) {
  router.add(
      "GET", std::string(pattern),
      [&asset](HttpRequest&&, Respond respond) {
        respond(HttpResponse{200, std::string(asset.content_type), std::string(asset.bytes),
                             page_headers()});
      },
      std::nullopt, "");
}

}  // namespace

void add_web_routes(Router& router, ApiContext&) {
  const WebAsset& page = asset_at(protocol::route::ui_page);
  serve(router, protocol::route::ui_page, page);
  serve(router, protocol::route::ui_job, page);
  serve(router, protocol::route::ui_workers, page);
  serve(router, protocol::route::ui_script, asset_at(protocol::route::ui_script));
  serve(router, protocol::route::ui_style, asset_at(protocol::route::ui_style));
}

}  // namespace tessera
