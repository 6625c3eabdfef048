#include "web/asset_serving.h"

#include <string>

#include "web/http_json.h"

namespace retarget {

void serve_web_asset(httplib::Response& res, const WebAsset* (*find)(std::string_view), std::string_view name) {
  const WebAsset* asset = find(name);
  if (!asset) asset = find_shared_web_asset(name);
  if (!asset) http_json::reject(404, "no such page");
  res.set_header("Cache-Control", "no-cache");
  res.set_content(std::string(asset->body), std::string(asset->content_type).c_str());
}

}  // namespace retarget
