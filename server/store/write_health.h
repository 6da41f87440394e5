// write_health.h — whether a store's writes fail for want of space now: the state behind
// Store::write_trouble and /healthz's "degraded", kept the same way by every backend.
#pragma once

#include <atomic>
#include <mutex>
#include <optional>
#include <string>

namespace manipid::server::store {

/// Whether writes fail for want of space now (Store::write_trouble): set when a write
/// transaction ends in StorageFull, cleared by the next write transaction that commits a change. One per
/// store, shared by its connections; the clear is one atomic load when nothing failed.
class WriteHealth {
 public:
  void failed(const std::string& reason);
  void succeeded() noexcept;
  std::optional<std::string> trouble() const;

 private:
  mutable std::mutex mutex_;
  std::atomic<bool> troubled_{false};
  std::string reason_;
};

}  // namespace manipid::server::store
