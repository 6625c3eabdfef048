#include "annotate/annotation_server.h"

#include <fmt/format.h>
#include <netinet/in.h>
#include <sys/socket.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <condition_variable>
#include <future>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <random>
#include <thread>
#include <vector>

#include "annotate/annotation_store.h"
#include "core/error.h"
#include "web/asset_serving.h"
#include "web/guarded_http_server.h"
#include "web/http_json.h"
#include "web/token.h"
#include "web/web_assets.h"

namespace retarget {

using http_json::bearer_token;
using http_json::body_object;
using http_json::checked_name;
using http_json::field;
using http_json::HttpError;
using http_json::id_field;
using http_json::reject;
using http_json::respond_to_error;
using http_json::respond_to_exception;
using http_json::same_token;
using http_json::send_json;
using nlohmann::json;

namespace {

// Store connections, one per request thread at a time (an AnnotationStore is one SQLite
// connection and is not shared between threads).
class StorePool {
 public:
  StorePool(std::string path, StoreOptions options) : path_(std::move(path)), options_(std::move(options)) {
    idle_.push_back(std::make_unique<AnnotationStore>(AnnotationStore::open(path_, options_)));
  }

  class Lease {
   public:
    Lease(StorePool& pool, std::unique_ptr<AnnotationStore> store) : pool_(pool), store_(std::move(store)) {}
    ~Lease() { pool_.give_back(std::move(store_)); }
    Lease(const Lease&) = delete;
    Lease& operator=(const Lease&) = delete;
    AnnotationStore& operator*() { return *store_; }
    AnnotationStore* operator->() { return store_.get(); }

   private:
    StorePool& pool_;
    std::unique_ptr<AnnotationStore> store_;
  };

  Lease take() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (!idle_.empty()) {
        std::unique_ptr<AnnotationStore> s = std::move(idle_.back());
        idle_.pop_back();
        return Lease(*this, std::move(s));
      }
    }
    return Lease(*this, std::make_unique<AnnotationStore>(AnnotationStore::open(path_, options_)));
  }

 private:
  void give_back(std::unique_ptr<AnnotationStore> store) {
    std::lock_guard<std::mutex> lock(mutex_);
    idle_.push_back(std::move(store));
  }

  std::string path_;
  StoreOptions options_;
  std::mutex mutex_;
  std::vector<std::unique_ptr<AnnotationStore>> idle_;
};

// Debian's compiled cpp-httplib listens with a backlog of 5 connections: a burst of people
// connecting at once (or one browser opening several connections) overflows it and connections
// are reset. listen() on a listening socket sets its backlog anew, so find ours - the listening
// TCP socket bound to `port` - and give it the system's maximum. Returns false if not found.
bool widen_listen_backlog(int port) {
  for (int fd = 3; fd < 4096; ++fd) {
    int listening = 0;
    socklen_t length = sizeof(listening);
    if (::getsockopt(fd, SOL_SOCKET, SO_ACCEPTCONN, &listening, &length) != 0 || !listening) continue;
    sockaddr_storage address{};
    socklen_t address_length = sizeof(address);
    if (::getsockname(fd, reinterpret_cast<sockaddr*>(&address), &address_length) != 0) continue;
    int bound = -1;
    if (address.ss_family == AF_INET) bound = ntohs(reinterpret_cast<const sockaddr_in*>(&address)->sin_port);
    if (address.ss_family == AF_INET6) bound = ntohs(reinterpret_cast<const sockaddr_in6*>(&address)->sin6_port);
    if (bound == port) return ::listen(fd, SOMAXCONN) == 0;
  }
  return false;
}

}  // namespace

void ServerOptions::validate(const std::string& key_path) const {
  if (host.empty()) throw Error(key_path + ".host", "must not be empty");
  if (port < 0 || port > 65535) throw Error(key_path + ".port", fmt::format("must be in 0..65535, got {}", port));
  if (!(lease_seconds > 0) || !std::isfinite(lease_seconds))
    throw Error(key_path + ".lease_seconds",
                fmt::format("must be a positive number of seconds, got {}", lease_seconds));
  if (!owner_token.empty() && owner_token.size() < 8)
    throw Error(key_path + ".owner_token", "must have at least 8 characters (or be empty for a random one)");
  if (max_body_bytes < 64 || max_body_bytes > (1u << 20))
    throw Error(key_path + ".max_body_bytes", fmt::format("must be in 64..1048576, got {}", max_body_bytes));
  if (threads < 1 || threads > 256)
    throw Error(key_path + ".threads", fmt::format("must be in 1..256, got {}", threads));
  connections.validate(key_path + ".connections");
}

// body["answer"]: "left", "right" or "draw"; 400 otherwise.
static Answer answer_field(const nlohmann::json& body) {
  const nlohmann::json& value = http_json::field(body, "answer");
  const std::string text = value.is_string() ? value.get<std::string>() : std::string();
  if (text == "left") return Answer::left;
  if (text == "right") return Answer::right;
  if (text == "draw") return Answer::draw;
  http_json::reject(400, "'answer' must be \"left\", \"right\" or \"draw\"");
}

struct AnnotationServer::Impl {
  TurntablePictures pictures;
  ServerOptions options;
  std::string owner;
  StorePool stores;
  GuardedHttpServer http;
  int port = 0;

  // Pictures: PNG bytes by key ("a<group>", "c<sample>"), each rendered once. Rendering is
  // serialised (the picture source is not thread-safe); waiters share the result.
  std::mutex picture_mutex;
  std::map<std::string, std::shared_future<std::string>> picture_cache;
  std::mutex render_mutex;
  std::thread prerenderer;
  std::atomic<bool> stopping{false};

  Impl(const std::string& db, TurntablePictures p, const ServerOptions& o)
      : pictures(std::move(p)),
        options(o),
        stores(db, StoreOptions{}),
        http(o.connections, o.max_body_bytes, o.threads) {
    owner = options.owner_token.empty() ? random_token() : options.owner_token;
    routes();
  }

  ~Impl() {
    stopping = true;
    if (prerenderer.joinable()) prerenderer.join();
  }

  // --- authentication -------------------------------------------------------------------

  // The annotator the request's session token stands for; 401 otherwise.
  std::string annotator(const httplib::Request& req, AnnotationStore& store) {
    const std::string token = bearer_token(req);
    if (token.empty()) reject(401, "sign in first: no session token (Authorization: Bearer <token>)");
    const std::optional<std::string> name = store.session_annotator(token);
    if (!name) reject(401, "unknown or ended session: sign in again");
    return *name;
  }

  void require_owner(const httplib::Request& req) {
    const std::string token = bearer_token(req);
    if (token.empty()) reject(401, "the owner's token is required (Authorization: Bearer <owner token>)");
    if (!same_token(token, owner)) reject(403, "this is not the owner's token");
  }

  // --- pictures ---------------------------------------------------------------------------

  std::string picture(const std::string& key, const std::function<std::string()>& make) {
    std::promise<std::string> promise;
    std::shared_future<std::string> future;
    bool mine = false;
    {
      std::lock_guard<std::mutex> lock(picture_mutex);
      auto it = picture_cache.find(key);
      if (it == picture_cache.end()) {
        future = promise.get_future().share();
        picture_cache.emplace(key, future);
        mine = true;
      } else {
        future = it->second;
      }
    }
    if (mine) {
      try {
        std::lock_guard<std::mutex> lock(render_mutex);
        promise.set_value(make());
      } catch (...) {
        // Let a later request try again.
        {
          std::lock_guard<std::mutex> lock(picture_mutex);
          picture_cache.erase(key);
        }
        promise.set_exception(std::current_exception());
      }
    }
    return future.get();
  }

  std::string anchor_picture(int64_t group, const std::string& label) {
    return picture(fmt::format("a{}", group), [&] { return pictures.anchor(label); });
  }
  std::string candidate_picture(int64_t sample) {
    return picture(fmt::format("c{}", sample), [&] { return pictures.candidate(sample); });
  }

  // Renders every group's pictures, groups with work left first, until stopped.
  void prerender_all() {
    std::vector<GroupInfo> groups;
    {
      auto store = stores.take();
      groups = store->groups();
      const StoreProgress p = store->progress();
      std::map<int64_t, bool> finished;
      for (const GroupProgress& g : p.groups) finished[g.group] = g.champion.has_value();
      std::stable_partition(groups.begin(), groups.end(), [&](const GroupInfo& g) { return !finished[g.id]; });
    }
    for (const GroupInfo& g : groups) {
      try {
        if (stopping) return;
        anchor_picture(g.id, g.label);
        for (int64_t sample : g.candidates) {
          if (stopping) return;
          candidate_picture(sample);
        }
      } catch (const std::exception& e) {
        fmt::print(stderr, "[warn] pictures of group {} ('{}'): {}\n", g.id, g.label, e.what());
      }
    }
  }

  // --- JSON views ------------------------------------------------------------------------

  json progress_of(const StoreProgress& p, const std::string& name) const {
    json out = {{"done", 0}, {"draws", 0}, {"left", p.total() - p.done()}, {"total", p.total()}};
    int groups_done = 0;
    for (const GroupProgress& g : p.groups) groups_done += g.champion ? 1 : 0;
    out["groups_done"] = groups_done;
    out["groups"] = p.groups.size();
    for (const AnnotatorProgress& a : p.annotators) {
      if (a.name != name) continue;
      out["done"] = a.decided;
      out["draws"] = a.draws;
    }
    return out;
  }

  json assignment_of(const Assignment& a, AnnotationStore& store) const {
    json prefetch = json::array();
    for (int64_t sample : store.group(a.group).candidates)
      if (sample != a.left && sample != a.right) prefetch.push_back(fmt::format("/img/candidate/{}.png", sample));
    return {{"comparison", a.comparison},
            {"group", a.group},
            {"label", a.label},
            {"round", a.round},
            {"left", a.left},
            {"right", a.right},
            {"lease_seconds", options.lease_seconds},
            {"images",
             {{"anchor", fmt::format("/img/anchor/{}.png", a.group)},
              {"left", fmt::format("/img/candidate/{}.png", a.left)},
              {"right", fmt::format("/img/candidate/{}.png", a.right)}}},
            {"prefetch", prefetch}};
  }

  // {"assignment", "progress", "waiting", "finished"} after leasing the annotator's next comparison.
  json next_for(const std::string& name, AnnotationStore& store) {
    const std::optional<Assignment> a = store.next_comparison(name, options.lease_seconds);
    const StoreProgress p = store.progress();
    int mine = 0;
    for (const AnnotatorProgress& ap : p.annotators)
      if (ap.name == name) mine = ap.holding;
    return {{"assignment", a ? assignment_of(*a, store) : json(nullptr)},
            {"progress", progress_of(p, name)},
            {"waiting", p.held - mine},
            {"finished", p.finished()}};
  }

  // --- routes ------------------------------------------------------------------------------

  using Endpoint = void (Impl::*)(const httplib::Request&, httplib::Response&);

  // Runs `endpoint`, turning HttpError and retarget::Error into JSON errors. A chunked body is
  // capped on the wire (GuardedHttpServer), not exactly: its decoded size is checked here.
  httplib::Server::Handler wrap(Endpoint endpoint) {
    return [this, endpoint](const httplib::Request& req, httplib::Response& res) {
      try {
        if (req.body.size() > options.max_body_bytes) reject(413, "the request body is too large");
        (this->*endpoint)(req, res);
      } catch (const HttpError& e) {
        send_json(res, {{"error", e.message}}, e.status);
      } catch (const Error& e) {
        // A store refusal (a comparison decided meanwhile, a lease lost): the message without the
        // database's path.
        send_json(res, {{"error", e.detail()}}, 409);
      }
    };
  }

  // Every endpoint, by method and path; the handlers follow in this order.
  void routes() {
    http.set_default_headers(
        {{"X-Content-Type-Options", "nosniff"}, {"X-Frame-Options", "DENY"}, {"Referrer-Policy", "no-referrer"}});

    // The pages.
    http.Get("/", wrap(&Impl::on_index_page));
    http.Get("/overview", wrap(&Impl::on_overview_page));
    http.Get(R"(/static/([A-Za-z0-9_-]+\.(js|css)))", wrap(&Impl::on_static_asset));

    // Annotators.
    http.Post("/api/signin", wrap(&Impl::on_signin));
    http.Get("/api/me", wrap(&Impl::on_me));
    http.Post("/api/next", wrap(&Impl::on_next));
    http.Post("/api/answer", wrap(&Impl::on_answer));
    http.Post("/api/undo", wrap(&Impl::on_undo));
    http.Post("/api/release", wrap(&Impl::on_release));
    http.Post("/api/signout", wrap(&Impl::on_signout));
    http.Get(R"(/img/anchor/(\d{1,12})\.png)", wrap(&Impl::on_anchor_picture));
    http.Get(R"(/img/candidate/(\d{1,12})\.png)", wrap(&Impl::on_candidate_picture));

    // The owner.
    http.Get("/api/overview", wrap(&Impl::on_overview));
    http.Get("/api/export", wrap(&Impl::on_export));
    http.Get("/api/annotator", wrap(&Impl::on_annotator));
    http.Post("/api/reset", wrap(&Impl::on_reset));

    // Anything else (unknown paths, path tricks, other methods, the connection guards' refusals):
    // a JSON error, never a file.
    http.set_error_responder(respond_to_error);
    http.set_exception_handler(respond_to_exception);
  }

  // --- the pages ---------------------------------------------------------------------------

  void serve_asset(httplib::Response& res, std::string_view name) { serve_web_asset(res, find_web_asset, name); }

  void on_index_page(const httplib::Request&, httplib::Response& res) { serve_asset(res, "index.html"); }

  void on_overview_page(const httplib::Request&, httplib::Response& res) { serve_asset(res, "overview.html"); }

  void on_static_asset(const httplib::Request& req, httplib::Response& res) { serve_asset(res, req.matches[1].str()); }

  // --- the annotators' endpoints -------------------------------------------------------------
  // Each checks the token first, then the body (no reading of strangers' bodies).

  void on_signin(const httplib::Request& req, httplib::Response& res) {
    const std::string name = checked_name(field(body_object(req), "name"), "name");
    auto store = stores.take();
    if (store->has_session(name))
      reject(409, fmt::format("'{}' is signed in elsewhere: continue in that browser, pick another "
                              "name, or ask the project's owner to reset it",
                              name));
    const std::string token = random_token();
    store->add_session(token, name);
    send_json(res, {{"name", name}, {"token", token}});
  }

  void on_me(const httplib::Request& req, httplib::Response& res) {
    auto store = stores.take();
    const std::string name = annotator(req, *store);
    send_json(res, {{"name", name}, {"progress", progress_of(store->progress(), name)}});
  }

  void on_next(const httplib::Request& req, httplib::Response& res) {
    auto store = stores.take();
    const std::string name = annotator(req, *store);
    send_json(res, next_for(name, *store));
  }

  void on_answer(const httplib::Request& req, httplib::Response& res) {
    auto store = stores.take();
    const std::string name = annotator(req, *store);
    const json body = body_object(req);
    const int64_t comparison = id_field(body, "comparison");
    const Answer answer = answer_field(body);
    if (!store->has_comparison(comparison)) reject(404, fmt::format("no comparison {}", comparison));
    const AnswerResult r = store->answer(comparison, name, answer);
    const char* status = r.status == AnswerStatus::decided    ? "decided"
                         : r.status == AnswerStatus::requeued ? "requeued"
                                                              : "tie_break";
    json out = next_for(name, *store);
    out["result"] = {{"status", status},
                     {"winner", r.winner ? json(*r.winner) : json(nullptr)},
                     {"champion", r.champion ? json(*r.champion) : json(nullptr)}};
    send_json(res, out);
  }

  void on_undo(const httplib::Request& req, httplib::Response& res) {
    auto store = stores.take();
    const std::string name = annotator(req, *store);
    const Assignment a = store->undo_last(name, options.lease_seconds);
    send_json(res, {{"assignment", assignment_of(a, *store)}, {"progress", progress_of(store->progress(), name)}});
  }

  void on_release(const httplib::Request& req, httplib::Response& res) {
    auto store = stores.take();
    const std::string name = annotator(req, *store);
    const int64_t comparison = id_field(body_object(req), "comparison");
    if (!store->has_comparison(comparison)) reject(404, fmt::format("no comparison {}", comparison));
    store->release(comparison, name);
    send_json(res, json::object());
  }

  void on_signout(const httplib::Request& req, httplib::Response& res) {
    auto store = stores.take();
    const std::string name = annotator(req, *store);
    store->end_sessions(name);
    send_json(res, json::object());
  }

  // The pictures: any annotator's token, or the owner's.
  void on_anchor_picture(const httplib::Request& req, httplib::Response& res) {
    const int64_t group = std::stoll(req.matches[1].str());
    std::string label;
    {
      auto store = stores.take();
      if (!same_token(bearer_token(req), owner)) annotator(req, *store);
      try {
        label = store->group(group).label;
      } catch (const Error&) {
        reject(404, fmt::format("no group {}", group));
      }
    }
    send_picture(res, anchor_picture(group, label));
  }

  void on_candidate_picture(const httplib::Request& req, httplib::Response& res) {
    const int64_t sample = std::stoll(req.matches[1].str());
    {
      auto store = stores.take();
      if (!same_token(bearer_token(req), owner)) annotator(req, *store);
      if (!store->has_sample(sample)) reject(404, fmt::format("no candidate sample {}", sample));
    }
    send_picture(res, candidate_picture(sample));
  }

  void send_picture(httplib::Response& res, const std::string& png) {
    res.set_header("Cache-Control", "private, max-age=86400");
    res.set_header("X-Turntable-Frames", std::to_string(pictures.frames));
    res.set_content(png, "image/png");
  }

  // --- the owner's endpoints -----------------------------------------------------------------

  void on_overview(const httplib::Request& req, httplib::Response& res) {
    require_owner(req);
    auto store = stores.take();
    const StoreProgress p = store->progress();
    json groups = json::array(), annotators = json::array();
    for (const GroupProgress& g : p.groups)
      groups.push_back({{"id", g.group},
                        {"label", g.label},
                        {"done", g.done},
                        {"total", g.total},
                        {"tie_breaks", g.tie_breaks},
                        {"champion", g.champion ? json(*g.champion) : json(nullptr)}});
    for (const AnnotatorProgress& a : p.annotators)
      annotators.push_back({{"name", a.name},
                            {"decided", a.decided},
                            {"draws", a.draws},
                            {"last_seen", a.last_seen},
                            {"holding", a.holding}});
    send_json(res, {{"groups", groups},
                    {"annotators", annotators},
                    {"done", p.done()},
                    {"total", p.total()},
                    {"finished", p.finished()}});
  }

  void on_export(const httplib::Request& req, httplib::Response& res) {
    require_owner(req);
    const std::string derived = req.has_param("derived") ? req.get_param_value("derived") : "1";
    if (derived != "0" && derived != "1") reject(400, "'derived' must be 0 or 1");
    auto store = stores.take();
    const std::vector<Triplet> rows = store->triplets(derived == "1");
    std::string csv = "group,anchor,positive,negative,derived,tie_break\n";
    for (const Triplet& t : rows)
      csv += fmt::format("{},{},{},{},{},{}\n", t.group, csv_field(t.anchor), t.positive, t.negative, t.derived ? 1 : 0,
                         t.tie_break ? 1 : 0);
    res.set_header("Cache-Control", "no-store");
    res.set_header("Content-Disposition", "attachment; filename=\"triplets.csv\"");
    res.set_content(csv, "text/csv; charset=utf-8");
  }

  void on_annotator(const httplib::Request& req, httplib::Response& res) {
    require_owner(req);
    if (!req.has_param("name")) reject(400, "the query has no 'name'");
    const std::string name = checked_name(json(req.get_param_value("name")), "name");
    auto store = stores.take();
    std::map<int64_t, ComparisonRecord> comparisons;
    for (ComparisonRecord& c : store->comparisons()) comparisons.emplace(c.id, std::move(c));
    std::map<int64_t, std::string> labels;
    for (const GroupInfo& g : store->groups()) labels[g.id] = g.label;
    bool known = false;
    for (const AnnotatorProgress& a : store->progress().annotators) known = known || a.name == name;
    if (!known) reject(404, fmt::format("no annotator '{}'", name));
    json decisions = json::array();
    for (const DecisionRecord& d : store->decisions()) {
      if (d.annotator != name) continue;
      json row = {{"comparison", d.comparison},
                  {"answer", answer_name(d.answer)},
                  {"time", d.time},
                  {"tie_break", d.tie_break}};
      const auto c = comparisons.find(d.comparison);
      if (c != comparisons.end()) {
        row["group"] = c->second.group;
        row["label"] = labels[c->second.group];
        row["left"] = c->second.left;
        row["right"] = c->second.right;
      }
      decisions.push_back(std::move(row));
    }
    send_json(res, {{"name", name}, {"decisions", decisions}});
  }

  void on_reset(const httplib::Request& req, httplib::Response& res) {
    require_owner(req);
    const std::string name = checked_name(field(body_object(req), "name"), "name");
    auto store = stores.take();
    bool known = false;
    for (const AnnotatorProgress& a : store->progress().annotators) known = known || a.name == name;
    if (!known) reject(404, fmt::format("no annotator '{}'", name));
    const SessionsEnded ended = store->end_sessions(name);
    send_json(res, {{"released", ended.released}, {"revoked", ended.sessions}});
  }
};

AnnotationServer::AnnotationServer(const std::string& database, TurntablePictures pictures,
                                   const ServerOptions& options) {
  options.validate();
  if (pictures.frames < 1 || !pictures.anchor || !pictures.candidate)
    throw Error("serve", "the server needs both picture sources and at least one frame per turntable");
  impl_ = std::make_unique<Impl>(database, std::move(pictures), options);
}

AnnotationServer::~AnnotationServer() { stop(); }

int AnnotationServer::bind() {
  Impl& s = *impl_;
  s.port = s.http.listen_on(s.options.host, s.options.port);
  if (!widen_listen_backlog(s.port))
    fmt::print(stderr, "[warn] could not widen the listen backlog of port {}; bursts of connections may be reset\n",
               s.port);
  if (s.options.prerender) s.prerenderer = std::thread([&s] { s.prerender_all(); });
  return s.port;
}

void AnnotationServer::run() { impl_->http.listen_after_bind(); }

void AnnotationServer::stop() {
  if (!impl_) return;
  impl_->stopping = true;
  impl_->http.stop();
}

int AnnotationServer::port() const { return impl_->port; }
const std::string& AnnotationServer::owner_token() const { return impl_->owner; }
std::string AnnotationServer::base_url() const { return fmt::format("http://{}:{}", impl_->options.host, impl_->port); }

}  // namespace retarget
