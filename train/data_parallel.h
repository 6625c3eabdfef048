// Data-parallel training across processes and machines on LibTorch's own c10d: a TCPStore
// rendezvous and a ProcessGroupGloo, started from torchrun's environment (WORLD_SIZE, RANK,
// LOCAL_RANK, MASTER_ADDR, MASTER_PORT), so `torchrun ... retarget train CONFIG` and
// `retarget train CONFIG --nproc N` (cli/train_launcher.h) run the same way.
//
// How the trainers use it (train/vae_trainer.h, translate/translation_trainer.h): every rank
// draws the same seeded epoch order and walks the same global batches; each takes a contiguous
// shard of every batch (shard()), scales its loss by its share of the batch's rows, and the
// ranks' gradients are added while the backward pass runs (GradientSync), so every rank steps
// with the gradient of the whole batch and the weights stay identical everywhere. Rank 0 alone
// writes checkpoints, run.yaml and the logs.
//
// Network: Gloo sends on GLOO_SOCKET_IFNAME when set (as PyTorch), else on loopback when rank 0
// is on loopback, else on the address this host's name resolves to.
//
// Faults: every collective waits at most `timeout`; a rank that died or never arrived makes the
// others throw retarget::Error naming what they waited for, instead of hanging.
#pragma once

#include <torch/torch.h>

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace retarget {

struct DataParallelEnv {
  int rank = 0, world_size = 1, local_rank = 0;
  std::string master_addr = "127.0.0.1";
  int master_port = 29500;
  std::chrono::milliseconds timeout{std::chrono::seconds(120)};
  bool distributed() const { return world_size > 1; }
};

// torchrun's variables, and RETARGET_DIST_TIMEOUT (seconds, default 120). Without WORLD_SIZE:
// one process. Throws retarget::Error naming the variable for a value that is not a number in
// range (RANK >= WORLD_SIZE, a port outside 1..65535, ...) or a missing MASTER_ADDR / MASTER_PORT.
DataParallelEnv data_parallel_env_from_environment();

class DataParallel {
 public:
  // Joins the group: rank 0 serves the store at master_addr:master_port, every rank connects and
  // waits until all world_size ranks have. Throws retarget::Error when they do not within timeout.
  explicit DataParallel(const DataParallelEnv& env);
  ~DataParallel();
  DataParallel(const DataParallel&) = delete;
  DataParallel& operator=(const DataParallel&) = delete;

  int rank() const { return env_.rank; }
  int world_size() const { return env_.world_size; }
  bool leader() const { return env_.rank == 0; }

  // The rows [first, second) of rows [begin, end) this rank takes: contiguous, sizes differing by
  // at most one, rank 0 first.
  std::pair<int64_t, int64_t> shard(int64_t begin, int64_t end) const;

  // The sum over ranks of each value (float64).
  std::vector<double> sum(const std::vector<double>& values);
  // Waits until every rank gets here.
  void barrier(const std::string& what);
  // Warns (rank 0) when a global batch of `batch_size` rows leaves ranks without rows: they
  // then only wait and send zeros, and every step still all-reduces every gradient.
  void warn_if_batch_too_small(int batch_size, const std::string& key) const;

 private:
  friend class GradientSync;
  struct Group;
  DataParallelEnv env_;
  std::unique_ptr<Group> group_;
};

// Sums the gradients of `parameters` over the ranks while the backward pass is still running:
// each parameter's gradient hook copies its gradient into its bucket (buckets of about 16 MB,
// in reverse registration order, which is about the order backward produces them), and a
// bucket whose every gradient has arrived is all-reduced asynchronously on Gloo's threads while
// backward goes on with the layers before it. Buckets start in the same order on every rank
// (a bucket waits for the ones before it), as Gloo's collectives must match.
//   GradientSync sync(parallel, module.parameters());   // once: registers the hooks
//   optimiser.zero_grad(); loss.backward(); sync.finish(); optimiser.step();   // every step
// finish() also serves a rank whose part of the batch is empty (no backward): its buckets go
// out as zeros. Parameters that do not require a gradient are left out.
class GradientSync {
 public:
  GradientSync(DataParallel& parallel, const std::vector<torch::Tensor>& parameters);
  ~GradientSync();
  GradientSync(const GradientSync&) = delete;
  GradientSync& operator=(const GradientSync&) = delete;
  // Starts the buckets backward did not fill (their missing gradients as zeros), waits for all
  // and sets every parameter's gradient to the sum over the ranks.
  void finish();

 private:
  struct State;
  std::unique_ptr<State> state_;
};

// A loopback TCP port nobody listens on now (the kernel's choice): a MASTER_PORT for workers on
// this machine. Throws retarget::Error when no socket can be opened or bound.
int free_loopback_port();

// The data-parallel view a trainer takes: a group, or nothing (one process).
using DataParallelPtr = std::shared_ptr<DataParallel>;

}  // namespace retarget
