// The web dashboard: its page and the files the page loads, public routes that carry no data
// (the page asks the API for everything, with the user's token). The page picks its view from
// location.pathname, so the paths of its views answer with the page too.
#include <stdexcept>
#include <string>

#include "common/protocol/paths.hpp"
#include "server/api/api_routes.hpp"
#include "server/api/web_assets.hpp"

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

const WebAsset* asset_at(std::string_view path) {
  for (const WebAsset& asset : web_assets())
    if (asset.path == path) return &asset;
  return nullptr;
}

HttpResponse file_response(const WebAsset& asset) {
  return HttpResponse{200, std::string(asset.content_type), std::string(asset.bytes),
                      page_headers()};
}

void serve_page(Router& router, std::string_view pattern, const WebAsset& page) {
  router.add("GET", std::string(pattern),
             [&page](HttpRequest&&, Respond respond) { respond(file_response(page)); });
}

}  // namespace

void add_web_routes(Router& router, ApiContext&) {
  const WebAsset* page = asset_at(protocol::route::ui_page);
  if (!page) throw std::logic_error("the web dashboard has no page (server/web/index.html)");
  serve_page(router, protocol::route::ui_page, *page);
  serve_page(router, protocol::route::ui_job, *page);
  serve_page(router, protocol::route::ui_workers, *page);
  // Every other file of server/web/ by its name, which is data: it only ever picks one of
  // the files built in (web_assets.cmake allows letters, digits, '.', '_' and '-').
  router.add("GET", std::string(protocol::route::ui_file),
             [](HttpRequest&& request, Respond respond) {
               const WebAsset* asset = asset_at("/ui/" + request.params.at("name"));
               if (!asset)
                 return respond(error_response(404, "not_found", "the dashboard has no such file"));
               respond(file_response(*asset));
             });
}

}  // namespace tessera
