#include "web/guarded_http_server.h"

#include <arpa/inet.h>
#include <fmt/format.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <functional>

#include "core/error.h"

namespace retarget {

namespace {

using Clock = std::chrono::steady_clock;

Clock::time_point after(double seconds) {
  return Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds));
}

// Waits are cut into slices so that a stopping server, or a connection waiting for a thread, is
// noticed within one slice.
constexpr int kSliceMs = 50;

int slice_until(Clock::time_point until) {
  const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(until - Clock::now()).count();
  return static_cast<int>(std::clamp<long long>(left, 0, kSliceMs));
}

// A refused request's connection: what the client still sends is read and dropped for this long
// (or this many bytes) so that closing does not reset the connection before it reads the refusal.
constexpr double kLingerSeconds = 1.0;
constexpr size_t kLingerBytes = size_t{1} << 20;

// The address a connection comes from, the unit of the per-client cap: IPv4 (also when mapped into
// IPv6) as dotted quad, IPv6 as its /64 (one host usually holds a whole /64).
std::string client_of(socket_t sock) {
  sockaddr_storage address{};
  socklen_t length = sizeof(address);
  if (::getpeername(sock, reinterpret_cast<sockaddr*>(&address), &length) != 0) return "?";
  char text[INET6_ADDRSTRLEN] = {};
  if (address.ss_family == AF_INET) {
    ::inet_ntop(AF_INET, &reinterpret_cast<const sockaddr_in*>(&address)->sin_addr, text, sizeof(text));
    return text;
  }
  if (address.ss_family == AF_INET6) {
    const in6_addr& a = reinterpret_cast<const sockaddr_in6*>(&address)->sin6_addr;
    if (IN6_IS_ADDR_V4MAPPED(&a)) {
      ::inet_ntop(AF_INET, a.s6_addr + 12, text, sizeof(text));
      return text;
    }
    in6_addr prefix{};
    std::memcpy(prefix.s6_addr, a.s6_addr, 8);
    ::inet_ntop(AF_INET6, &prefix, text, sizeof(text));
    return std::string(text) + "/64";
  }
  return "?";
}

void address_of(socket_t sock, bool peer, std::string& ip, int& port) {
  sockaddr_storage address{};
  socklen_t length = sizeof(address);
  const int rc = peer ? ::getpeername(sock, reinterpret_cast<sockaddr*>(&address), &length)
                      : ::getsockname(sock, reinterpret_cast<sockaddr*>(&address), &length);
  if (rc != 0) return;
  char text[INET6_ADDRSTRLEN] = {};
  if (address.ss_family == AF_INET) {
    const auto* a = reinterpret_cast<const sockaddr_in*>(&address);
    ::inet_ntop(AF_INET, &a->sin_addr, text, sizeof(text));
    port = ntohs(a->sin_port);
  } else if (address.ss_family == AF_INET6) {
    const auto* a = reinterpret_cast<const sockaddr_in6*>(&address);
    ::inet_ntop(AF_INET6, &a->sin6_addr, text, sizeof(text));
    port = ntohs(a->sin6_port);
  }
  ip = text;
}

// Reads and drops what the client still sends, for a bounded time and amount.
void drain(socket_t sock, double seconds, size_t bytes) {
  const Clock::time_point until = after(seconds);
  char sink[4096];
  size_t dropped = 0;
  while (dropped < bytes && Clock::now() < until) {
    pollfd p{sock, POLLIN, 0};
    const int ready = ::poll(&p, 1, slice_until(until));
    if (ready < 0 && errno == EINTR) continue;
    if (ready <= 0) continue;
    const ssize_t n = ::recv(sock, sink, sizeof(sink), MSG_DONTWAIT);
    if (n < 0 && (errno == EINTR || errno == EAGAIN || errno == EWOULDBLOCK)) continue;
    if (n <= 0) return;
    dropped += static_cast<size_t>(n);
  }
}

// A connection over its client's cap: 429, closed at once.
void refuse_connection(socket_t sock) {
  static const std::string body =
      R"({"error": "too many connections from your address at once: close some and try again"})";
  static const std::string response = fmt::format(
      "HTTP/1.1 429 Too Many Requests\r\nContent-Type: application/json\r\nContent-Length: {}\r\n"
      "Connection: close\r\nRetry-After: 1\r\nCache-Control: no-store\r\n\r\n{}",
      body.size(), body);
  [[maybe_unused]] const ssize_t sent = ::send(sock, response.data(), response.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
  ::shutdown(sock, SHUT_WR);
  drain(sock, 0, 1 << 16);  // what already arrived, without waiting: fewer resets before the 429 is read
  ::close(sock);
}

bool same_text(const std::string& a, const char* b) {
  const size_t n = std::strlen(b);
  if (a.size() != n) return false;
  for (size_t i = 0; i < n; ++i)
    if (std::tolower(static_cast<unsigned char>(a[i])) != std::tolower(static_cast<unsigned char>(b[i]))) return false;
  return true;
}

// The methods whose body cpp-httplib reads (its detail::expect_content).
bool reads_body(const std::string& method) {
  return method == "POST" || method == "PUT" || method == "PATCH" || method == "DELETE" || method == "PRI";
}

// Content-Length's value: 1 to 18 digits and nothing else, else -1.
long long content_length(const std::string& value) {
  if (value.empty() || value.size() > 18) return -1;
  long long n = 0;
  for (char c : value) {
    if (c < '0' || c > '9') return -1;
    n = 10 * n + (c - '0');
  }
  return n;
}

}  // namespace

// The socket as httplib sees it, with a deadline and a byte budget per request: reads fail when
// the deadline passes (a timeout) or the budget is spent (too large). Bytes read ahead of the
// current request (a pipelined next one) stay buffered for it.
class GuardedHttpServer::GuardedStream final : public httplib::Stream {
 public:
  enum class Failure { none, timeout, budget, closed };

  GuardedStream(socket_t sock, double write_seconds, std::function<bool()> stopping)
      : sock_(sock), write_seconds_(write_seconds), stopping_(std::move(stopping)) {}

  // A new request: its reads end at `deadline` or after `budget` bytes.
  void expect(Clock::time_point deadline, size_t budget) {
    deadline_ = deadline;
    budget_ = budget;
    failure_ = Failure::none;
  }
  // The rest of the request (its body) may take `budget` more bytes.
  void allow(size_t budget) { budget_ = budget; }
  Failure failure() const { return failure_; }

  // True once a byte is there to read (or the client closed: the read tells); false at `until`, on
  // stop, or as soon as `give_up()` says so.
  bool wait_readable(Clock::time_point until, const std::function<bool()>& give_up = nullptr) {
    while (begin_ == end_) {
      if (stopping_() || (give_up && give_up())) return false;
      if (Clock::now() >= until) return false;
      pollfd p{sock_, POLLIN, 0};
      const int ready = ::poll(&p, 1, slice_until(until));
      if (ready > 0) return true;
      if (ready < 0 && errno != EINTR) return false;
    }
    return true;
  }

  bool is_readable() const override {
    if (begin_ < end_) return true;
    pollfd p{sock_, POLLIN, 0};
    return ::poll(&p, 1, 0) > 0;
  }

  bool is_writable() const override {
    pollfd p{sock_, POLLOUT, 0};
    return ::poll(&p, 1, static_cast<int>(write_seconds_ * 1000)) > 0;
  }

  ssize_t read(char* ptr, size_t size) override {
    if (failure_ != Failure::none) return -1;
    if (budget_ == 0) {
      failure_ = Failure::budget;
      return -1;
    }
    if (begin_ == end_ && !fill()) return -1;
    const size_t n = std::min({size, end_ - begin_, budget_});
    std::memcpy(ptr, buffer_ + begin_, n);
    begin_ += n;
    budget_ -= n;
    return static_cast<ssize_t>(n);
  }

  ssize_t write(const char* ptr, size_t size) override {
    const Clock::time_point until = after(write_seconds_);
    for (;;) {
      const ssize_t n = ::send(sock_, ptr, size, MSG_NOSIGNAL | MSG_DONTWAIT);
      if (n >= 0) return n;
      if (errno == EINTR) continue;
      if (errno != EAGAIN && errno != EWOULDBLOCK) return -1;
      pollfd p{sock_, POLLOUT, 0};
      if (Clock::now() >= until || stopping_()) return -1;
      ::poll(&p, 1, slice_until(until));
    }
  }

  void get_remote_ip_and_port(std::string& ip, int& port) const override { address_of(sock_, true, ip, port); }
  void get_local_ip_and_port(std::string& ip, int& port) const override { address_of(sock_, false, ip, port); }
  socket_t socket() const override { return sock_; }

 private:
  bool fill() {
    if (!wait_readable(deadline_)) {
      failure_ = Clock::now() >= deadline_ ? Failure::timeout : Failure::closed;
      return false;
    }
    for (;;) {
      const ssize_t n = ::recv(sock_, buffer_, sizeof(buffer_), MSG_DONTWAIT);
      if (n > 0) {
        begin_ = 0;
        end_ = static_cast<size_t>(n);
        return true;
      }
      if (n < 0 && errno == EINTR) continue;
      if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) {
        if (wait_readable(deadline_)) continue;
        failure_ = Clock::now() >= deadline_ ? Failure::timeout : Failure::closed;
        return false;
      }
      failure_ = Failure::closed;
      return false;
    }
  }

  socket_t sock_;
  double write_seconds_;
  std::function<bool()> stopping_;
  Clock::time_point deadline_ = Clock::now();
  size_t budget_ = 0;
  Failure failure_ = Failure::none;
  char buffer_[4096];
  size_t begin_ = 0, end_ = 0;
};

struct GuardedHttpServer::Connection {
  GuardedStream stream;
  bool in_body = false;  // the current request's headers are read
  bool close = false;    // close after the current response
};

namespace {

// The connection the calling request thread serves: httplib runs a connection's requests, and
// their handlers, on the thread that took the connection up.
thread_local void* current_connection = nullptr;

// Counts the accepted connections that wait for a thread, so that idle kept-alive connections
// can give theirs up.
class CountingThreadPool final : public httplib::TaskQueue {
 public:
  CountingThreadPool(size_t threads, std::atomic<int>& waiting) : pool_(threads), waiting_(waiting) {}
  void enqueue(std::function<void()> job) override {
    ++waiting_;
    pool_.enqueue([this, job = std::move(job)] {
      --waiting_;
      job();
    });
  }
  void shutdown() override { pool_.shutdown(); }

 private:
  httplib::ThreadPool pool_;
  std::atomic<int>& waiting_;
};

}  // namespace

GuardedHttpServer::GuardedHttpServer(const ConnectionLimits& limits, size_t max_body_bytes, int threads)
    : limits_(limits), max_body_bytes_(max_body_bytes) {
  limits_.validate();
  // By default one client never holds more than half the threads: the rest answer the others
  // (and write this client's 429s) at once.
  if (limits_.per_client == 0) limits_.per_client = std::max(1, threads / 2);
  set_payload_max_length(max_body_bytes);
  set_keep_alive_max_count(static_cast<size_t>(limits.requests_per_connection));
  set_keep_alive_timeout(static_cast<time_t>(std::ceil(limits.idle_seconds)));
  new_task_queue = [this, threads] { return new CountingThreadPool(static_cast<size_t>(threads), waiting_); };
  set_pre_routing_handler([this](const httplib::Request& req, httplib::Response& res) { return screen(req, res); });
  set_error_handler([this](const httplib::Request& req, httplib::Response& res) { respond_to_error(req, res); });
  // A declared body over the limit is refused before the client sends it.
  set_expect_100_continue_handler([this](const httplib::Request& req, httplib::Response& res) {
    const long long length = content_length(req.get_header_value("Content-Length"));
    if (length < 0 || static_cast<unsigned long long>(length) <= max_body_bytes_) return 100;
    if (auto* c = static_cast<Connection*>(current_connection)) c->close = true;
    res.status = 413;
    return 413;
  });
}

int GuardedHttpServer::listen_on(const std::string& host, int port) {
  if (port == 0) {
    const int bound = bind_to_any_port(host);
    if (bound <= 0) throw Error(fmt::format("{}:0", host), "cannot listen on any port of this address");
    return bound;
  }
  if (!bind_to_port(host, port))
    throw Error(fmt::format("{}:{}", host, port),
                "cannot listen here (the port is in use or the address is not this machine's)");
  return port;
}

void GuardedHttpServer::set_error_responder(Handler responder) { responder_ = std::move(responder); }

bool GuardedHttpServer::stopping() const { return svr_sock_ == INVALID_SOCKET; }

bool GuardedHttpServer::admit(const std::string& client) {
  std::lock_guard<std::mutex> lock(clients_mutex_);
  int& served = clients_[client];
  if (served >= limits_.per_client) {
    if (served == 0) clients_.erase(client);
    return false;
  }
  ++served;
  return true;
}

void GuardedHttpServer::leave(const std::string& client) {
  std::lock_guard<std::mutex> lock(clients_mutex_);
  const auto it = clients_.find(client);
  if (it != clients_.end() && --it->second <= 0) clients_.erase(it);
}

bool GuardedHttpServer::process_and_close_socket(socket_t sock) {
  const std::string client = client_of(sock);
  if (!admit(client)) {
    refuse_connection(sock);
    return true;
  }
  Connection c{GuardedStream(sock, limits_.write_seconds, [this] { return stopping(); })};
  current_connection = &c;
  for (int served = 0; served < limits_.requests_per_connection && !stopping(); ++served) {
    // The first request must arrive within request_seconds of the connection reaching this thread;
    // a later one may first idle, but not while another connection waits for a thread.
    if (served > 0 && !c.stream.wait_readable(after(limits_.idle_seconds), [this] { return waiting_ > 0; })) break;
    c.stream.expect(after(limits_.request_seconds), limits_.max_header_bytes);
    c.in_body = false;
    bool client_closes = false;
    const bool last = served + 1 == limits_.requests_per_connection;
    if (!process_request(c.stream, last, client_closes, nullptr)) break;
    if (client_closes || c.close) break;
  }
  current_connection = nullptr;
  if (c.close) {
    ::shutdown(sock, SHUT_WR);
    drain(sock, kLingerSeconds, kLingerBytes);
  }
  ::shutdown(sock, SHUT_RDWR);
  ::close(sock);
  leave(client);
  return true;
}

// After the headers, before the body: the checks the body's framing needs.
httplib::Server::HandlerResponse GuardedHttpServer::screen(const httplib::Request& req, httplib::Response& res) {
  auto* c = static_cast<Connection*>(current_connection);
  if (!c) return HandlerResponse::Unhandled;
  c->in_body = true;
  const auto refuse = [&](int status) {
    res.status = status;
    c->close = true;
    return HandlerResponse::Handled;
  };

  size_t fields = req.headers.size();
  for (const char* added : {"REMOTE_ADDR", "REMOTE_PORT", "LOCAL_ADDR", "LOCAL_PORT"})
    fields -= std::min(fields, req.get_header_value_count(added));
  if (fields > static_cast<size_t>(limits_.max_header_fields)) return refuse(431);

  const size_t codings = req.get_header_value_count("Transfer-Encoding");
  const size_t lengths = req.get_header_value_count("Content-Length");
  const bool body_read = reads_body(req.method);
  if (codings > 1 || lengths > 1 || (codings == 1 && lengths == 1)) return refuse(400);
  if (req.has_header("Content-Encoding") && !same_text(req.get_header_value("Content-Encoding"), "identity"))
    return refuse(415);
  if (codings == 1) {
    if (!same_text(req.get_header_value("Transfer-Encoding"), "chunked")) return refuse(501);
    // httplib leaves a body it does not read in the connection: never parse it as a request.
    if (!body_read) c->close = true;
    c->stream.allow(2 * max_body_bytes_ + 1024);
    return HandlerResponse::Unhandled;
  }
  if (lengths == 1) {
    const long long length = content_length(req.get_header_value("Content-Length"));
    if (length < 0) return refuse(400);
    if (static_cast<unsigned long long>(length) > max_body_bytes_) return refuse(413);
    if (!body_read && length > 0) c->close = true;
    c->stream.allow(static_cast<size_t>(length));
    return HandlerResponse::Unhandled;
  }
  // No length: httplib would read the body up to the end of the connection.
  if (body_read) return refuse(411);
  c->stream.allow(0);
  return HandlerResponse::Unhandled;
}

void GuardedHttpServer::respond_to_error(const httplib::Request& req, httplib::Response& res) {
  auto* c = static_cast<Connection*>(current_connection);
  if (c && res.body.empty()) {
    // httplib's own refusal, or a read this class cut short.
    switch (c->stream.failure()) {
      case GuardedStream::Failure::timeout:
        res.status = 408;
        break;
      case GuardedStream::Failure::budget:
        res.status = c->in_body ? 413 : 431;
        break;
      default:
        break;
    }
    // The connection may hold the unread rest of this request: close it.
    if (res.status != 404 && res.status != 405) c->close = true;
  }
  if (responder_) responder_(req, res);
  if (c && c->close) res.set_header("Connection", "close");
}

}  // namespace retarget
