#include "web/http_json.h"

#include <fmt/format.h>

#include <cctype>

namespace retarget::http_json {

using nlohmann::json;

[[noreturn]] void reject(int status, std::string message) { throw HttpError{status, std::move(message)}; }

void send_json(httplib::Response& res, const json& body, int status) {
  res.status = status;
  res.set_header("Cache-Control", "no-store");
  res.set_content(body.dump(), "application/json");
}

bool same_token(const std::string& a, const std::string& b) {
  if (a.size() != b.size()) return false;
  unsigned char diff = 0;
  for (size_t i = 0; i < a.size(); ++i) diff |= static_cast<unsigned char>(a[i] ^ b[i]);
  return diff == 0;
}

std::string bearer_token(const httplib::Request& req) {
  const std::string header = req.get_header_value("Authorization");
  const std::string prefix = "Bearer ";
  if (header.size() <= prefix.size() || header.compare(0, prefix.size(), prefix) != 0) return {};
  return header.substr(prefix.size());
}

std::string checked_name(const json& value, const std::string& key) {
  if (!value.is_string()) reject(400, fmt::format("'{}' must be a string (the annotator's name)", key));
  const std::string name = value.get<std::string>();
  if (name.empty() || name.size() > 40)
    reject(400, fmt::format("'{}' must have 1 to 40 characters, got {}", key, name.size()));
  for (char c : name) {
    const auto u = static_cast<unsigned char>(c);
    if (!(std::isalnum(u) || c == ' ' || c == '_' || c == '.' || c == '-'))
      reject(400, fmt::format("'{}' may hold letters, digits, spaces and _ . - only", key));
  }
  if (name.front() == ' ' || name.back() == ' ')
    reject(400, fmt::format("'{}' must not start or end with a space", key));
  return name;
}

json body_object(const httplib::Request& req) {
  if (req.body.empty()) return json::object();
  json body = json::parse(req.body, nullptr, false);
  if (body.is_discarded()) reject(400, "the request body is not valid JSON");
  if (!body.is_object()) reject(400, "the request body must be a JSON object");
  return body;
}

const json& field(const json& body, const std::string& key) {
  const auto it = body.find(key);
  if (it == body.end()) reject(400, fmt::format("the request body has no '{}'", key));
  return *it;
}

int64_t id_field(const json& body, const std::string& key) {
  const json& value = field(body, key);
  if (!value.is_number_integer()) reject(400, fmt::format("'{}' must be an integer id", key));
  // nlohmann reads 2^63 and above as unsigned: never wrap them into negative ids.
  if (value.is_number_unsigned() ? value.get<uint64_t>() > static_cast<uint64_t>(INT64_MAX) : value.get<int64_t>() < 1)
    reject(400, fmt::format("'{}' must be an id from 1 to {}, got {}", key, INT64_MAX, value.dump()));
  return value.get<int64_t>();
}

void respond_to_error(const httplib::Request&, httplib::Response& res) {
  if (!res.body.empty()) return;
  const char* what = res.status == 404   ? "no such page or endpoint"
                     : res.status == 405 ? "method not allowed"
                     : res.status == 408 ? "the request did not arrive in time"
                     : res.status == 411 ? "the request body needs a Content-Length"
                     : res.status == 413 ? "the request body is too large"
                     : res.status == 415 ? "request bodies must not be compressed (Content-Encoding)"
                     : res.status == 431 ? "the request's headers are too large or too many"
                     : res.status == 501 ? "unsupported Transfer-Encoding (only chunked)"
                                         : "bad request";
  send_json(res, {{"error", what}}, res.status);
}

void respond_to_exception(const httplib::Request&, httplib::Response& res, std::exception_ptr ep) {
  std::string what = "internal error";
  try {
    std::rethrow_exception(ep);
  } catch (const std::exception& e) {
    what = e.what();
  } catch (...) {
  }
  fmt::print(stderr, "[error] {}\n", what);
  send_json(res, {{"error", "internal server error"}}, 500);
}

}  // namespace retarget::http_json
