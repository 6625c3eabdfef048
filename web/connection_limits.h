// Limits on the web annotation tool's HTTP connections (enforced by
// web/guarded_http_server.h), so that no client - slow, greedy or hostile - holds the request
// threads or the memory the others need. Each request thread serves one connection at a time, so
// these bound how long and how many threads a client can hold:
//   - a connection's first request must arrive whole (line, headers and body) within
//     request_seconds of the connection reaching a thread; a later one within request_seconds of
//     its first byte; else 408 and the connection is closed;
//   - a kept-alive connection waits idle_seconds at most for its next request, and gives its
//     thread up at once when another connection waits for one;
//   - at most per_client connections from one address are served at once (IPv6: one /64; 0, the
//     default: half the server's threads); a
//     further one gets 429 and is closed at once, without waiting for the others. Several people
//     behind one address (a NAT, a reverse proxy, an SSH tunnel) share this cap;
//   - request line and headers: max_header_bytes and max_header_fields, else 431 and closed.
#pragma once

#include <cstddef>
#include <string>

namespace retarget {

struct ConnectionLimits {
  double request_seconds = 5;         // a request must arrive whole within this; 0.1..600
  double idle_seconds = 5;            // an idle kept-alive connection is closed after this; 0.1..600
  double write_seconds = 10;          // a response write making no progress this long fails; 0.1..600
  int requests_per_connection = 100;  // then the connection is closed (clients open another); 1..100000
  int per_client = 0;                 // connections served at once per client address; 0 = half the threads; 0..4096
  size_t max_header_bytes = 32768;    // request line + headers; 1 KiB..1 MiB
  int max_header_fields = 100;        // header lines per request; 1..10000

  // Throws retarget::Error naming `key_path`.<field> for a value out of range.
  void validate(const std::string& key_path = "serve.connections") const;
};

}  // namespace retarget
