// cpp-httplib's server with its connections guarded (web/connection_limits.h). Debian's
// cpp-httplib 0.11.4 leaves these open, measured: set_payload_max_length caps Content-Length
// bodies only - a chunked body (or a body without a length, read to the end of the connection)
// is read whole into memory; its read timeout applies to each read, so a request trickling in a
// byte at a time holds its thread forever, and nothing caps the number of header lines; any
// number of connections from one client are served, so one client can hold every thread.
//
// Here each connection is served by this class (process_and_close_socket) through a Stream of its
// own that gives every request a deadline and a byte budget, and httplib parses and routes each
// request (process_request). Before a body is read, the request's framing is checked:
//   - Content-Length over max_body_bytes: 413 without reading the body;
//   - Transfer-Encoding: chunked: read up to ~2 x max_body_bytes on the wire, then 413 (handlers
//     refuse a decoded body over max_body_bytes: the wire budget includes the chunk framing);
//   - a body-carrying method without a length: 411; any Content-Encoding: 415 (no decompression
//     bombs); both or repeated lengths, another transfer coding: 400 / 501.
// A refused request's connection is closed after its response (the unread rest of its body
// must not be parsed as a further request), briefly draining what the client still sends so
// that it can read the response. The accept loop stays httplib's: it only accepts and queues;
// refusals (429 for a client over its cap) are written by the request threads, at once.
#pragma once

// clang-format off
#include <httplib.h>
// clang-format on

#include <atomic>
#include <cstddef>
#include <map>
#include <mutex>
#include <string>

#include "web/connection_limits.h"

namespace retarget {

class GuardedHttpServer : public httplib::Server {
 public:
  // max_body_bytes: the largest request body; threads: request threads (each serves one
  // connection at a time). A client is served on at most limits.per_client connections at once;
  // per_client 0 (the default) is half the threads (at least one), so that one slow or greedy
  // client leaves threads for the others and for its own refusals. Installs its own pre-routing, error
  // and 100-continue handlers: use set_error_responder, not set_error_handler, and no pre-routing handler of your own.
  GuardedHttpServer(const ConnectionLimits& limits, size_t max_body_bytes, int threads);

  // Fills error responses that have no body yet (unknown paths, 405, and this class's refusals:
  // 400, 408, 411, 413, 415, 431, 501) from res.status.
  void set_error_responder(Handler responder);

  // Listens on host:port, or on any free port of host when port is 0; returns the port. Throws
  // retarget::Error naming host:port when it cannot (the port in use, an address not this
  // machine's).
  int listen_on(const std::string& host, int port);

 protected:
  bool process_and_close_socket(socket_t sock) override;

 private:
  class GuardedStream;
  struct Connection;

  HandlerResponse screen(const httplib::Request& req, httplib::Response& res);
  void respond_to_error(const httplib::Request& req, httplib::Response& res);
  bool admit(const std::string& client);
  void leave(const std::string& client);
  bool stopping() const;

  ConnectionLimits limits_;
  size_t max_body_bytes_;
  Handler responder_;
  std::atomic<int> waiting_{0};  // accepted connections no thread has taken up yet
  std::mutex clients_mutex_;
  std::map<std::string, int> clients_;  // connections being served, by client address
};

}  // namespace retarget
