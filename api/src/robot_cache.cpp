// robot_cache.cpp — stored robots parsed once per process, by robot id (robot_cache.h).
#include "manipid/api/robot_cache.h"

#include <utility>

namespace manipid::api {

RobotCache::RobotCache(std::size_t entries, std::size_t bytes) : most_entries_(entries), most_bytes_(bytes) {}

std::shared_ptr<const ParsedRobot> RobotCache::find(const std::string& id) {
  std::lock_guard<std::mutex> lock(mutex_);
  for (auto it = entries_.begin(); it != entries_.end(); ++it) {
    if (it->id == id) {
      entries_.splice(entries_.begin(), entries_, it);
      return entries_.front().parsed;
    }
  }
  return nullptr;
}

std::shared_ptr<const ParsedRobot> RobotCache::get(const RobotInfo& robot,
                                                   const std::function<std::optional<std::string>()>& load_urdf) {
  if (std::shared_ptr<const ParsedRobot> found = find(robot.id)) return found;
  const std::optional<std::string> urdf = load_urdf();
  if (!urdf) return nullptr;
  auto parsed = std::make_shared<const ParsedRobot>(parse_robot({robot.name, *urdf, robot.base, robot.tip}));
  keep(robot.id, parsed, urdf->size());
  // Another thread's parse, kept first, wins: every caller holds the same model. Not kept (too large): this one.
  std::shared_ptr<const ParsedRobot> kept = find(robot.id);
  return kept ? kept : parsed;
}

void RobotCache::keep(const std::string& id, std::shared_ptr<const ParsedRobot> parsed, std::size_t document_bytes) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (document_bytes > most_bytes_ || most_entries_ == 0) return;
  for (const Entry& entry : entries_) {
    if (entry.id == id) return;  // another thread parsed it meanwhile
  }
  entries_.push_front({id, document_bytes, std::move(parsed)});
  bytes_ += document_bytes;
  while (entries_.size() > most_entries_ || bytes_ > most_bytes_) {
    bytes_ -= entries_.back().bytes;
    entries_.pop_back();
  }
}

std::size_t RobotCache::size() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return entries_.size();
}

}  // namespace manipid::api
