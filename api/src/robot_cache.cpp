// robot_cache.cpp — parsed robots kept by the document they came from, so a stored robot is parsed once
// per process, not at every submission, job and view (api/robot_requests.h: parsed_robot).
#include "manipid/api/robot_requests.h"

#include <list>
#include <mutex>

namespace manipid::api {
namespace {

struct CachedRobot {
  std::string urdf, base, tip;
  std::shared_ptr<const ParsedRobot> parsed;
};

/// Most recently used first.
class RobotCache {
 public:
  std::shared_ptr<const ParsedRobot> find(const RobotUpload& upload) {
    std::lock_guard<std::mutex> lock(mutex_);
    for (auto it = entries_.begin(); it != entries_.end(); ++it) {
      if (it->urdf == upload.urdf && it->base == upload.base && it->tip == upload.tip) {
        entries_.splice(entries_.begin(), entries_, it);
        return entries_.front().parsed;
      }
    }
    return nullptr;
  }

  void keep(const RobotUpload& upload, std::shared_ptr<const ParsedRobot> parsed) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (upload.urdf.size() > kRobotCacheBytes) return;
    for (const CachedRobot& entry : entries_) {  // another thread parsed it meanwhile
      if (entry.urdf == upload.urdf && entry.base == upload.base && entry.tip == upload.tip) return;
    }
    entries_.push_front({upload.urdf, upload.base, upload.tip, std::move(parsed)});
    bytes_ += upload.urdf.size();
    while (entries_.size() > kRobotCacheEntries || bytes_ > kRobotCacheBytes) {
      bytes_ -= entries_.back().urdf.size();
      entries_.pop_back();
    }
  }

 private:
  std::mutex mutex_;
  std::list<CachedRobot> entries_;
  std::size_t bytes_ = 0;
};

RobotCache& cache() {
  static RobotCache instance;
  return instance;
}

}  // namespace

std::shared_ptr<const ParsedRobot> parsed_robot(const RobotUpload& upload) {
  if (std::shared_ptr<const ParsedRobot> found = cache().find(upload)) return found;
  // Parsed outside the cache's lock: a slow parse keeps no other robot waiting.
  auto parsed = std::make_shared<const ParsedRobot>(parse_robot(upload));
  cache().keep(upload, parsed);
  return parsed;
}

}  // namespace manipid::api
