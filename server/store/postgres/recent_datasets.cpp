// recent_datasets.cpp — the PostgreSQL store's in-memory samples of recent datasets (see recent_datasets.h).
#include "store/postgres/recent_datasets.h"

namespace manipid::server::store::postgres {

std::optional<Trajectory> RecentDatasets::find(const std::string& id) {
  std::lock_guard lock(mutex_);
  for (auto entry = entries_.begin(); entry != entries_.end(); ++entry) {
    if (entry->id != id) continue;
    entries_.splice(entries_.begin(), entries_, entry);  // now the most recent
    return entry->data;
  }
  return std::nullopt;
}

void RecentDatasets::insert(const std::string& id, const Trajectory& data) {
  const std::size_t bytes = sizeof(double) * static_cast<std::size_t>(data.t.size() + data.q.size() + data.tau.size() +
                                                                      data.ref.size() + data.qd.size() + data.qdd.size());
  if (bytes > budget_ / 4) return;  // a huge dataset is read when needed, not kept
  std::lock_guard lock(mutex_);
  for (const auto& entry : entries_) {
    if (entry.id == id) return;
  }
  entries_.push_front({id, data, bytes});
  held_ += bytes;
  while (held_ > budget_) {
    held_ -= entries_.back().bytes;
    entries_.pop_back();
  }
}

void RecentDatasets::erase(const std::string& id) {
  std::lock_guard lock(mutex_);
  entries_.remove_if([&](const Entry& entry) {
    if (entry.id != id) return false;
    held_ -= entry.bytes;
    return true;
  });
}

}  // namespace manipid::server::store::postgres
