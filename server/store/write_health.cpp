// write_health.cpp — WriteHealth (see write_health.h).
#include "store/write_health.h"

namespace manipid::server::store {

void WriteHealth::failed(const std::string& reason) {
  std::lock_guard lock(mutex_);
  reason_ = reason;
  troubled_.store(true);
}

void WriteHealth::succeeded() noexcept {
  if (!troubled_.load()) return;
  std::lock_guard lock(mutex_);
  troubled_.store(false);
  reason_.clear();
}

std::optional<std::string> WriteHealth::trouble() const {
  if (!troubled_.load()) return std::nullopt;
  std::lock_guard lock(mutex_);
  if (!troubled_.load()) return std::nullopt;
  return reason_;
}

}  // namespace manipid::server::store
