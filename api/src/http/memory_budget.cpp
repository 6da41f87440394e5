// memory_budget.cpp — the reservations of memory_budget.h, one per HTTP thread.
#include "http/memory_budget.h"

namespace manipid::api::http {
namespace {

/// The calling thread's reservation: which budget, how many bytes.
struct Held {
  MemoryBudget* budget = nullptr;
  std::size_t bytes = 0;
};
thread_local Held held;

}  // namespace

bool MemoryBudget::reserve(std::size_t bytes) {
  std::lock_guard lock(mutex_);
  const std::size_t others = reserved_ - (held.budget == this ? held.bytes : 0);
  if (bytes > budget_ - others) return false;
  reserved_ = others + bytes;
  held = {this, bytes};
  return true;
}

void MemoryBudget::release() {
  if (held.budget != this) return;
  std::lock_guard lock(mutex_);
  reserved_ -= held.bytes;
  held = {};
}

std::size_t MemoryBudget::reserved() const {
  std::lock_guard lock(mutex_);
  return reserved_;
}

}  // namespace manipid::api::http
