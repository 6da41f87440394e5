// events.cpp — announcing job changes and listening for them over LISTEN/NOTIFY (see events.h).
#include "store/postgres/events.h"

#include <algorithm>
#include <chrono>
#include <optional>

namespace manipid::server::store::postgres {

namespace {

/// The channel every process LISTENs on; a payload is "<kind> <job id>" (JobEvent).
constexpr const char* kChannel = "manipid_jobs";

std::optional<JobEvent> parse_event(const std::string& payload) {
  const std::size_t space = payload.find(' ');
  if (space == std::string::npos) return std::nullopt;
  const std::string kind = payload.substr(0, space);
  JobEvent event;
  event.job_id = payload.substr(space + 1);
  if (kind == "queued") event.kind = JobEvent::Kind::queued;
  else if (kind == "cancel") event.kind = JobEvent::Kind::cancel_requested;
  else if (kind == "changed") event.kind = JobEvent::Kind::changed;
  else return std::nullopt;
  return event;
}

}  // namespace

void announce(Connection& connection, const char* kind, const std::string& id) {
  connection.exec(std::string("SELECT pg_notify('") + kChannel + "', $1)", Params().text(std::string(kind) + " " + id));
}

std::string announcement(const char* kind, const char* rows) {
  return std::string("SELECT pg_notify('") + kChannel + "', '" + kind + " ' || id) FROM " + rows;
}

JobListener::~JobListener() {
  {
    std::lock_guard lock(listen_mutex_);
    stop_listening_ = true;
  }
  listen_wake_.notify_all();
  if (listener_.joinable()) listener_.join();
}

void JobListener::watch(std::function<void(const JobEvent&)> on_event) {
  const bool watch = static_cast<bool>(on_event);
  {
    std::lock_guard lock(watcher_mutex_);  // waits for an event being handed over
    on_event_ = std::move(on_event);
  }
  std::unique_lock lock(listen_mutex_);
  if (watch && !listener_.joinable()) {
    listener_ = std::thread([this] { listen(); });
    // Heard from here on: return once the first LISTEN has been tried (a notification sent
    // before it would be missed). A database that is away does not hold this up for long:
    // the attempt fails and the watcher polls meanwhile.
    listen_wake_.wait_for(lock, std::chrono::seconds(10), [this] { return listen_attempted_ || stop_listening_; });
  }
}

void JobListener::listen() {
  std::chrono::milliseconds pause{100};
  const auto stopping = [this] {
    std::lock_guard lock(listen_mutex_);
    return stop_listening_;
  };
  while (!stopping()) {
    const auto attempted = [this] {
      {
        std::lock_guard lock(listen_mutex_);
        listen_attempted_ = true;
      }
      listen_wake_.notify_all();
    };
    try {
      Connection connection(conninfo_);
      connection.execute(std::string("LISTEN ") + kChannel);
      attempted();
      pause = std::chrono::milliseconds(100);
      while (!stopping()) {
        for (const std::string& payload : connection.notifications(std::chrono::milliseconds(200))) {
          const auto event = parse_event(payload);
          if (!event) continue;
          std::lock_guard lock(watcher_mutex_);
          if (on_event_) on_event_(*event);
        }
      }
    } catch (const StoreError&) {
      // The database is away: try again after a pause that grows to 5 s.
      attempted();
    }
    std::unique_lock lock(listen_mutex_);
    listen_wake_.wait_for(lock, pause, [this] { return stop_listening_; });
    pause = std::min(pause * 2, std::chrono::milliseconds(5000));
  }
}

}  // namespace manipid::server::store::postgres
