// robot_cache.h — stored robots parsed once per process: a bounded, thread-safe LRU of parsed models keyed
// by robot id. A robot's row and document never change (a different document is another robot, another id),
// so its id is the whole key. One cache serves a process's routes (api/service.h: Service::parsed_robot) and
// its job runner (server/jobs/job_runner.h: RunnerOptions::robots); callers check first that the caller may
// see the robot (the id is the same for every owner).
#pragma once

#include "manipid/api/records.h"
#include "manipid/api/robot_requests.h"

#include <cstddef>
#include <functional>
#include <list>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

namespace manipid::api {

class RobotCache {
 public:
  /// The last `entries` robots used, at most `bytes` of their documents (a larger document is parsed, not kept).
  explicit RobotCache(std::size_t entries = kRobotCacheEntries, std::size_t bytes = kRobotCacheBytes);
  RobotCache(const RobotCache&) = delete;
  RobotCache& operator=(const RobotCache&) = delete;

  /// `robot` parsed: the kept model, else its document from `load_urdf` parsed (outside the cache's lock: a
  /// slow parse keeps no other robot waiting) and kept. nullptr when load_urdf finds no document (the robot was
  /// deleted). Throws what parse_robot throws; a refusal is not kept.
  std::shared_ptr<const ParsedRobot> get(const RobotInfo& robot,
                                         const std::function<std::optional<std::string>()>& load_urdf);
  /// Keeps a robot parsed elsewhere (at its upload) under its id; `document_bytes` its URDF's size.
  void keep(const std::string& id, std::shared_ptr<const ParsedRobot> parsed, std::size_t document_bytes);
  /// Robots kept now.
  std::size_t size() const;

 private:
  struct Entry {
    std::string id;
    std::size_t bytes = 0;
    std::shared_ptr<const ParsedRobot> parsed;
  };
  std::shared_ptr<const ParsedRobot> find(const std::string& id);

  const std::size_t most_entries_, most_bytes_;
  mutable std::mutex mutex_;
  std::list<Entry> entries_;  ///< most recently used first
  std::size_t bytes_ = 0;
};

}  // namespace manipid::api
