#include "cli/train_launcher.h"

#include <fmt/format.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <map>
#include <thread>

#include "core/cpu_threads.h"
#include "core/error.h"
#include "core/log.h"
#include "core/process_environment.h"
#include "train/data_parallel.h"

namespace retarget::cli {

namespace {

// Starts one worker. argv and the environment are built before the fork: between fork and exec
// the child only calls async-signal-safe functions (this process may have LibTorch's threads).
pid_t start_worker(const std::vector<std::string>& args, int rank, int nproc, int port) {
  std::map<std::string, std::string> set{
      {"WORLD_SIZE", std::to_string(nproc)}, {"RANK", std::to_string(rank)},
      {"LOCAL_RANK", std::to_string(rank)},  {"LOCAL_WORLD_SIZE", std::to_string(nproc)},
      {"MASTER_ADDR", "127.0.0.1"},          {"MASTER_PORT", std::to_string(port)}};
  // The workers share this machine's cores, as torchrun has them (a count the user set stays).
  if (!std::getenv("OMP_NUM_THREADS")) set["OMP_NUM_THREADS"] = std::to_string(std::max(1, available_cpus() / nproc));
  std::vector<std::string> env_storage = environment_with(set);
  std::vector<std::string> arg_storage{"retarget"};
  arg_storage.insert(arg_storage.end(), args.begin(), args.end());
  std::vector<char*> argv, envp;
  for (std::string& a : arg_storage) argv.push_back(a.data());
  argv.push_back(nullptr);
  for (std::string& e : env_storage) envp.push_back(e.data());
  envp.push_back(nullptr);
  const pid_t parent = ::getpid();
  const pid_t pid = ::fork();
  if (pid < 0) throw Error("--nproc", "cannot start a worker process (fork failed)");
  if (pid == 0) {
    // A launcher that dies (killed, say) takes its workers with it: none goes on writing the run
    // folder beside the run that resumes it.
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (::getppid() != parent) ::_exit(126);  // the launcher died before prctl
    ::execve("/proc/self/exe", argv.data(), envp.data());
    ::_exit(127);  // exec failed
  }
  return pid;
}

std::string describe(int status) {
  if (WIFEXITED(status)) return fmt::format("exited with code {}", WEXITSTATUS(status));
  if (WIFSIGNALED(status))
    return fmt::format("was killed by signal {} ({})", WTERMSIG(status), strsignal(WTERMSIG(status)));
  return "stopped";
}

// Stops every worker still running: SIGTERM, then SIGKILL to those left after 10 s.
void stop_all(std::map<pid_t, int>& running) {
  for (const auto& [pid, rank] : running) ::kill(pid, SIGTERM);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (!running.empty() && std::chrono::steady_clock::now() < deadline) {
    int status = 0;
    const pid_t pid = ::waitpid(-1, &status, WNOHANG);
    if (pid > 0)
      running.erase(pid);
    else
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  for (const auto& [pid, rank] : running) {
    ::kill(pid, SIGKILL);
    ::waitpid(pid, nullptr, 0);
  }
  running.clear();
}

}  // namespace

int launch_local_workers(int nproc, const std::vector<std::string>& args) {
  if (nproc < 1 || nproc > 256) throw Error("--nproc", fmt::format("expected 1..256 workers, got {}", nproc));
  const int port = free_loopback_port();
  log::info("starting {} data-parallel workers on 127.0.0.1:{}", nproc, port);
  std::map<pid_t, int> running;
  for (int rank = 0; rank < nproc; ++rank) running[start_worker(args, rank, nproc, port)] = rank;
  while (!running.empty()) {
    int status = 0;
    const pid_t pid = ::waitpid(-1, &status, 0);
    if (pid < 0) break;
    const auto it = running.find(pid);
    if (it == running.end()) continue;
    const int rank = it->second;
    running.erase(it);
    if (WIFEXITED(status) && WEXITSTATUS(status) == 0) continue;
    const size_t left = running.size();
    stop_all(running);
    throw Error("retarget train --nproc",
                fmt::format("worker rank {} of {} {}; stopped the {} other worker(s). Rank 0's last checkpoint "
                            "stays: continue with --resume (any --nproc)",
                            rank, nproc, describe(status), left));
  }
  return 0;
}

}  // namespace retarget::cli
