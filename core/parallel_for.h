// Independent items on the machine's cores: the few places that fan plain C++ work (rendering
// pictures, describing meshes) out over threads without LibTorch's pool.
#pragma once

#include <functional>

namespace retarget {

// Calls work(i) for every i in [0, count) on up to available_cpus() threads (this one among
// them), each taking the next item as it finishes one. Every item runs even when some throw; the
// first exception by item order is rethrown after all have finished.
void parallel_for(int count, const std::function<void(int)>& work);

}  // namespace retarget
