// OpenMP's idle threads sleep instead of spinning, so that jobs sharing cores (two trainings, a
// training beside a build, CI's ctest -j2) slow each other down in proportion instead of
// collapsing. LibTorch's GNU OpenMP spins a while on every barrier by default; when more threads
// than cores want to run, the spinning ones take the cores the working ones need. Measured
// (2-core AMD EPYC, two paper-size avatar VAE trainings side by side, each alone 47 samples/s):
// 18 and 19 samples/s spinning, 25 and 25 passive; alone, passive costs nothing (48/s).
//
// libgomp reads OMP_WAIT_POLICY once, when it is loaded, so the executables set it and start
// themselves again before doing anything else. A policy the user set is kept.
#pragma once

namespace retarget {

// When OMP_WAIT_POLICY is unset: sets it to PASSIVE and replaces this process with a fresh run
// of the same executable and arguments (execv of /proc/self/exe). Returns only when the policy
// was set already, or when the new start failed (the process then goes on spinning). Call first
// thing in main(), before any thread exists.
void restart_with_passive_wait(char** argv);

}  // namespace retarget
