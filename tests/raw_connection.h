// A raw TCP client for the project's HTTP servers' tests (web/guarded_http_server.h): what
// httplib's client does not send (chunked bodies, half-sent requests), from any loopback address
// (so that one test can be several clients), and the slow-client check every server must pass.
#pragma once

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <memory>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

namespace retarget::test {

// A raw TCP connection to the server, for what httplib's client does not send: chunked bodies,
// half-sent requests. `from`: the local address to connect from (any of 127.0.0.0/8 is this
// machine), so that one test can be several clients.
class RawConnection {
 public:
  explicit RawConnection(int port, const char* from = "127.0.0.1") {
    fd_ = ::socket(AF_INET, SOCK_STREAM, 0);
    REQUIRE(fd_ >= 0);
    sockaddr_in local{};
    local.sin_family = AF_INET;
    ::inet_pton(AF_INET, from, &local.sin_addr);
    REQUIRE(::bind(fd_, reinterpret_cast<sockaddr*>(&local), sizeof(local)) == 0);
    sockaddr_in server{};
    server.sin_family = AF_INET;
    server.sin_port = htons(static_cast<uint16_t>(port));
    ::inet_pton(AF_INET, "127.0.0.1", &server.sin_addr);
    REQUIRE(::connect(fd_, reinterpret_cast<sockaddr*>(&server), sizeof(server)) == 0);
  }
  ~RawConnection() { ::close(fd_); }
  RawConnection(const RawConnection&) = delete;
  RawConnection& operator=(const RawConnection&) = delete;

  // False once the server has closed or reset the connection.
  bool send_all(std::string_view data) {
    while (!data.empty()) {
      const ssize_t n = ::send(fd_, data.data(), data.size(), MSG_NOSIGNAL);
      if (n <= 0) return false;
      data.remove_prefix(static_cast<size_t>(n));
    }
    return true;
  }
  // True when the server has sent something (or closed) already.
  bool answered() const {
    pollfd p{fd_, POLLIN, 0};
    return ::poll(&p, 1, 0) > 0;
  }
  // What the server sends until it closes the connection; gives up after `seconds` (generous: a
  // bound, not a measurement), with `closed` false.
  std::string read_until_closed(double seconds = 60) {
    std::string text;
    const auto until = std::chrono::steady_clock::now() + std::chrono::milliseconds(static_cast<int>(seconds * 1000));
    closed = false;
    while (std::chrono::steady_clock::now() < until) {
      pollfd p{fd_, POLLIN, 0};
      if (::poll(&p, 1, 100) <= 0) continue;
      char buffer[4096];
      const ssize_t n = ::recv(fd_, buffer, sizeof(buffer), 0);
      if (n <= 0) {
        closed = true;
        break;
      }
      text.append(buffer, static_cast<size_t>(n));
    }
    return text;
  }
  // One response, read up to the end of its body (Content-Length); empty if none arrives within
  // `seconds` (a bound, not a measurement).
  std::string read_response(double seconds = 60) {
    std::string text;
    const auto until = std::chrono::steady_clock::now() + std::chrono::milliseconds(static_cast<int>(seconds * 1000));
    while (std::chrono::steady_clock::now() < until) {
      const size_t head = text.find("\r\n\r\n");
      if (head != std::string::npos) {
        const size_t at = text.find("Content-Length: ");
        const size_t length = at < head ? std::stoul(text.substr(at + 16)) : 0;
        if (text.size() >= head + 4 + length) return text;
      }
      pollfd p{fd_, POLLIN, 0};
      if (::poll(&p, 1, 100) <= 0) continue;
      char buffer[4096];
      const ssize_t n = ::recv(fd_, buffer, sizeof(buffer), 0);
      if (n <= 0) break;
      text.append(buffer, static_cast<size_t>(n));
    }
    return {};
  }
  bool closed = false;

 private:
  int fd_ = -1;
};

// The status of a raw response ("HTTP/1.1 413 ..." -> 413), 0 for none.
inline int raw_status(const std::string& response) {
  if (response.rfind("HTTP/1.1 ", 0) != 0 || response.size() < 12) return 0;
  return std::stoi(response.substr(9, 3));
}

inline std::string raw_body(const std::string& response) {
  const size_t end = response.find("\r\n\r\n");
  return end == std::string::npos ? std::string() : response.substr(end + 4);
}

// Every server's guard against slow clients, over loopback: `slow` connections from 127.0.0.2
// send a request line and never finish their headers (the server's request deadline must be
// longer than this check). The client's cap of connections served at once (`cap`) holds; each
// one beyond it is refused with 429 at once; and a GET `path` from another client (127.0.0.3) is
// served with 200 while they are held.
inline void check_slow_clients_are_contained(int port, int slow, int cap, const std::string& path = "/") {
  std::vector<std::unique_ptr<RawConnection>> all, held, refused;
  for (int i = 0; i < slow; ++i) {
    all.push_back(std::make_unique<RawConnection>(port, "127.0.0.2"));
    REQUIRE(all.back()->send_all("GET / HTTP/1.1\r\nHost: 127.0.0.1\r\nX-Slow: "));
  }
  // Served connections answer nothing until their request is whole; refused ones get 429 and are
  // closed: wait (generously: a bound, not a measurement) until all but `cap` have answered.
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  auto answered = [&] {
    int n = 0;
    for (const auto& c : all) n += c->answered();
    return n;
  };
  while (answered() < slow - cap && std::chrono::steady_clock::now() < until)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  std::this_thread::sleep_for(std::chrono::milliseconds(200));  // none more would answer
  for (auto& c : all) (c->answered() ? refused : held).push_back(std::move(c));
  CHECK(static_cast<int>(held.size()) == cap);
  for (auto& c : refused) {
    CHECK(raw_status(c->read_until_closed()) == 429);
    CHECK(c->closed);
  }
  RawConnection other(port, "127.0.0.3");
  REQUIRE(other.send_all("GET " + path + " HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n"));
  CHECK(raw_status(other.read_until_closed()) == 200);
  for (auto& c : held) CHECK_FALSE(c->answered());  // still held, not dropped
}

}  // namespace retarget::test
