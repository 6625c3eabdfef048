// A web page's files (*.html, *.js, *.css), compiled into the binary (cmake/embed_web_assets.cmake
// writes their definitions at build time), so a server needs no files at run time and no request
// path can reach the file system. web_assets() and find_web_asset() are the annotation tool's
// (annotate/web/, defined in retarget_annotate); the landmark editor's are the same functions
// renamed (avatar/CMakeLists.txt), and so are the assets both pages share (web/assets/:
// theme.css, defined in retarget_web).
#pragma once

#include <string_view>
#include <vector>

namespace retarget {

struct WebAsset {
  std::string_view name;          // file name in the page's folder, "app.js"
  std::string_view content_type;  // "text/javascript; charset=utf-8"
  std::string_view body;
};

// Every embedded file, by name.
const std::vector<WebAsset>& web_assets();
// The asset called exactly `name`; nullptr for anything else.
const WebAsset* find_web_asset(std::string_view name);

// The assets both pages share (web/assets/), by name.
const std::vector<WebAsset>& shared_web_assets();
const WebAsset* find_shared_web_asset(std::string_view name);

}  // namespace retarget
