// memory_budget.h — internal to the routes: the memory set aside for the request bodies being
// read and handled now (--memory-budget), so that many large uploads at once are refused with
// 503 and Retry-After instead of taking the process past what the machine has.
#pragma once

#include <cstddef>
#include <mutex>

namespace manipid::api::http {

/// Each request reserves before its body is read (the pre-routing hook) and gives back once its
/// answer is made (the post-routing hook, which cpp-httplib 0.11.4 runs for every request that
/// got past pre-routing, a body that never arrived included). An HTTP thread serves one request
/// at a time, so a reservation belongs to the calling thread.
class MemoryBudget {
 public:
  explicit MemoryBudget(std::size_t bytes) : budget_(bytes) {}

  /// Reserves `bytes` for the calling thread's request, in place of what it held; false (its
  /// reservation unchanged) when the budget has no room for them now.
  bool reserve(std::size_t bytes);
  /// Gives back the calling thread's reservation, if it holds one.
  void release();
  /// Bytes reserved now, by every thread.
  std::size_t reserved() const;
  std::size_t budget() const { return budget_; }

 private:
  mutable std::mutex mutex_;
  const std::size_t budget_;
  std::size_t reserved_ = 0;
};

}  // namespace manipid::api::http
