// The web annotation tool's HTTP server (`retarget annotate serve`): several people at once, each
// in a browser, choose for a human expression which of two avatar expressions looks more alike,
// over one annotation store (annotate/annotation_store.h).
//
// Pages (embedded in the binary from annotate/web/, see web_assets.h; no request path ever
// reaches the file system):
//   GET /                 the annotation page        GET /overview   the owner's overview page
//   GET /static/<asset>   its scripts and style sheet
// Annotators (header "Authorization: Bearer <session token>"; 401 without a known token):
//   POST /api/signin  {"name"}                 -> {"name", "token"}   (409: the name has a session)
//   GET  /api/me                               -> {"name", "progress"}
//   POST /api/next                             -> {"assignment" | null, "progress", "waiting", "finished"}
//   POST /api/answer  {"comparison", "answer"} -> {"result", "assignment" | null, "progress", ...}
//   POST /api/undo                             -> {"assignment", "progress"}
//   POST /api/release {"comparison"}           -> {}
//   POST /api/signout                          -> {}
//   GET  /img/anchor/<group>.png, /img/candidate/<sample>.png: turntable strips (any valid token)
// The owner (header "Authorization: Bearer <owner token>"; 401 without, 403 for another token):
//   GET  /api/overview                         -> per-group progress, per-annotator counts
//   GET  /api/export?derived=1|0               -> the triplets as CSV (derived ones marked)
//   GET  /api/annotator?name=<name>            -> that annotator's decisions
//   POST /api/reset   {"name"}                 -> ends their sessions, releases what they hold
// Errors are {"error": "message"} with a 4xx status. Every answer is committed to SQLite before
// its response is sent, so a killed server loses nothing a page showed as done. Endpoints that need
// a token check it before they look at the request's body (401 before 400).
// Connections are guarded (web/guarded_http_server.h, limits in ServerOptions::connections):
// bodies over max_body_bytes get 413 whether sent with a length or chunked, without being read
// whole; a request must arrive within a deadline (408); one client address gets a bounded number
// of request threads at once (429 beyond); header size and count are capped (431).
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "web/connection_limits.h"

namespace retarget {

// The pictures the pages show: PNG turntable strips of `frames` square pictures side by side
// (yaw -max..+max degrees, see render_turntable). Called at most once per picture (the server
// caches the bytes) and never concurrently.
struct TurntablePictures {
  int frames = 1;
  std::function<std::string(const std::string& label)> anchor;  // the human expression of a group
  std::function<std::string(int64_t sample)> candidate;         // an avatar sample
};

struct ServerOptions {
  std::string host = "127.0.0.1";  // the address to listen on; only loopback unless asked
  int port = 8080;                 // 0 = any free port; 0..65535
  double lease_seconds = 120;      // how long a shown comparison stays reserved for its annotator; > 0
  std::string owner_token;         // the owner's token or password (>= 8 characters); empty = random
  size_t max_body_bytes = 4096;    // larger request bodies (Content-Length or chunked) get 413; 64..1 MiB
  int threads = 32;                // request threads, each serving one connection at a time; 1..256
  bool prerender = true;           // render every group's pictures in the background at start
  // Deadlines, keep-alive, the per-client cap (by default half the threads: 16 connections per
  // address at once), header limits: see connection_limits.h.
  ConnectionLimits connections;

  // Throws retarget::Error naming `key_path`.<field> (connections: `key_path`.connections.<field>)
  // for a value out of range.
  void validate(const std::string& key_path = "serve") const;
};

class AnnotationServer {
 public:
  // Opens the store at `database` (one connection per request thread) and prepares the routes.
  // Throws retarget::Error for invalid options or a store that does not open.
  AnnotationServer(const std::string& database, TurntablePictures pictures, const ServerOptions& options);
  ~AnnotationServer();
  AnnotationServer(const AnnotationServer&) = delete;
  AnnotationServer& operator=(const AnnotationServer&) = delete;

  // Binds options.host:options.port and returns the port (the chosen one for port 0). Throws
  // retarget::Error naming the address when it cannot bind.
  int bind();
  // Serves until stop() (from another thread or a signal handler's thread). bind() first.
  void run();
  void stop();

  int port() const;
  const std::string& owner_token() const;
  // "http://127.0.0.1:8080"
  std::string base_url() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace retarget
