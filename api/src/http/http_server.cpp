// http_server.cpp — HttpServer (http_server.h): cpp-httplib 0.11.4's connection loop, taken
// back so that a refusal closes its connection, the backlog is ours, a late request head or
// body is cut off and stopping shuts every connection down. Requests are still read by httplib itself.
#include "manipid/api/http_server.h"

#include <poll.h>
#include <sys/socket.h>

#include <algorithm>
#include <array>
#include <deque>
#include <functional>
#include <limits>
#include <vector>

namespace manipid::api {
namespace {

using Clock = std::chrono::steady_clock;

/// The connection this thread is serving, for the static calls made from hooks and handlers.
thread_local HttpServer* current_server = nullptr;
thread_local socket_t current_socket = INVALID_SOCKET;
thread_local bool close_requested = false;

/// After an answer that closes the connection: the client's unread bytes (a refused body) are
/// read and dropped for at most this long and this much, so that closing does not reset the
/// connection (a close with unread data sends RST, and the client may lose the answer). An
/// honest client that sends its whole too-large body before reading (curl without
/// Expect: 100-continue, Python's http.client) still reads its 413 when the body fits.
constexpr auto linger_time = std::chrono::milliseconds(2000);
constexpr std::size_t linger_bytes = 64u << 20;

/// Waits until `sock` is readable (or closed): false when `timeout` passes first.
bool wait_readable(socket_t sock, std::chrono::milliseconds timeout) {
  pollfd descriptor{sock, POLLIN, 0};
  const int ready = ::poll(&descriptor, 1, static_cast<int>(std::max<std::chrono::milliseconds::rep>(timeout.count(), 0)));
  return ready > 0;
}

/// Half-closes, drops what the client still sends (bounded), and lets the caller close.
void linger(socket_t sock) {
  ::shutdown(sock, SHUT_WR);
  const auto deadline = Clock::now() + linger_time;
  std::array<char, 16384> sink{};
  std::size_t dropped = 0;
  while (dropped < linger_bytes) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now());
    if (left.count() <= 0 || !wait_readable(sock, left)) break;
    const ssize_t n = ::recv(sock, sink.data(), sink.size(), 0);
    if (n <= 0) break;
    dropped += static_cast<std::size_t>(n);
  }
}

/// httplib::ThreadPool plus a count of the connections waiting for a thread (its own queue is
/// private), so an idle keep-alive connection can give its thread up to one.
class CountingPool : public httplib::TaskQueue {
 public:
  CountingPool(std::size_t threads, std::atomic<std::size_t>& queued) : queued_(queued) {
    try {
      for (std::size_t i = 0; i < threads; ++i) threads_.emplace_back([this] { work(); });
    } catch (...) {
      // No thread for them all (a thread or address-space limit): the ones started must end
      // before the members they wait on go, or destroying the condition variable waits for ever
      // and the server listens without serving anyone.
      shutdown();
      throw;
    }
  }
  ~CountingPool() override { shutdown(); }

  void enqueue(std::function<void()> task) override {
    {
      std::lock_guard lock(mutex_);
      tasks_.push_back(std::move(task));
      ++queued_;
    }
    ready_.notify_one();
  }

  void shutdown() override {
    {
      std::lock_guard lock(mutex_);
      stopping_ = true;
    }
    ready_.notify_all();
    for (std::thread& thread : threads_) {
      if (thread.joinable()) thread.join();
    }
  }

 private:
  void work() {
    for (;;) {
      std::function<void()> task;
      {
        std::unique_lock lock(mutex_);
        ready_.wait(lock, [this] { return stopping_ || !tasks_.empty(); });
        if (tasks_.empty()) return;  // stopping, and every accepted connection served
        task = std::move(tasks_.front());
        tasks_.pop_front();
        --queued_;
      }
      task();
    }
  }

  std::atomic<std::size_t>& queued_;
  std::vector<std::thread> threads_;
  std::deque<std::function<void()>> tasks_;
  std::mutex mutex_;
  std::condition_variable ready_;
  bool stopping_ = false;
};

}  // namespace

HttpServer::HttpServer() = default;

void HttpServer::set_http_threads(std::size_t threads) {
  new_task_queue = [this, threads] { return new CountingPool(std::max<std::size_t>(threads, 1), queued_); };
}

HttpServer::~HttpServer() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  changed_.notify_all();
  if (watchdog_.joinable()) watchdog_.join();
}

int HttpServer::bind(const std::string& host, int port) {
  if (port == 0) {
    port = bind_to_any_port(host);
  } else if (!bind_to_port(host, port)) {
    port = -1;
  }
  if (port <= 0) return -1;
  // 0.11.4 listens with a backlog of 5; listen() again on the bound socket sets ours.
  if (::listen(svr_sock_, backlog_) != 0) return -1;
  if (header_deadline_.count() > 0 && !watchdog_.joinable()) watchdog_ = std::thread([this] { watch_deadlines(); });
  return port;
}

void HttpServer::stop_and_disconnect(std::chrono::milliseconds grace) {
  stop();
  std::unique_lock lock(mutex_);
  stopping_ = true;
  // Reading ends at once (a trickling head, an idle keep-alive): those threads return now.
  // An answer being written (a long-poll woken by the shutdown) may finish within `grace`.
  for (const auto& [sock, deadline] : connections_) ::shutdown(sock, SHUT_RD);
  changed_.notify_all();
  changed_.wait_for(lock, grace, [this] { return connections_.empty(); });
  for (const auto& [sock, deadline] : connections_) ::shutdown(sock, SHUT_RDWR);
}

void HttpServer::close_after_answer(httplib::Response& response) {
  if (!response.has_header("Connection")) response.set_header("Connection", "close");
  close_requested = true;
}

void HttpServer::head_received(std::uint64_t declared_body) {
  if (current_server == nullptr) return;
  HttpServer& server = *current_server;
  auto deadline = Clock::time_point::max();
  if (declared_body > 0 && server.header_deadline_.count() > 0 && server.body_rate_ > 0) {
    const double seconds = static_cast<double>(declared_body) / static_cast<double>(server.body_rate_);
    deadline = Clock::now() + server.header_deadline_ +
               std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(std::min(seconds, 1e7)));
  }
  std::lock_guard lock(server.mutex_);
  if (auto found = server.connections_.find(current_socket); found != server.connections_.end()) found->second = deadline;
}

void HttpServer::body_received() { head_received(0); }

/// Waits for the next request on a kept-alive connection: false when `idle` passes first, or
/// as soon as an accepted connection is waiting for a thread (this one then gives its thread up).
bool HttpServer::wait_next_request(socket_t sock, std::chrono::milliseconds idle) {
  const auto deadline = Clock::now() + idle;
  constexpr auto slice = std::chrono::milliseconds(50);
  for (;;) {
    if (queued_ > 0) return false;
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now());
    if (left.count() <= 0) return false;
    if (wait_readable(sock, std::min(left, std::chrono::milliseconds(slice)))) return true;
  }
}

/// Shuts down the connections whose request head is late; the thread reading it then sees the
/// end of the stream, and httplib gives up on the request.
void HttpServer::watch_deadlines() {
  std::unique_lock lock(mutex_);
  while (!stopping_) {
    changed_.wait_for(lock, std::chrono::milliseconds(200));
    const auto now = Clock::now();
    for (const auto& [sock, deadline] : connections_) {
      if (deadline <= now) ::shutdown(sock, SHUT_RDWR);
    }
  }
}

/// The keep-alive loop of 0.11.4 (process_server_socket), plus: the connection ends after an
/// answer given close_after_answer, when the server stops, or when a request head is late.
bool HttpServer::process_and_close_socket(socket_t sock) {
  {
    std::lock_guard lock(mutex_);
    if (stopping_) {
      ::shutdown(sock, SHUT_RDWR);
      httplib::detail::close_socket(sock);
      return false;
    }
    connections_.emplace(sock, Clock::time_point::max());
  }
  current_server = this;
  current_socket = sock;
  bool answered = false;
  bool lingering = false;
  const std::chrono::milliseconds idle{std::chrono::seconds(keep_alive_timeout_sec_)};
  for (std::size_t count = keep_alive_max_count_; count > 0 && svr_sock_ != INVALID_SOCKET; --count) {
    if (count == keep_alive_max_count_) {
      if (!wait_readable(sock, idle)) break;
    } else if (!wait_next_request(sock, idle)) {
      break;
    }
    {
      std::lock_guard lock(mutex_);
      if (stopping_) break;
      connections_[sock] = header_deadline_.count() > 0 ? Clock::now() + header_deadline_ : Clock::time_point::max();
    }
    close_requested = false;
    bool client_closes = false;
    answered = httplib::detail::process_client_socket(
        sock, read_timeout_sec_, read_timeout_usec_, write_timeout_sec_, write_timeout_usec_,
        [&](httplib::Stream& stream) { return process_request(stream, count == 1, client_closes, nullptr); });
    {
      std::lock_guard lock(mutex_);
      connections_[sock] = Clock::time_point::max();
    }
    if (close_requested) lingering = answered;
    if (!answered || client_closes || close_requested) break;
  }
  close_requested = false;
  current_server = nullptr;
  current_socket = INVALID_SOCKET;
  if (lingering) linger(sock);
  {
    std::lock_guard lock(mutex_);
    connections_.erase(sock);
    ::shutdown(sock, SHUT_RDWR);
    httplib::detail::close_socket(sock);
  }
  changed_.notify_all();
  return answered;
}

}  // namespace manipid::api
