// Reading the JSON documents the project stores inside its files (the metadata.json of a VAE
// export or a retargeting bundle), with errors that name the file, the document and the key path:
//   "b/bundle.pt: metadata.json: \"human.vertices\" should be an integer, got \"x\"".
#pragma once

#include <nlohmann/json_fwd.hpp>
#include <string>

namespace retarget {

struct JsonFields {
  std::string where;     // the file the document came from (the Error's where)
  std::string document;  // its name in messages, e.g. "metadata.json"

  // Parses `text`, which must hold a JSON object. Throws retarget::Error(where, "<document> is not
  // valid JSON: ..." or "<document> is not a JSON object").
  nlohmann::json parse(const std::string& text) const;

  // object[key]; `path` is the key path of `object` in the document ("" for the root), for
  // messages. Throws for a missing key, or when `object` is no object.
  const nlohmann::json& member(const nlohmann::json& object, const std::string& key,
                               const std::string& path = "") const;

  // object[key] as T: std::string, int64_t, double or bool. Throws for a missing key or a
  // value of another type ("should be a string, got 3").
  template <typename T>
  T get(const nlohmann::json& object, const std::string& key, const std::string& path = "") const;
};

}  // namespace retarget
