// The JSON conventions of the project's web pages' HTTP APIs (annotate/annotation_server.h,
// avatar/landmark_editor.h), internal to their servers: errors are {"error": message} with a 4xx/5xx status, a request
// body is one JSON object whose missing or mistyped fields get a 400 naming the field, and annotators and the owner
// present "Authorization: Bearer <token>".
//
// An endpoint refuses a request by throwing HttpError (reject); the server's handler wrapper
// turns it into send_json(res, {{"error", message}}, status).
#pragma once

// clang-format off
#include <httplib.h>
// clang-format on

#include <cstdint>
#include <exception>
#include <nlohmann/json.hpp>
#include <string>

namespace retarget::http_json {

// An error for the client: `status` with {"error": message}.
struct HttpError {
  int status;
  std::string message;
};

// Throws HttpError{status, message}.
[[noreturn]] void reject(int status, std::string message);

// `body` as the response, with `status` and "Cache-Control: no-store".
void send_json(httplib::Response& res, const nlohmann::json& body, int status = 200);

// Constant-time comparison, so a token cannot be guessed byte by byte from response times.
bool same_token(const std::string& a, const std::string& b);

// The token of "Authorization: Bearer <token>"; empty when absent or malformed.
std::string bearer_token(const httplib::Request& req);

// An annotator's name: 1..40 characters of letters, digits, space, '_', '.', '-', not starting
// or ending with a space. 400 naming `key` otherwise.
std::string checked_name(const nlohmann::json& value, const std::string& key);

// The request body as a JSON object (an empty body is an empty object); 400 otherwise.
nlohmann::json body_object(const httplib::Request& req);

// body[key]; 400 naming `key` when absent.
const nlohmann::json& field(const nlohmann::json& body, const std::string& key);

// body[key] as an integer id; 400 naming `key` when absent or not an integer.
int64_t id_field(const nlohmann::json& body, const std::string& key);

// The error responder: the JSON error for a request no endpoint took (unknown paths, path
// tricks, other methods, the connection guards' refusals), unless a body was already set.
void respond_to_error(const httplib::Request& req, httplib::Response& res);

// The exception handler: logs an exception no endpoint turned into an answer to stderr and
// answers a bare 500.
void respond_to_exception(const httplib::Request& req, httplib::Response& res, std::exception_ptr ep);

}  // namespace retarget::http_json
