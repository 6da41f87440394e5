// events.h — the PostgreSQL store's job events through LISTEN/NOTIFY: a change announced inside
// the transaction that makes it (NOTIFY is sent at commit, never for a rollback), and the
// listener thread that hands every process's announcements to the watcher (Store::watch_jobs).
#pragma once

#include "store/postgres/connection.h"

#include <condition_variable>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <utility>

namespace manipid::server::store::postgres {

/// Tells every listening process, when the transaction commits (NOTIFY is transactional: a
/// rolled-back change is never announced). `kind`: "queued", "cancel" or "changed" (JobEvent).
void announce(Connection& connection, const char* kind, const std::string& id);

/// The tail of a statement whose CTE `rows` returns the ids of changed jobs: announces each
/// (as announce does) in the same round trip; the statement returns one row per id.
std::string announcement(const char* kind, const char* rows);

/// One connection of its own LISTENing on the channel, on a thread the first watcher starts,
/// handing each notification to the watcher; a lost connection is opened again (events
/// meanwhile are missed: watchers poll as well).
class JobListener {
 public:
  explicit JobListener(std::string conninfo) : conninfo_(std::move(conninfo)) {}
  ~JobListener();  ///< stops the thread and waits for it
  JobListener(const JobListener&) = delete;
  JobListener& operator=(const JobListener&) = delete;

  /// Store::watch_jobs: `on_event` replaces the watcher (empty: none), once an event being
  /// handed over has been. The first watcher starts the thread, and this returns once its
  /// first LISTEN has been tried (up to 10 s).
  void watch(std::function<void(const JobEvent&)> on_event);

 private:
  void listen();

  std::string conninfo_;
  std::mutex watcher_mutex_;  ///< guards on_event_, held while it runs
  std::function<void(const JobEvent&)> on_event_;
  std::mutex listen_mutex_;
  std::condition_variable listen_wake_;
  bool stop_listening_ = false;
  bool listen_attempted_ = false;  ///< the listener's first LISTEN has succeeded or failed
  std::thread listener_;  ///< last: joined (in the destructor) before the members it uses go
};

}  // namespace manipid::server::store::postgres
