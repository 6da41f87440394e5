// recent_datasets.h — the samples of the datasets the PostgreSQL store read last, kept in memory
// up to a byte budget (datasets never change once stored, so only their existence is asked again).
#pragma once

#include "manipid/core/signal/trajectory.h"

#include <cstddef>
#include <list>
#include <mutex>
#include <optional>
#include <string>

namespace manipid::server::store::postgres {

/// The samples of the datasets read last, up to a byte budget, oldest dropped first. Thread-safe.
class RecentDatasets {
 public:
  explicit RecentDatasets(std::size_t budget) : budget_(budget) {}

  /// The samples of dataset `id` if kept (it becomes the most recent).
  std::optional<Trajectory> find(const std::string& id);
  /// Keeps the samples of dataset `id`, unless they are above a quarter of the budget.
  void insert(const std::string& id, const Trajectory& data);
  void erase(const std::string& id);

 private:
  struct Entry {
    std::string id;
    Trajectory data;
    std::size_t bytes = 0;
  };
  std::size_t budget_;
  std::size_t held_ = 0;
  std::list<Entry> entries_;
  std::mutex mutex_;
};

}  // namespace manipid::server::store::postgres
