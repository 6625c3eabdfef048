// The tokens the project's web pages are opened with (the annotation tool's owner and annotator
// links, the landmark editor's page): random, unguessable, compared in constant time
// (web/http_json.h same_token).
#pragma once

#include <string>

namespace retarget {

// A random token of `bytes` random bytes as lower-case hex (std::random_device).
std::string random_token(int bytes = 16);

}  // namespace retarget
