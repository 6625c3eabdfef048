// The web annotation tool's server without a browser: real HTTP over loopback (cpp-httplib's
// client), a real SQLite store, real turntable PNGs of a sphere.
#include "annotate/annotation_server.h"

#include "web/token.h"

// Eigen (through geometry/) before httplib.h: OpenSSL's headers, which httplib.h pulls in, define
// macros that break Eigen's product kernels.
// clang-format off
#include "geometry/primitive_meshes.h"
#include "render/render.h"
#include <httplib.h>
// clang-format on

#include <arpa/inet.h>
#include <fmt/format.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <catch2/catch.hpp>
#include <chrono>
#include <fstream>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <set>
#include <thread>
#include <vector>

#include "annotate/annotation_store.h"
#include "annotate_test_support.h"
#include "core/random.h"
#include "raw_connection.h"

namespace retarget {
namespace {

using nlohmann::json;
using test::make_test_group;
using test::raw_body;
using test::raw_status;
using test::RawConnection;
using test::scratch_dir;
using test::TestGroup;

// Real pictures: a small sphere's turntable, the sample id in the picture's size so that
// pictures of different candidates differ.
TurntablePictures sphere_pictures(std::atomic<int>* renders = nullptr) {
  TurntablePictures p;
  p.frames = 3;
  auto draw = [renders](int size) {
    if (renders) ++*renders;
    RenderOptions o;
    o.width = o.height = size;
    o.supersample = 1;
    const Mesh sphere = uv_sphere(8, 12);
    return encode_png(render_turntable(sphere, sphere.vertices, 3, 30, o));
  };
  p.anchor = [draw](const std::string&) { return draw(24); };
  p.candidate = [draw](int64_t sample) { return draw(16 + static_cast<int>(sample % 8)); };
  return p;
}

// A store with `groups` groups of `candidates` candidates (sample ids 1000 k + i).
std::string make_store(const std::string& name, int groups, int candidates) {
  const std::string path = (scratch_dir(name) / "annotations.db").string();
  AnnotationStore store = AnnotationStore::open(path);
  for (int k = 0; k < groups; ++k) {
    const TestGroup g = make_test_group(fmt::format("expression{:03d}", k), candidates, 1000 * k);
    store.create_group(g.label, g.samples, g.distances, static_cast<uint64_t>(k + 1));
  }
  return path;
}

// A server on a free loopback port, serving from a thread of its own until destroyed.
struct RunningServer {
  AnnotationServer server;
  std::thread thread;

  RunningServer(const std::string& db, ServerOptions options, TurntablePictures pictures = sphere_pictures())
      : server(db, std::move(pictures), with_free_port(options)) {
    server.bind();
    thread = std::thread([this] { server.run(); });
  }
  ~RunningServer() {
    server.stop();
    thread.join();
  }
  static ServerOptions with_free_port(ServerOptions o) {
    o.port = 0;
    o.prerender = false;
    return o;
  }
  httplib::Client client() const {
    httplib::Client c("127.0.0.1", server.port());
    c.set_read_timeout(60, 0);
    return c;
  }
};

httplib::Headers bearer(const std::string& token) { return {{"Authorization", "Bearer " + token}}; }

json parse(const httplib::Result& r) {
  REQUIRE(r);
  return json::parse(r->body);
}

std::string sign_in(httplib::Client& c, const std::string& name) {
  auto r = c.Post("/api/signin", json{{"name", name}}.dump(), "application/json");
  REQUIRE(r);
  INFO(r->body);
  REQUIRE(r->status == 200);
  return json::parse(r->body).at("token").get<std::string>();
}

json post(httplib::Client& c, const std::string& path, const std::string& token, const json& body, int expected = 200) {
  auto r = c.Post(path.c_str(), bearer(token), body.dump(), "application/json");
  REQUIRE(r);
  INFO(path << " " << body.dump() << " -> " << r->status << " " << r->body);
  CHECK(r->status == expected);
  return json::parse(r->body);
}

int status_of(const httplib::Result& r) { return r ? r->status : -1; }

std::string chunk(std::string_view data) { return fmt::format("{:x}\r\n{}\r\n", data.size(), data); }

// This process's resident memory (the server runs inside the test), KiB.
long resident_kib() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line))
    if (line.rfind("VmRSS:", 0) == 0) return std::stol(line.substr(6));
  return 0;
}

}  // namespace

TEST_CASE("serve: pages are embedded; path tricks never reach the file system", "[server]") {
  const std::string db = make_store("server_paths", 2, 4);
  RunningServer s(db, ServerOptions{});
  httplib::Client c = s.client();

  auto page = c.Get("/");
  REQUIRE(page);
  CHECK(page->status == 200);
  CHECK(page->get_header_value("Content-Type").find("text/html") == 0);
  CHECK(page->body.find("/static/app.js") != std::string::npos);
  for (const char* asset :
       {"/static/app.js", "/static/api.js", "/static/overview.js", "/static/style.css", "/overview"}) {
    INFO(asset);
    CHECK(status_of(c.Get(asset)) == 200);
  }

  for (const char* trick :
       {"/annotations.db", "/../annotations.db", "/static/../annotations.db", "/static/%2e%2e/annotations.db",
        "/static/..%2Fannotations.db", "/static/app.js/../../annotations.db", "//etc/passwd", "/static//etc/passwd",
        "/img/candidate/..%2F..%2Fannotations.db", "/img/anchor/1.png/../../../annotations.db",
        "/static/%2Fetc%2Fpasswd", "/static/index.html", "/static/app.js%00.css", "/img/candidate/1000000000000.png"}) {
    INFO(trick);
    auto r = c.Get(trick);
    REQUIRE(r);
    CHECK(r->status == 404);
    CHECK(r->body.find("SQLite format") == std::string::npos);
    CHECK(r->body.find("root:") == std::string::npos);
    CHECK(json::parse(r->body).contains("error"));
  }
}

TEST_CASE("serve: sign-in names, tokens and bad requests are refused with a reason", "[server]") {
  const std::string db = make_store("server_validation", 2, 4);
  RunningServer s(db, ServerOptions{});
  httplib::Client c = s.client();

  for (const json& bad :
       {json{{"name", ""}}, json{{"name", std::string(41, 'a')}}, json{{"name", "../etc"}}, json{{"name", "<script>"}},
        json{{"name", 42}}, json{{"nom", "ana"}}, json{{"name", " ana"}}}) {
    INFO(bad.dump());
    auto r = c.Post("/api/signin", bad.dump(), "application/json");
    CHECK(status_of(r) == 400);
  }
  CHECK(status_of(c.Post("/api/signin", "{not json", "application/json")) == 400);
  CHECK(status_of(c.Post("/api/signin", "[1, 2]", "application/json")) == 400);

  const std::string ana = sign_in(c, "ana");
  // A second sign-in as "ana" (another browser) is refused: names are not shared.
  auto again = c.Post("/api/signin", json{{"name", "ana"}}.dump(), "application/json");
  REQUIRE(again);
  CHECK(again->status == 409);
  CHECK(json::parse(again->body).at("error").get<std::string>().find("signed in elsewhere") != std::string::npos);

  // No token, an unknown token, a malformed header.
  auto no_token = c.Post("/api/next", "", "application/json");
  CHECK(status_of(no_token) == 401);
  CHECK(json::parse(no_token->body).at("error").get<std::string>().find("sign in first") != std::string::npos);
  CHECK(status_of(c.Post("/api/next", bearer(std::string(32, 'f')), "", "application/json")) == 401);
  CHECK(status_of(c.Post("/api/next", {{"Authorization", "Basic " + ana}}, "", "application/json")) == 401);
  CHECK(status_of(c.Get("/img/anchor/1.png")) == 401);

  const json next = post(c, "/api/next", ana, json::object());
  const int64_t id = next.at("assignment").at("comparison").get<int64_t>();
  // Bad ids and bodies: unknown comparison 404, wrong types and answers 400.
  CHECK(post(c, "/api/answer", ana, {{"comparison", 999999}, {"answer", "left"}}, 404).at("error") ==
        "no comparison 999999");
  CHECK(post(c, "/api/answer", ana, {{"comparison", "1"}, {"answer", "left"}}, 400).at("error") ==
        "'comparison' must be an integer id");
  post(c, "/api/answer", ana, {{"comparison", 1.5}, {"answer", "left"}}, 400);
  post(c, "/api/answer", ana, {{"comparison", id}, {"answer", "maybe"}}, 400);
  post(c, "/api/answer", ana, {{"comparison", id}}, 400);
  CHECK(post(c, "/api/release", ana, {{"comparison", -3}}, 400).at("error") ==
        "'comparison' must be an id from 1 to 9223372036854775807, got -3");
  // 2^63 is not echoed back wrapped into a negative id.
  CHECK(post(c, "/api/answer", ana, {{"comparison", uint64_t{1} << 63}, {"answer", "left"}}, 400).at("error") ==
        "'comparison' must be an id from 1 to 9223372036854775807, got 9223372036854775808");
  auto missing_group = c.Get("/img/anchor/999.png", bearer(ana));
  CHECK(status_of(missing_group) == 404);
  CHECK(json::parse(missing_group->body).at("error") == "no group 999");
  CHECK(status_of(c.Get("/img/candidate/77.png", bearer(ana))) == 404);  // not a candidate of any group

  // Pictures: real PNG turntables with their frame count.
  const std::string left_url = next.at("assignment").at("images").at("left").get<std::string>();
  auto picture = c.Get(left_url.c_str(), bearer(ana));
  REQUIRE(picture);
  CHECK(picture->status == 200);
  CHECK(picture->get_header_value("Content-Type") == "image/png");
  CHECK(picture->get_header_value("X-Turntable-Frames") == "3");
  CHECK(picture->body.substr(1, 3) == "PNG");

  // Undo with nothing answered: refused, with a reason.
  const json undo = post(c, "/api/undo", ana, json::object(), 409);
  CHECK(undo.contains("error"));

  // Ben cannot answer the comparison Ana holds.
  const std::string ben = sign_in(c, "ben");
  const json refused = post(c, "/api/answer", ben, {{"comparison", id}, {"answer", "left"}}, 409);
  CHECK(refused.at("error").get<std::string>().find("ana") != std::string::npos);
  CHECK(refused.at("error").get<std::string>().find(db) == std::string::npos);  // no server paths leak
  CHECK_THAT(refused.at("error").get<std::string>(),
             Catch::EndsWith("ask for the next comparison to go on"));  // not the store's API

  // Ana answers; the same comparison cannot be answered twice.
  const json answered = post(c, "/api/answer", ana, {{"comparison", id}, {"answer", "left"}});
  CHECK(answered.at("result").at("status") == "decided");
  CHECK(answered.at("result").at("winner") == next.at("assignment").at("left"));
  CHECK(answered.at("progress").at("done") == 1);
  post(c, "/api/answer", ana, {{"comparison", id}, {"answer", "right"}}, 409);
}

TEST_CASE("serve: bodies over the limit get 413 and change nothing", "[server]") {
  const std::string db = make_store("server_body", 1, 4);
  ServerOptions o;
  o.max_body_bytes = 1024;
  RunningServer s(db, o);
  httplib::Client c = s.client();
  const std::string huge = json{{"name", "ana"}, {"padding", std::string(4096, 'x')}}.dump();
  auto r = c.Post("/api/signin", huge, "application/json");
  REQUIRE(r);
  CHECK(r->status == 413);
  CHECK(json::parse(r->body).at("error") == "the request body is too large");
  CHECK_FALSE(AnnotationStore::open(db).has_session("ana"));
  // Just under the limit is fine.
  sign_in(c, "ana");
}

TEST_CASE("serve: a chunked body over the limit is refused without being read whole", "[server][limits]") {
  const std::string db = make_store("server_chunked", 1, 4);
  RunningServer s(db, ServerOptions{});  // bodies up to 4 KiB
  const std::string head =
      "POST /api/signin HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Type: application/json\r\n"
      "Transfer-Encoding: chunked\r\n\r\n";

  // 100 MB in 64 KiB chunks, no sign-in needed; the client stops when the server answers or closes.
  const size_t total = 100u << 20;
  const long rss_before = resident_kib();
  RawConnection c(s.server.port());
  REQUIRE(c.send_all(head));
  const std::string payload(64u << 10, 'x');
  size_t sent = 0;
  bool refused_early = !c.send_all(chunk(R"({"name": "ana", "padding": ")"));
  while (!refused_early && sent < total) {
    if (c.answered() || !c.send_all(chunk(payload))) {
      refused_early = true;
      break;
    }
    sent += payload.size();
  }
  const std::string response = c.read_until_closed();
  const long rss_growth_kib = resident_kib() - rss_before;
  INFO("sent " << sent << " bytes; resident memory grew " << rss_growth_kib
               << " KiB; response: " << response.substr(0, 300));
  CHECK(refused_early);  // the server answered or closed before the 100 MB were sent
  CHECK(sent < total / 4);
  CHECK(raw_status(response) == 413);
  CHECK(json::parse(raw_body(response)).at("error") == "the request body is too large");
  CHECK(c.closed);
  CHECK(rss_growth_kib < 32 * 1024);  // 100 MB read whole would show here
  CHECK_FALSE(AnnotationStore::open(db).has_session("ana"));

  // A chunked body within the limit is read as any other.
  {
    RawConnection ok(s.server.port());
    REQUIRE(ok.send_all(head + chunk(R"({"name": )") + chunk(R"("ben"})") + "0\r\n\r\n"));
    const std::string r = ok.read_until_closed(5);  // kept alive: ends by the bound, not closed
    CHECK(raw_status(r) == 200);
    CHECK(r.find("\"token\"") != std::string::npos);
  }
  // Over the limit once decoded, even within the wire budget: 413.
  {
    RawConnection over(s.server.port());
    REQUIRE(
        over.send_all(head + chunk(json{{"name", "cy"}, {"padding", std::string(5000, 'x')}}.dump()) + "0\r\n\r\n"));
    CHECK(raw_status(over.read_until_closed(5)) == 413);
    CHECK_FALSE(AnnotationStore::open(db).has_session("cy"));
  }
}

TEST_CASE("serve: request framing that could smuggle or flood a body is refused", "[server][limits]") {
  const std::string db = make_store("server_framing", 1, 4);
  RunningServer s(db, ServerOptions{});
  const std::string signin = "POST /api/signin HTTP/1.1\r\nHost: 127.0.0.1\r\n";
  const std::string body = R"({"name": "ana"})";
  struct Case {
    const char* what;
    std::string request;
    int status;
  };
  const std::vector<Case> cases = {
      // Declared too large: refused before the body is sent (no body follows here).
      {"Content-Length over the limit", signin + "Content-Length: 104857600\r\n\r\n", 413},
      // Not "100 Continue" first: the client is told at once not to send it.
      {"Content-Length over the limit, 100-continue expected",
       signin + "Content-Length: 104857600\r\nExpect: 100-continue\r\n\r\n", 413},
      {"no length", signin + "\r\n" + body, 411},
      {"a compressed body", signin + "Content-Encoding: gzip\r\nContent-Length: 15\r\n\r\n" + body, 415},
      {"length and chunked", signin + "Content-Length: 15\r\nTransfer-Encoding: chunked\r\n\r\n" + body, 400},
      {"two lengths", signin + "Content-Length: 15\r\nContent-Length: 16\r\n\r\n" + body, 400},
      {"a bad length", signin + "Content-Length: 1e3\r\n\r\n" + body, 400},
      {"another transfer coding", signin + "Transfer-Encoding: gzip\r\n\r\n" + body, 501},
  };
  for (const Case& k : cases) {
    INFO(k.what);
    RawConnection c(s.server.port());
    REQUIRE(c.send_all(k.request));
    const std::string r = c.read_until_closed();
    CHECK(raw_status(r) == k.status);
    CHECK(json::parse(raw_body(r)).contains("error"));
    CHECK(c.closed);  // the rest of the request is never read as another one
  }
  CHECK_FALSE(AnnotationStore::open(db).has_session("ana"));

  // A body on a GET, which httplib does not read, is not parsed as a second request either.
  const std::string smuggled = signin + "Content-Length: 15\r\n\r\n" + body;
  RawConnection c(s.server.port());
  REQUIRE(c.send_all("GET / HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Length: " + std::to_string(smuggled.size()) +
                     "\r\n\r\n" + smuggled));
  const std::string r = c.read_until_closed();
  CHECK(raw_status(r) == 200);
  CHECK(c.closed);
  CHECK_FALSE(AnnotationStore::open(db).has_session("ana"));
}

TEST_CASE("serve: request headers are capped in size and number", "[server][limits]") {
  const std::string db = make_store("server_headers", 1, 4);
  ServerOptions o;
  o.connections.max_header_bytes = 8192;
  o.connections.max_header_fields = 20;
  RunningServer s(db, o);
  std::string many_bytes = "GET / HTTP/1.1\r\nHost: 127.0.0.1\r\n";
  for (int i = 0; i < 12; ++i) many_bytes += fmt::format("X-Filler-{}: {}\r\n", i, std::string(1000, 'a'));
  std::string many_fields = "GET / HTTP/1.1\r\nHost: 127.0.0.1\r\n";
  for (int i = 0; i < 25; ++i) many_fields += fmt::format("X-Field-{}: {}\r\n", i, i);
  for (const std::string& request : {many_bytes + "\r\n", many_fields + "\r\n"}) {
    RawConnection c(s.server.port());
    c.send_all(request);  // may fail part-way: the server stops reading at the limit
    const std::string r = c.read_until_closed();
    CHECK(raw_status(r) == 431);
    CHECK(c.closed);
  }
  // Within both limits: served.
  httplib::Client c = s.client();
  httplib::Headers fine;
  for (int i = 0; i < 10; ++i) fine.emplace(fmt::format("X-Field-{}", i), std::string(100, 'b'));
  CHECK(status_of(c.Get("/", fine)) == 200);
}

TEST_CASE("serve: slow connections time out; beyond its cap a client's connections are refused at once",
          "[server][limits]") {
  const std::string db = make_store("server_slow", 1, 4);
  ServerOptions o;
  o.threads = 4;
  o.connections.per_client = 2;
  o.connections.request_seconds = 3;
  RunningServer s(db, o);

  // More slow connections than threads, from one address: request line sent, headers never finished.
  std::vector<std::unique_ptr<RawConnection>> slow;
  for (int i = 0; i < 7; ++i) {
    slow.push_back(std::make_unique<RawConnection>(s.server.port()));
    REQUIRE(slow.back()->send_all("GET / HTTP/1.1\r\nHost: 127.0.0.1\r\nX-Slow: "));
  }
  // Each one is answered and closed: 429 at once beyond the cap, 408 at the deadline for the two
  // served (none waits for a thread first: the cap leaves two threads for the refusals).
  int refused = 0, timed_out = 0;
  for (auto& c : slow) {
    const std::string r = c->read_until_closed();
    CHECK(c->closed);
    refused += raw_status(r) == 429;
    timed_out += raw_status(r) == 408;
    if (raw_status(r) == 429)
      CHECK(json::parse(raw_body(r)).at("error").get<std::string>().find("too many connections") != std::string::npos);
  }
  CHECK(refused == 5);
  CHECK(timed_out == 2);
  // The deadline released them (once their clients close, as clients told "Connection: close"
  // do): a request from the same address is served.
  slow.clear();
  httplib::Client c = s.client();
  CHECK(status_of(c.Get("/")) == 200);
}

TEST_CASE("serve: one client's slow connections do not hold up another client", "[server][limits]") {
  const std::string db = make_store("server_fair", 1, 4);
  ServerOptions o;
  o.threads = 4;
  o.connections.per_client = 2;
  o.connections.request_seconds = 120;  // the slow client's connections stay held all through
  RunningServer s(db, o);

  // Client A (127.0.0.2): 6 slow connections, more than the threads. Two are served (held), the
  // (cap + 1)-th and later are refused with 429 at once.
  std::vector<std::unique_ptr<RawConnection>> held, refused;
  for (int i = 0; i < 6; ++i) {
    auto c = std::make_unique<RawConnection>(s.server.port(), "127.0.0.2");
    REQUIRE(c->send_all("GET / HTTP/1.1\r\nHost: 127.0.0.1\r\nX-Slow: "));
    // Served connections answer nothing until their request is whole; refused ones get 429 and
    // are closed: wait (generously) for one or the other before the next.
    const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(2);
    while (!c->answered() && std::chrono::steady_clock::now() < until)
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    (c->answered() ? refused : held).push_back(std::move(c));
  }
  REQUIRE(held.size() == 2);
  for (auto& c : refused) {
    CHECK(raw_status(c->read_until_closed()) == 429);
    CHECK(c->closed);
  }

  // Client B (127.0.0.3) is served while A's two connections are still held.
  RawConnection b(s.server.port(), "127.0.0.3");
  REQUIRE(b.send_all("GET / HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n"));
  CHECK(raw_status(b.read_until_closed()) == 200);

  // A's held connections were held, not dropped: they finish their requests.
  for (auto& c : held) {
    REQUIRE(c->send_all("1\r\nConnection: close\r\n\r\n"));
    CHECK(raw_status(c->read_until_closed()) == 200);
  }
}

TEST_CASE(
    "serve: never-finished requests from one client leave the page to the others; by default a client is "
    "served on half the threads at most",
    "[server][limits]") {
  struct Case {
    int threads, slow, cap;
  };
  // 32 threads (the default): 16 connections per client; 6 threads: 3.
  for (const Case c : {Case{32, 40, 16}, Case{6, 10, 3}}) {
    CAPTURE(c.threads);
    const std::string db = make_store("server_slow_" + std::to_string(c.threads), 1, 4);
    ServerOptions o;
    o.threads = c.threads;
    o.connections.request_seconds = 120;
    RunningServer s(db, o);
    test::check_slow_clients_are_contained(s.server.port(), c.slow, c.cap);
  }
}

TEST_CASE("serve: an idle kept-alive connection gives its thread up to a waiting one", "[server][limits]") {
  const std::string db = make_store("server_idle", 1, 4);
  ServerOptions o;
  o.threads = 2;
  o.connections.idle_seconds = 300;  // longer than any bound below: only yielding frees the threads
  RunningServer s(db, o);
  // Two kept-alive connections (two clients: one client holds at most half the threads), one
  // request each, then idle: they hold both threads.
  std::vector<std::unique_ptr<RawConnection>> idle;
  for (const char* from : {"127.0.0.2", "127.0.0.3"}) {
    idle.push_back(std::make_unique<RawConnection>(s.server.port(), from));
    REQUIRE(idle.back()->send_all("GET / HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n"));
    CHECK(raw_status(idle.back()->read_response()) == 200);
  }
  // A third connection waits for a thread: an idle one closes and it is served.
  httplib::Client c = s.client();
  CHECK(status_of(c.Get("/")) == 200);
  int closed = 0;
  for (auto& i : idle) {
    i->read_until_closed(1);  // a bound, not a measurement: the one that yielded is closed already
    closed += i->closed;
  }
  CHECK(closed >= 1);
}

TEST_CASE("serve: endpoints that need a token check it before the body", "[server]") {
  const std::string db = make_store("server_auth_first", 1, 4);
  RunningServer s(db, ServerOptions{});
  httplib::Client c = s.client();
  for (const char* path : {"/api/answer", "/api/release", "/api/next", "/api/undo", "/api/signout", "/api/reset"}) {
    INFO(path);
    for (const char* body : {"{not json", "[1, 2]", R"({"comparison": "x"})"}) {
      INFO(body);
      CHECK(status_of(c.Post(path, body, "application/json")) == 401);
      if (std::string(path) != "/api/reset")
        CHECK(status_of(c.Post(path, bearer(std::string(32, 'f')), body, "application/json")) == 401);
    }
  }
}

TEST_CASE("serve: only the owner exports, resets and sees others' work", "[server]") {
  const std::string db = make_store("server_owner", 2, 4);
  ServerOptions o;
  o.owner_token = "correct horse battery";
  RunningServer s(db, o);
  CHECK(s.server.owner_token() == "correct horse battery");
  httplib::Client c = s.client();
  const std::string ana = sign_in(c, "ana");
  json step = post(c, "/api/next", ana, json::object());
  for (int i = 0; i < 2; ++i) {
    const int64_t id = step.at("assignment").at("comparison").get<int64_t>();
    step = post(c, "/api/answer", ana, {{"comparison", id}, {"answer", i == 0 ? "left" : "right"}});
  }

  for (const char* path : {"/api/export", "/api/overview", "/api/annotator?name=ana"}) {
    INFO(path);
    auto missing = c.Get(path);
    CHECK(status_of(missing) == 401);
    CHECK(json::parse(missing->body).at("error").get<std::string>().find("owner's token is required") !=
          std::string::npos);
    CHECK(status_of(c.Get(path, bearer(ana))) == 403);
    CHECK(status_of(c.Get(path, bearer("correct horse batterz"))) == 403);
    CHECK(status_of(c.Get(path, bearer(o.owner_token))) == 200);
  }
  CHECK(status_of(c.Post("/api/reset", bearer(ana), json{{"name", "ana"}}.dump(), "application/json")) == 403);
  CHECK(status_of(c.Get("/api/export?derived=2", bearer(o.owner_token))) == 400);
  CHECK(status_of(c.Get("/api/annotator?name=nobody", bearer(o.owner_token))) == 404);

  // The export equals the store's triplets (direct ones: the two answers).
  auto csv = c.Get("/api/export?derived=0", bearer(o.owner_token));
  REQUIRE(csv);
  CHECK(csv->get_header_value("Content-Type").find("text/csv") == 0);
  std::string expected = "group,anchor,positive,negative,derived,tie_break\n";
  for (const Triplet& t : AnnotationStore::open(db).triplets(false))
    expected += fmt::format("{},{},{},{},{},{}\n", t.group, t.anchor, t.positive, t.negative, t.derived ? 1 : 0,
                            t.tie_break ? 1 : 0);
  CHECK(csv->body == expected);
  CHECK(std::count(csv->body.begin(), csv->body.end(), '\n') == 3);

  const json work = json::parse(c.Get("/api/annotator?name=ana", bearer(o.owner_token))->body);
  REQUIRE(work.at("decisions").size() == 2);
  CHECK(work.at("decisions")[0].at("answer") == "left");
  CHECK(work.at("decisions")[1].at("answer") == "right");

  const json overview = json::parse(c.Get("/api/overview", bearer(o.owner_token))->body);
  CHECK(overview.at("done") == 2);
  CHECK(overview.at("total") == 6);
  CHECK(overview.at("annotators")[0].at("name") == "ana");
  CHECK(overview.at("annotators")[0].at("decided") == 2);
  CHECK(overview.at("annotators")[0].at("holding") == 1);

  // Reset: Ana's session ends and her comparison returns to the queue; she may sign in again.
  const json reset = post(c, "/api/reset", o.owner_token, {{"name", "ana"}});
  CHECK(reset.at("revoked") == 1);
  CHECK(reset.at("released") == 1);
  CHECK(status_of(c.Post("/api/next", bearer(ana), "", "application/json")) == 401);
  sign_in(c, "ana");
}

TEST_CASE("serve: a draw goes to someone else, an abandoned comparison comes back", "[server]") {
  const std::string db = make_store("server_draw", 1, 2);  // one comparison
  ServerOptions o;
  o.lease_seconds = 1.0;
  RunningServer s(db, o);
  httplib::Client c = s.client();
  const std::string ana = sign_in(c, "ana"), ben = sign_in(c, "ben");

  const json first = post(c, "/api/next", ana, json::object());
  const int64_t id = first.at("assignment").at("comparison").get<int64_t>();
  // Ben waits: the only comparison is Ana's.
  const json waiting = post(c, "/api/next", ben, json::object());
  CHECK(waiting.at("assignment").is_null());
  CHECK(waiting.at("waiting") == 1);
  CHECK(waiting.at("finished") == false);

  // Ana calls it a draw: it goes to Ben, not back to Ana.
  const json drawn = post(c, "/api/answer", ana, {{"comparison", id}, {"answer", "draw"}});
  CHECK(drawn.at("result").at("status") == "requeued");
  CHECK(drawn.at("assignment").is_null());
  const json to_ben = post(c, "/api/next", ben, json::object());
  REQUIRE_FALSE(to_ben.at("assignment").is_null());
  CHECK(to_ben.at("assignment").at("comparison") == id);

  // Ben walks away; after the lease runs out the comparison returns to the queue, for anyone who
  // has not called it a draw (not Ana).
  std::this_thread::sleep_for(std::chrono::milliseconds(1300));
  CHECK(post(c, "/api/next", ana, json::object()).at("assignment").is_null());
  const std::string cy = sign_in(c, "cy");
  const json back = post(c, "/api/next", cy, json::object());
  REQUIRE_FALSE(back.at("assignment").is_null());
  CHECK(back.at("assignment").at("comparison") == id);
  const json done = post(c, "/api/answer", cy, {{"comparison", id}, {"answer", "right"}});
  CHECK(done.at("finished") == true);
  CHECK(done.at("result").at("champion") == first.at("assignment").at("right"));
  // Ben's late answer is refused: the comparison is decided.
  post(c, "/api/answer", ben, {{"comparison", id}, {"answer", "left"}}, 409);
}

TEST_CASE("serve: a restarted server keeps sessions, leases and answers", "[server]") {
  const std::string db = make_store("server_restart", 2, 4);
  std::string ana;
  int64_t held = 0;
  int done = 0;
  {
    RunningServer s(db, ServerOptions{});
    httplib::Client c = s.client();
    ana = sign_in(c, "ana");
    json step = post(c, "/api/next", ana, json::object());
    for (int i = 0; i < 3; ++i)
      step = post(c, "/api/answer", ana,
                  {{"comparison", step.at("assignment").at("comparison")}, {"answer", i % 2 ? "left" : "right"}});
    held = step.at("assignment").at("comparison").get<int64_t>();
    done = step.at("progress").at("done").get<int>();
  }
  RunningServer s(db, ServerOptions{});
  httplib::Client c = s.client();
  const json me = json::parse(c.Get("/api/me", bearer(ana))->body);
  CHECK(me.at("name") == "ana");
  CHECK(me.at("progress").at("done") == done);
  CHECK(done == 3);
  // The comparison shown before the restart is shown again.
  const json again = post(c, "/api/next", ana, json::object());
  CHECK(again.at("assignment").at("comparison") == held);
}

TEST_CASE("serve: 50 concurrent annotators answer 2,000 comparisons, none lost or duplicated", "[server]") {
  // 125 groups of 17 candidates: 16 comparisons each.
  const std::string db = make_store("server_load", 125, 17);
  ServerOptions o;
  o.connections.per_client = 256;  // 50 people, all from 127.0.0.1: no per-address cap here
  RunningServer s(db, o);

  struct Click {
    int64_t comparison;
    std::string annotator;
    std::string answer;
    std::string status;
  };
  std::mutex mutex;
  std::vector<Click> clicks;
  std::atomic<int> errors{0};
  std::vector<std::string> messages;
  std::vector<std::thread> annotators;
  for (int a = 0; a < 50; ++a) {
    annotators.emplace_back([&, a] {
      httplib::Client c = s.client();
      const std::string name = fmt::format("annotator{:02d}", a);
      auto signed_in = c.Post("/api/signin", json{{"name", name}}.dump(), "application/json");
      if (!signed_in || signed_in->status != 200) {
        ++errors;
        std::lock_guard<std::mutex> lock(mutex);
        messages.push_back(signed_in ? fmt::format("sign-in {}: {}", signed_in->status, signed_in->body)
                                     : "sign-in: " + httplib::to_string(signed_in.error()));
        return;
      }
      const std::string token = json::parse(signed_in->body).at("token");
      Random random(static_cast<uint64_t>(a));
      auto call = [&](const std::string& path, const json& body) -> std::optional<json> {
        auto r = c.Post(path.c_str(), bearer(token), body.dump(), "application/json");
        if (!r || r->status != 200) {
          ++errors;
          std::lock_guard<std::mutex> lock(mutex);
          messages.push_back(r ? fmt::format("{} {}: {}", path, r->status, r->body)
                               : path + ": " + httplib::to_string(r.error()));
          return std::nullopt;
        }
        return json::parse(r->body);
      };
      std::optional<json> step = call("/api/next", json::object());
      while (step) {
        if ((*step)["assignment"].is_null()) {
          if ((*step)["finished"].get<bool>()) return;
          std::this_thread::sleep_for(std::chrono::milliseconds(20));
          step = call("/api/next", json::object());
          continue;
        }
        const int64_t id = (*step)["assignment"]["comparison"].get<int64_t>();
        const int roll = static_cast<int>(random.below(100));
        const std::string answer = roll < 4 ? "draw" : roll < 52 ? "left" : "right";
        step = call("/api/answer", {{"comparison", id}, {"answer", answer}});
        if (step) {
          std::lock_guard<std::mutex> lock(mutex);
          clicks.push_back({id, name, answer, (*step)["result"]["status"].get<std::string>()});
        }
      }
    });
  }
  for (std::thread& t : annotators) t.join();
  INFO((messages.empty() ? std::string() : messages.front()));
  CHECK(errors == 0);

  AnnotationStore store = AnnotationStore::open(db);
  CHECK(store.finished());
  const StoreProgress p = store.progress();
  CHECK(p.total() == 2000);
  CHECK(p.done() == 2000);

  // Every verdict the server confirmed is in the store, once, by the annotator who gave it; every
  // verdict in the store was confirmed to someone (tie-breaks: to the one whose draw settled it).
  std::map<int64_t, DecisionRecord> verdicts;
  int draws_stored = 0;
  for (const DecisionRecord& d : store.decisions()) {
    if (d.answer == Answer::draw) {
      ++draws_stored;
      continue;
    }
    CHECK(verdicts.emplace(d.comparison, d).second);  // no comparison decided twice
  }
  CHECK(verdicts.size() == 2000);
  int confirmed = 0, requeued = 0;
  std::set<int64_t> confirmed_ids;
  for (const Click& k : clicks) {
    if (k.status == "requeued") {
      ++requeued;
      continue;
    }
    ++confirmed;
    CHECK(confirmed_ids.insert(k.comparison).second);
    const auto v = verdicts.find(k.comparison);
    REQUIRE(v != verdicts.end());
    if (k.status == "decided") {
      CHECK(v->second.annotator == k.annotator);
      CHECK(answer_name(v->second.answer) == k.answer);
    } else {
      CHECK(k.status == "tie_break");
      CHECK(v->second.tie_break);
    }
  }
  CHECK(confirmed == 2000);
  CHECK(requeued + static_cast<int>(std::count_if(clicks.begin(), clicks.end(),
                                                  [](const Click& k) { return k.status == "tie_break"; })) ==
        draws_stored);
  // 50 people took part.
  std::set<std::string> who;
  for (const Click& k : clicks) who.insert(k.annotator);
  CHECK(who.size() == 50);
}

TEST_CASE("serve: options are validated, naming the option", "[server]") {
  ServerOptions o;
  o.port = 70000;
  CHECK_THROWS_WITH(o.validate(), Catch::Contains("serve.port"));
  o = ServerOptions{};
  o.lease_seconds = 0;
  CHECK_THROWS_WITH(o.validate(), Catch::Contains("serve.lease_seconds"));
  o = ServerOptions{};
  o.owner_token = "short";
  CHECK_THROWS_WITH(o.validate(), Catch::Contains("serve.owner_token"));
  o = ServerOptions{};
  o.max_body_bytes = 10;
  CHECK_THROWS_WITH(o.validate(), Catch::Contains("serve.max_body_bytes"));
  o = ServerOptions{};
  o.connections.per_client = -1;
  CHECK_THROWS_WITH(o.validate(), Catch::Contains("serve.connections.per_client"));
  o = ServerOptions{};
  o.connections.request_seconds = 0;
  CHECK_THROWS_WITH(o.validate(), Catch::Contains("serve.connections.request_seconds"));
  o = ServerOptions{};
  o.connections.idle_seconds = std::nan("");
  CHECK_THROWS_WITH(o.validate(), Catch::Contains("serve.connections.idle_seconds"));
  o = ServerOptions{};
  o.connections.max_header_bytes = 100;
  CHECK_THROWS_WITH(o.validate(), Catch::Contains("serve.connections.max_header_bytes"));
  o = ServerOptions{};
  o.connections.max_header_fields = 0;
  CHECK_THROWS_WITH(o.validate(), Catch::Contains("serve.connections.max_header_fields"));
  o = ServerOptions{};
  o.connections.requests_per_connection = 0;
  CHECK_THROWS_WITH(o.validate(), Catch::Contains("serve.connections.requests_per_connection"));
  CHECK_THROWS_WITH(AnnotationServer("unused.db", sphere_pictures(), o), Catch::Contains("requests_per_connection"));
  CHECK(random_token().size() == 32);
  CHECK(random_token() != random_token());
}

}  // namespace retarget
