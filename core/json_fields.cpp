#include "core/json_fields.h"

#include <cstdint>
#include <nlohmann/json.hpp>
#include <type_traits>

#include "core/error.h"

namespace retarget {

using json = nlohmann::json;

namespace {

std::string joined(const std::string& path, const std::string& key) { return path.empty() ? key : path + "." + key; }

}  // namespace

json JsonFields::parse(const std::string& text) const {
  json value;
  try {
    value = json::parse(text);
  } catch (const json::exception& e) {
    throw Error(where, document + " is not valid JSON: " + e.what());
  }
  if (!value.is_object()) throw Error(where, document + " is not a JSON object");
  return value;
}

const json& JsonFields::member(const json& object, const std::string& key, const std::string& path) const {
  if (!object.is_object())
    throw Error(where, document + ": \"" + path + "\" should be an object, got " + object.dump());
  const auto it = object.find(key);
  if (it == object.end()) throw Error(where, document + ": missing key \"" + joined(path, key) + "\"");
  return *it;
}

template <typename T>
T JsonFields::get(const json& object, const std::string& key, const std::string& path) const {
  const json& value = member(object, key, path);
  const char* expected = "";
  bool ok = false;
  if constexpr (std::is_same_v<T, std::string>) {
    ok = value.is_string();
    expected = "a string";
  } else if constexpr (std::is_same_v<T, int64_t>) {
    ok = value.is_number_integer();
    expected = "an integer";
  } else if constexpr (std::is_same_v<T, double>) {
    ok = value.is_number();
    expected = "a number";
  } else {
    static_assert(std::is_same_v<T, bool>, "JsonFields::get reads strings, integers, numbers and booleans");
    ok = value.is_boolean();
    expected = "true or false";
  }
  if (!ok) {
    throw Error(where, document + ": \"" + joined(path, key) + "\" should be " + expected + ", got " + value.dump());
  }
  return value.get<T>();
}

template std::string JsonFields::get<std::string>(const json&, const std::string&, const std::string&) const;
template int64_t JsonFields::get<int64_t>(const json&, const std::string&, const std::string&) const;
template double JsonFields::get<double>(const json&, const std::string&, const std::string&) const;
template bool JsonFields::get<bool>(const json&, const std::string&, const std::string&) const;

}  // namespace retarget
