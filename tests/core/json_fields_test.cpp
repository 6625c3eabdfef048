#include "core/json_fields.h"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include "core/error.h"

using namespace retarget;

TEST_CASE("JsonFields reads typed members and names file, document and key path in errors", "[json_fields]") {
  const JsonFields fields{"b/bundle.pt", "metadata.json"};
  const nlohmann::json d =
      fields.parse(R"({"name": "fox", "vertices": 4068, "scale": 0.5, "flag": true, "side": {"latent": 25}})");
  CHECK(fields.get<std::string>(d, "name") == "fox");
  CHECK(fields.get<int64_t>(d, "vertices") == 4068);
  CHECK(fields.get<double>(d, "scale") == 0.5);
  CHECK(fields.get<double>(d, "vertices") == 4068.0);  // an integer is a number too
  CHECK(fields.get<bool>(d, "flag"));
  CHECK(fields.get<int64_t>(fields.member(d, "side"), "latent", "side") == 25);

  CHECK_THROWS_WITH(fields.get<int64_t>(d, "name"),
                    "b/bundle.pt: metadata.json: \"name\" should be an integer, got \"fox\"");
  CHECK_THROWS_WITH(fields.get<std::string>(d, "vertices"),
                    "b/bundle.pt: metadata.json: \"vertices\" should be a string, got 4068");
  CHECK_THROWS_WITH(fields.get<bool>(d, "scale"),
                    "b/bundle.pt: metadata.json: \"scale\" should be true or false, got 0.5");
  CHECK_THROWS_WITH(fields.get<int64_t>(fields.member(d, "side"), "faces", "side"),
                    "b/bundle.pt: metadata.json: missing key \"side.faces\"");
  CHECK_THROWS_WITH(fields.get<int64_t>(d["name"], "x", "name"),
                    "b/bundle.pt: metadata.json: \"name\" should be an object, got \"fox\"");
  CHECK_THROWS_WITH(fields.parse("{\"a\": "), Catch::StartsWith("b/bundle.pt: metadata.json is not valid JSON: "));
  CHECK_THROWS_WITH(fields.parse("[1, 2]"), "b/bundle.pt: metadata.json is not a JSON object");
}
