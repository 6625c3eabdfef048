// Sending a page's embedded files (web/web_assets.h) over HTTP, the same way for both pages.
#pragma once

#include <httplib.h>

#include <string_view>

#include "web/web_assets.h"

namespace retarget {

// Sends the asset `name` of a page (`find`: its room's finder, e.g. find_web_asset) or, when the
// page has none of that name, of the shared assets (theme.css), uncached; answers 404 "no such
// page" (http_json::reject) for anything else.
void serve_web_asset(httplib::Response& res, const WebAsset* (*find)(std::string_view), std::string_view name);

}  // namespace retarget
