#include "infer/memory_reuse.h"

#include <c10/core/Allocator.h>
#include <c10/core/CPUAllocator.h>
#include <c10/core/impl/alloc_cpu.h>

#include <atomic>
#include <map>
#include <mutex>
#include <unordered_map>

namespace retarget {

namespace {

constexpr size_t kMinimumBytes = size_t{1} << 20;  // smaller blocks: glibc reuses them well
constexpr size_t kGranule = size_t{64} << 10;      // sizes rounded up to 64 KB, so near sizes share blocks

class CachingCpuAllocator final : public c10::Allocator {
 public:
  CachingCpuAllocator(c10::Allocator* fallback, size_t max_cached) : fallback_(fallback), max_cached_(max_cached) {}

  c10::DataPtr allocate(size_t bytes) const override {
    if (bytes < kMinimumBytes) return fallback_->allocate(bytes);
    void* data = take((bytes + kGranule - 1) / kGranule * kGranule);
    return {data, data, &release, c10::Device(c10::DeviceType::CPU)};
  }

  c10::DeleterFnPtr raw_deleter() const override { return &release; }

  void set_cap(size_t max_cached) {
    std::lock_guard<std::mutex> lock(mutex_);
    max_cached_ = max_cached;
    trim();
  }

  size_t cached() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return cached_;
  }

  static void release(void* data);

 private:
  // A cached block of at least `size` bytes and not much more, else a new one.
  void* take(size_t size) const {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      const auto it = idle_.lower_bound(size);
      if (it != idle_.end() && it->first <= size + size / 4) {
        void* data = it->second;
        cached_ -= it->first;
        idle_.erase(it);
        return data;
      }
    }
    void* data = c10::alloc_cpu(size);
    std::lock_guard<std::mutex> lock(mutex_);
    size_of_[data] = size;
    return data;
  }

  void give_back(void* data) {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto it = size_of_.find(data);
    if (it == size_of_.end()) return;  // cannot happen: only our blocks carry this deleter
    idle_.emplace(it->second, data);
    cached_ += it->second;
    trim();
  }

  // Frees the largest idle blocks until the cap holds. mutex_ held.
  void trim() const {
    while (cached_ > max_cached_ && !idle_.empty()) {
      const auto largest = std::prev(idle_.end());
      cached_ -= largest->first;
      size_of_.erase(largest->second);
      c10::free_cpu(largest->second);
      idle_.erase(largest);
    }
  }

  c10::Allocator* fallback_;
  mutable std::mutex mutex_;
  mutable std::multimap<size_t, void*> idle_;          // size -> idle block
  mutable std::unordered_map<void*, size_t> size_of_;  // every block we own -> its size
  mutable size_t cached_ = 0;                          // bytes in idle_
  size_t max_cached_;
};

// Never destroyed: tensors may be freed during static destruction.
std::atomic<CachingCpuAllocator*> installed{nullptr};

void CachingCpuAllocator::release(void* data) {
  if (data) installed.load()->give_back(data);
}

}  // namespace

void reuse_tensor_memory(size_t max_cached_bytes) {
  static std::once_flag once;
  std::call_once(once, [max_cached_bytes] {
    auto* allocator = new CachingCpuAllocator(c10::GetCPUAllocator(), max_cached_bytes);
    installed.store(allocator);
    c10::SetCPUAllocator(allocator, /*priority=*/1);
  });
  installed.load()->set_cap(max_cached_bytes);
}

size_t cached_tensor_bytes() {
  const CachingCpuAllocator* allocator = installed.load();
  return allocator ? allocator->cached() : 0;
}

}  // namespace retarget
