// The web annotation tool's pages (annotate/web/*.html, *.js, *.css), compiled into the binary
// (cmake/embed_web_assets.cmake writes web_assets.cpp at build time), so the server needs no
// files at run time and no request path can reach the file system.
#pragma once

#include <string_view>
#include <vector>

namespace retarget {

struct WebAsset {
  std::string_view name;          // file name in annotate/web/, "app.js"
  std::string_view content_type;  // "text/javascript; charset=utf-8"
  std::string_view body;
};

// Every embedded file, by name.
const std::vector<WebAsset>& web_assets();
// The asset called exactly `name`; nullptr for anything else.
const WebAsset* find_web_asset(std::string_view name);

}  // namespace retarget
