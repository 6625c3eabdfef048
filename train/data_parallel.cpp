#define USE_C10D_GLOO 1
#include "train/data_parallel.h"

#include <arpa/inet.h>
#include <fmt/format.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cstdlib>
#include <string>
#include <torch/csrc/distributed/c10d/PrefixStore.hpp>
#include <torch/csrc/distributed/c10d/ProcessGroupGloo.hpp>
#include <torch/csrc/distributed/c10d/TCPStore.hpp>

#include "core/error.h"
#include "core/log.h"

namespace retarget {

namespace {

constexpr int64_t kBucketBytes = 16 << 20;

// The integer in environment variable `name`, or `fallback` when unset.
int env_int(const char* name, int fallback, int lo, int hi) {
  const char* text = std::getenv(name);
  if (!text || !*text) return fallback;
  char* end = nullptr;
  const long value = std::strtol(text, &end, 10);
  if (*end != '\0' || value < lo || value > hi)
    throw Error(name, fmt::format("expected a whole number in {}..{}, got '{}'", lo, hi, text));
  return static_cast<int>(value);
}

}  // namespace

DataParallelEnv data_parallel_env_from_environment() {
  DataParallelEnv env;
  env.world_size = env_int("WORLD_SIZE", 1, 1, 65536);
  if (!env.distributed()) return env;
  env.rank = env_int("RANK", -1, 0, env.world_size - 1);
  if (env.rank < 0)
    throw Error("RANK", fmt::format("missing: WORLD_SIZE is {}, so each process needs its RANK", env.world_size));
  env.local_rank = env_int("LOCAL_RANK", env.rank, 0, 65535);
  const char* addr = std::getenv("MASTER_ADDR");
  if (!addr || !*addr) throw Error("MASTER_ADDR", "missing: the address of rank 0 (e.g. MASTER_ADDR=10.0.0.1)");
  env.master_addr = addr;
  env.master_port = env_int("MASTER_PORT", -1, 1, 65535);
  if (env.master_port < 0) throw Error("MASTER_PORT", "missing: the port rank 0 listens on (e.g. MASTER_PORT=29500)");
  env.timeout = std::chrono::seconds(env_int("RETARGET_DIST_TIMEOUT", 120, 1, 86400));
  return env;
}

int free_loopback_port() {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  if (fd < 0) throw Error("data-parallel", "cannot open a socket to find a free loopback port");
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t size = sizeof(address);
  const bool ok = ::bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof(address)) == 0 &&
                  ::getsockname(fd, reinterpret_cast<sockaddr*>(&address), &size) == 0;
  ::close(fd);
  if (!ok) throw Error("data-parallel", "cannot find a free loopback port");
  return ntohs(address.sin_port);
}

struct DataParallel::Group {
  c10::intrusive_ptr<c10d::Store> store;
  c10::intrusive_ptr<c10d::ProcessGroupGloo> gloo;
};

namespace {

// Runs a collective; a failure (a rank gone, a timeout) becomes an error that says so.
template <typename Run>
void collective(const DataParallelEnv& env, const std::string& what, Run run) {
  try {
    run();
  } catch (const c10::Error& e) {
    throw Error(
        fmt::format("data-parallel rank {} of {}", env.rank, env.world_size),
        fmt::format("{} failed: another rank stopped or did not answer within {} s ({})", what,
                    std::chrono::duration_cast<std::chrono::seconds>(env.timeout).count(), e.what_without_backtrace()));
  } catch (const std::exception& e) {
    throw Error(fmt::format("data-parallel rank {} of {}", env.rank, env.world_size),
                fmt::format("{} failed: another rank stopped or did not answer ({})", what, e.what()));
  }
}

// The network interface Gloo sends on, as PyTorch picks it: GLOO_SOCKET_IFNAME when set;
// loopback when rank 0 is on this machine's loopback; else the address this host's name resolves
// to (or loopback when it resolves to none).
std::shared_ptr<::gloo::transport::Device> transport_device(const DataParallelEnv& env) {
  if (const char* interface = std::getenv("GLOO_SOCKET_IFNAME"); interface && *interface)
    return c10d::ProcessGroupGloo::createDeviceForInterface(interface);
  if (env.master_addr == "localhost" || env.master_addr.rfind("127.", 0) == 0)
    return c10d::ProcessGroupGloo::createDeviceForHostname("127.0.0.1");
  return c10d::ProcessGroupGloo::createDefaultDevice();
}

}  // namespace

DataParallel::DataParallel(const DataParallelEnv& env) : env_(env), group_(std::make_unique<Group>()) {
  collective(env_, fmt::format("joining {}:{}", env.master_addr, env.master_port), [&] {
    c10d::TCPStoreOptions o;
    o.port = static_cast<uint16_t>(env.master_port);
    o.isServer = env.rank == 0;
    o.numWorkers = env.world_size;
    o.waitWorkers = true;
    o.timeout = env.timeout;
    group_->store = c10::make_intrusive<c10d::TCPStore>(env.master_addr, o);
    auto options = c10d::ProcessGroupGloo::Options::create(env.timeout);
    options->devices.push_back(transport_device(env));
    options->threads = 2;
    group_->gloo = c10::make_intrusive<c10d::ProcessGroupGloo>(
        c10::make_intrusive<c10d::PrefixStore>("retarget", group_->store), env.rank, env.world_size, options);
  });
  log::info("data-parallel: rank {} of {} joined {}:{}", env.rank, env.world_size, env.master_addr, env.master_port);
}

DataParallel::~DataParallel() = default;

std::pair<int64_t, int64_t> DataParallel::shard(int64_t begin, int64_t end) const {
  const int64_t n = end - begin, w = env_.world_size, r = env_.rank;
  return {begin + n * r / w, begin + n * (r + 1) / w};
}

struct GradientSync::State {
  DataParallel* parallel = nullptr;
  struct Slot {
    torch::Tensor parameter;
    int bucket = 0;
    int64_t offset = 0;
    bool seen = false;
    unsigned hook = 0;
  };
  std::vector<Slot> slots;
  std::vector<torch::Tensor> buffers;  // [bucket] flat float32
  std::vector<int> expected, arrived;  // per bucket: its parameters, and those whose gradient came
  std::vector<c10::intrusive_ptr<c10d::Work>> work;
  int next = 0;  // the next bucket to start

  void start(int bucket) {
    std::vector<at::Tensor> tensors{buffers[static_cast<size_t>(bucket)]};
    collective(parallel->env_, "summing the gradients",
               [&] { work[static_cast<size_t>(bucket)] = parallel->group_->gloo->allreduce(tensors); });
  }
  // Starts every complete bucket whose predecessors have started.
  void start_ready() {
    while (next < static_cast<int>(buffers.size()) &&
           arrived[static_cast<size_t>(next)] == expected[static_cast<size_t>(next)])
      start(next++);
  }
};

GradientSync::GradientSync(DataParallel& parallel, const std::vector<torch::Tensor>& parameters)
    : state_(std::make_unique<State>()) {
  State& s = *state_;
  s.parallel = &parallel;
  int64_t filled = 0;
  std::vector<int64_t> sizes;
  for (auto it = parameters.rbegin(); it != parameters.rend(); ++it) {
    if (!it->requires_grad()) continue;
    if (sizes.empty() || filled >= kBucketBytes / 4) {
      sizes.push_back(0);
      filled = 0;
    }
    s.slots.push_back({*it, static_cast<int>(sizes.size()) - 1, sizes.back(), false, 0});
    sizes.back() += it->numel();
    filled += it->numel();
  }
  for (int64_t size : sizes) s.buffers.push_back(torch::zeros({size}, torch::kFloat32));
  s.expected.assign(sizes.size(), 0);
  s.arrived.assign(sizes.size(), 0);
  s.work.resize(sizes.size());
  for (const State::Slot& slot : s.slots) ++s.expected[static_cast<size_t>(slot.bucket)];
  for (size_t i = 0; i < s.slots.size(); ++i) {
    State* state = state_.get();
    s.slots[i].hook = s.slots[i].parameter.register_hook([state, i](const torch::Tensor& grad) {
      State::Slot& slot = state->slots[i];
      torch::NoGradGuard no_grad;
      state->buffers[static_cast<size_t>(slot.bucket)]
          .slice(0, slot.offset, slot.offset + grad.numel())
          .copy_(grad.reshape({-1}));
      slot.seen = true;
      ++state->arrived[static_cast<size_t>(slot.bucket)];
      state->start_ready();
    });
  }
}

GradientSync::~GradientSync() {
  for (State::Slot& slot : state_->slots) slot.parameter.remove_hook(slot.hook);
}

void GradientSync::finish() {
  State& s = *state_;
  torch::NoGradGuard no_grad;
  for (State::Slot& slot : s.slots)
    if (!slot.seen) {
      s.buffers[static_cast<size_t>(slot.bucket)].slice(0, slot.offset, slot.offset + slot.parameter.numel()).zero_();
      ++s.arrived[static_cast<size_t>(slot.bucket)];
    }
  s.start_ready();
  for (size_t b = 0; b < s.work.size(); ++b)
    collective(s.parallel->env_, "summing the gradients", [&] { s.work[b]->wait(s.parallel->env_.timeout); });
  for (State::Slot& slot : s.slots) {
    torch::Tensor p = slot.parameter;
    const torch::Tensor summed =
        s.buffers[static_cast<size_t>(slot.bucket)].slice(0, slot.offset, slot.offset + p.numel()).view(p.sizes());
    if (p.grad().defined())
      p.mutable_grad().copy_(summed);
    else
      p.mutable_grad() = summed.clone();
    slot.seen = false;
  }
  std::fill(s.arrived.begin(), s.arrived.end(), 0);
  std::fill(s.work.begin(), s.work.end(), c10::intrusive_ptr<c10d::Work>());
  s.next = 0;
}

std::vector<double> DataParallel::sum(const std::vector<double>& values) {
  std::vector<torch::Tensor> t{torch::tensor(values, torch::kFloat64)};
  collective(env_, "summing the metrics", [&] { group_->gloo->allreduce(t)->wait(env_.timeout); });
  return std::vector<double>(t[0].data_ptr<double>(), t[0].data_ptr<double>() + t[0].numel());
}

void DataParallel::warn_if_batch_too_small(int batch_size, const std::string& key) const {
  if (leader() && batch_size < env_.world_size)
    log::warn(
        "{} is {} rows for {} ranks: {} of them get no rows at each step and only wait, while every step "
        "still sums every gradient; data-parallel pays off with at least one row per rank (more: several)",
        key, batch_size, env_.world_size, env_.world_size - batch_size);
}

void DataParallel::barrier(const std::string& what) {
  collective(env_, "waiting for every rank (" + what + ")", [&] { group_->gloo->barrier()->wait(env_.timeout); });
}

}  // namespace retarget
