// http_server.cpp — HttpServer (http_server.h): cpp-httplib 0.11.4's connection handling taken
// back. A reactor thread holds the connections waiting for a request head; an HTTP thread
// serves a connection only once its head is buffered, through a stream that serves those bytes
// first; requests are still parsed and answered by httplib's own process_request.
#include "manipid/api/http_server.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/epoll.h>
#include <sys/eventfd.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstring>
#include <limits>
#include <new>
#include <system_error>
#include <utility>

namespace manipid::api {
namespace {

using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;

/// After an answer that closes the connection: the client's unread bytes (a refused body) are
/// read and dropped for at most this long and this much, so that closing does not reset the
/// connection (a close with unread data sends RST, and the client may lose the answer). An
/// honest client that sends its whole too-large body before reading (curl without
/// Expect: 100-continue, Python's http.client) still reads its 413 when the body fits.
constexpr auto linger_time = milliseconds(2000);
constexpr std::size_t linger_bytes = 64u << 20;

/// A request head longer than this is handed to httplib as it stands, which then finds no end
/// to it and answers 400 (0.11.4 bounds each line, 8 KiB, but not their number). Browsers and
/// proxies send a few KiB; nginx's default buffers take 4 × 8 KiB.
constexpr std::size_t head_limit = 64u << 10;
/// 0.11.4 answers 414 for a request line longer than this (CPPHTTPLIB_REQUEST_URI_MAX_LENGTH).
constexpr std::size_t request_line_limit = 8192;
/// What one read takes at most (the reactor's, and a body's read-ahead).
constexpr std::size_t read_chunk = 16384;
/// An HTTP thread beyond --http-threads (started while others read bodies) ends once it has
/// had nothing to do for this long.
constexpr auto extra_thread_idle = std::chrono::seconds(5);
/// How often the reactor looks at its deadlines, and at most how often it logs closures.
constexpr auto sweep_interval = milliseconds(100);
constexpr auto log_interval = std::chrono::seconds(10);

/// Waits until `sock` is ready for `events` (or closed, or failed): false when `timeout` passes first.
bool wait_for(socket_t sock, short events, milliseconds timeout) {
  const auto deadline = Clock::now() + timeout;
  for (;;) {
    const auto left = std::chrono::duration_cast<milliseconds>(deadline - Clock::now()).count();
    pollfd descriptor{sock, events, 0};
    const int ready = ::poll(&descriptor, 1, static_cast<int>(std::clamp<long long>(left, 0, std::numeric_limits<int>::max())));
    if (ready > 0) return true;
    if (ready == 0 || errno != EINTR) return false;
  }
}

/// The address as the logs show it, and the key the per-client limits count by: an IPv4
/// address (also when mapped into IPv6), or an IPv6 address's /64, which a single subscriber
/// usually holds whole (counting its addresses one by one would be no limit at all).
void describe_peer(socket_t sock, std::string& shown, std::string& key, int& port) {
  sockaddr_storage address{};
  socklen_t length = sizeof address;
  shown = key = "unknown";
  port = 0;
  if (::getpeername(sock, reinterpret_cast<sockaddr*>(&address), &length) != 0) return;
  char text[INET6_ADDRSTRLEN] = {};
  if (address.ss_family == AF_INET) {
    const auto& v4 = reinterpret_cast<const sockaddr_in&>(address);
    ::inet_ntop(AF_INET, &v4.sin_addr, text, sizeof text);
    shown = key = text;
    port = ntohs(v4.sin_port);
  } else if (address.ss_family == AF_INET6) {
    const auto& v6 = reinterpret_cast<const sockaddr_in6&>(address);
    ::inet_ntop(AF_INET6, &v6.sin6_addr, text, sizeof text);
    shown = text;
    port = ntohs(v6.sin6_port);
    if (IN6_IS_ADDR_V4MAPPED(&v6.sin6_addr)) {
      ::inet_ntop(AF_INET, &v6.sin6_addr.s6_addr[12], text, sizeof text);
      key = text;
    } else {
      in6_addr prefix = v6.sin6_addr;
      std::memset(&prefix.s6_addr[8], 0, 8);
      ::inet_ntop(AF_INET6, &prefix, text, sizeof text);
      key = std::string(text) + "/64";
    }
  }
}

/// The process's open-file limit raised to its hard limit (each connection is a descriptor, and
/// a soft limit of 1024 is common); the soft limit now in force.
rlim_t raise_open_file_limit() {
  rlimit limit{};
  if (::getrlimit(RLIMIT_NOFILE, &limit) != 0) return 1024;
  if (limit.rlim_cur < limit.rlim_max) {
    rlimit raised = limit;
    raised.rlim_cur = limit.rlim_max;
    if (::setrlimit(RLIMIT_NOFILE, &raised) == 0) limit = raised;
  }
  return limit.rlim_cur;
}

}  // namespace

/// One client connection. Owned by one thread at a time: the reactor while it waits for a head
/// (or lingers), the ready queue, then the HTTP thread serving it; `deadline` and `upload` are
/// read by others, under the server's mutex_.
struct HttpServer::Connection {
  socket_t fd = INVALID_SOCKET;
  std::string shown;   ///< remote address, as the logs show it
  std::string client;  ///< the key of the per-client limits (describe_peer)
  int port = 0;

  /// Bytes read and not yet consumed: buffer[start, size()). The head search resumes at `scan`
  /// within the line starting at `line`.
  std::string buffer;
  std::size_t start = 0;
  std::size_t line = 0;
  std::size_t scan = 0;
  bool request_line_seen = false;
  /// The buffered head is whole: the stream reads the socket after it. Otherwise (the client
  /// closed, or the head is unreadable or too long) the stream ends with the buffer, so httplib
  /// answers 400 or 414 from what arrived and never waits on the socket for a head.
  bool complete = false;
  std::size_t served = 0;  ///< requests answered

  // Held by the reactor:
  bool lingering = false;
  bool head_begun = false;
  Clock::time_point until;  ///< closed then: idle, head deadline, end of lingering
  std::size_t dropped = 0;  ///< bytes dropped while lingering
  std::list<Connection*>::iterator in_order;
  std::list<Connection*>::iterator in_client;

  // Served, under the server's mutex_:
  Clock::time_point deadline = Clock::time_point::max();
  bool upload = false;  ///< holds one of the upload places (admit_body)

  std::size_t pending() const { return buffer.size() - start; }

  /// Drops the consumed bytes and starts looking for the next head at the first unread one.
  void begin_head() {
    buffer.erase(0, start);
    start = line = scan = 0;
    request_line_seen = false;
    complete = false;
  }

  enum class Head { partial, whole, unreadable };

  /// Where the head starting at `start` stands, read as httplib reads it: lines end at '\n';
  /// after the request line, the first line that is exactly "\r\n" ends the head (0.11.4 skips
  /// lines ending in a bare '\n'). A request line that cannot be one (not ending in
  /// " HTTP/1.x\r\n", or over httplib's limit) is `unreadable` at once: httplib refuses it
  /// without reading further, as it did when it read the socket itself.
  Head find_head() {
    for (;;) {
      const std::size_t end = buffer.find('\n', scan);
      if (end == std::string::npos) {
        scan = buffer.size();
        if (!request_line_seen && buffer.size() - line > request_line_limit) return Head::unreadable;
        return pending() > head_limit ? Head::unreadable : Head::partial;
      }
      const std::size_t length = end + 1 - line;
      if (!request_line_seen) {
        request_line_seen = true;
        const std::string_view text(buffer.data() + line, length);
        const bool versioned = text.size() > 11 && (text.substr(text.size() - 11) == " HTTP/1.1\r\n" ||
                                                    text.substr(text.size() - 11) == " HTTP/1.0\r\n");
        if (!versioned || length > request_line_limit) return Head::unreadable;
      } else if (length == 2 && buffer[line] == '\r') {
        return Head::whole;
      }
      line = scan = end + 1;
      if (line - start > head_limit) return Head::unreadable;
    }
  }
};

namespace {

/// The connection this thread is serving, for the static calls made from hooks and handlers.
thread_local HttpServer* current_server = nullptr;
thread_local HttpServer::Connection* current_connection = nullptr;
thread_local bool close_requested = false;

void close_connection(HttpServer::Connection& connection) {
  if (connection.fd == INVALID_SOCKET) return;
  ::shutdown(connection.fd, SHUT_RDWR);
  httplib::detail::close_socket(connection.fd);
  connection.fd = INVALID_SOCKET;
}

}  // namespace

/// httplib's accept loop runs each accepted socket through its task queue: this one hands it
/// to the reactor at once, on the accepting thread; its shutdown (the loop has ended) stops the
/// reactor and the HTTP threads.
class HttpServer::AcceptQueue final : public httplib::TaskQueue {
 public:
  explicit AcceptQueue(HttpServer& server) : server_(server) {}
  void enqueue(std::function<void()> task) override { task(); }  // process_and_close_socket: quick
  void shutdown() override { server_.finish_serving(); }

 private:
  HttpServer& server_;
};

/// What process_request reads a request from and writes its answer to: the connection's
/// buffered bytes first, then its socket (non-blocking, waited on with the read and write
/// timeouts). Bytes read past the request stay in the buffer for the next one.
class HttpServer::Stream final : public httplib::Stream {
 public:
  Stream(Connection& connection, milliseconds read_timeout, milliseconds write_timeout)
      : connection_(connection), read_timeout_(read_timeout), write_timeout_(write_timeout) {}

  bool is_readable() const override {
    return connection_.pending() > 0 || (connection_.complete && wait_for(connection_.fd, POLLIN, read_timeout_));
  }

  bool is_writable() const override {
    pollfd descriptor{connection_.fd, POLLOUT, 0};
    const int ready = ::poll(&descriptor, 1, static_cast<int>(write_timeout_.count()));
    return ready > 0 && (descriptor.revents & POLLOUT) != 0 && (descriptor.revents & (POLLERR | POLLHUP)) == 0;
  }

  ssize_t read(char* ptr, std::size_t size) override {
    Connection& c = connection_;
    if (size == 0) return 0;
    if (c.pending() > 0) return take(ptr, size);
    if (!c.complete) return 0;  // a head handed over as it stood: nothing after it is read
    c.buffer.clear();
    c.start = 0;
    const auto deadline = Clock::now() + read_timeout_;
    for (;;) {
      const auto left = std::chrono::duration_cast<milliseconds>(deadline - Clock::now());
      if (left.count() <= 0 || !wait_for(c.fd, POLLIN, left)) return -1;  // the read timeout
      ssize_t n;
      if (size >= read_chunk) {
        n = ::recv(c.fd, ptr, size, MSG_DONTWAIT);
        if (n >= 0) return n;
      } else {
        c.buffer.resize(read_chunk);
        n = ::recv(c.fd, c.buffer.data(), read_chunk, MSG_DONTWAIT);
        c.buffer.resize(n > 0 ? static_cast<std::size_t>(n) : 0);
        if (n > 0) return take(ptr, size);
        if (n == 0) return 0;
      }
      if (errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR) return -1;
    }
  }

  /// All of it, or -1: 0.11.4 writes an answer's head and body with one call each and takes a
  /// short count for success (its own socket blocks until all is sent).
  ssize_t write(const char* ptr, std::size_t size) override {
    std::size_t sent = 0;
    while (sent < size) {
      const ssize_t n = ::send(connection_.fd, ptr + sent, size - sent, MSG_NOSIGNAL | MSG_DONTWAIT);
      if (n > 0) {
        sent += static_cast<std::size_t>(n);
      } else if (n < 0 && errno == EINTR) {
        continue;
      } else if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) {
        if (!wait_for(connection_.fd, POLLOUT, write_timeout_)) return -1;
      } else {
        return -1;
      }
    }
    return static_cast<ssize_t>(size);
  }

  void get_remote_ip_and_port(std::string& ip, int& port) const override {
    ip = connection_.shown;
    port = connection_.port;
  }

  void get_local_ip_and_port(std::string& ip, int& port) const override {
    sockaddr_storage address{};
    socklen_t length = sizeof address;
    ip.clear();
    port = 0;
    if (::getsockname(connection_.fd, reinterpret_cast<sockaddr*>(&address), &length) != 0) return;
    char text[INET6_ADDRSTRLEN] = {};
    if (address.ss_family == AF_INET) {
      const auto& v4 = reinterpret_cast<const sockaddr_in&>(address);
      ip = ::inet_ntop(AF_INET, &v4.sin_addr, text, sizeof text) ? text : "";
      port = ntohs(v4.sin_port);
    } else if (address.ss_family == AF_INET6) {
      const auto& v6 = reinterpret_cast<const sockaddr_in6&>(address);
      ip = ::inet_ntop(AF_INET6, &v6.sin6_addr, text, sizeof text) ? text : "";
      port = ntohs(v6.sin6_port);
    }
  }

  socket_t socket() const override { return connection_.fd; }

 private:
  ssize_t take(char* ptr, std::size_t size) {
    Connection& c = connection_;
    const std::size_t n = std::min(size, c.pending());
    std::memcpy(ptr, c.buffer.data() + c.start, n);
    c.start += n;
    return static_cast<ssize_t>(n);
  }

  Connection& connection_;
  milliseconds read_timeout_;
  milliseconds write_timeout_;
};

HttpServer::HttpServer() {
  new_task_queue = [this] { return start_serving(); };
}

HttpServer::~HttpServer() { finish_serving(); }

int HttpServer::bind(const std::string& host, int port) {
  if (port == 0) {
    port = bind_to_any_port(host);
  } else if (!bind_to_port(host, port)) {
    port = -1;
  }
  if (port <= 0) return -1;
  // 0.11.4 listens with a backlog of 5; listen() again on the bound socket sets ours.
  if (::listen(svr_sock_, backlog_) != 0) return -1;
  // Connections waiting for a head are capped at half the descriptors the process may open, so
  // that accepting never runs out of them while the rest (served connections, the database,
  // files) still have room.
  const rlim_t files = raise_open_file_limit();
  waiting_total_ = std::max<std::size_t>(1, std::min<std::size_t>(waiting_total_, static_cast<std::size_t>(files / 2)));
  return port;
}

httplib::TaskQueue* HttpServer::start_serving() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = false;
    reactor_exit_ = false;
  }
  epoll_ = ::epoll_create1(EPOLL_CLOEXEC);
  wake_ = ::eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
  if (epoll_ < 0 || wake_ < 0) {
    const int error = errno;
    if (epoll_ >= 0) ::close(epoll_);
    if (wake_ >= 0) ::close(wake_);
    epoll_ = wake_ = -1;
    throw std::system_error(error, std::generic_category(), "epoll");
  }
  epoll_event event{};
  event.events = EPOLLIN;
  event.data.fd = wake_;
  ::epoll_ctl(epoll_, EPOLL_CTL_ADD, wake_, &event);
  started_ = true;
  try {
    {
      std::lock_guard lock(pool_mutex_);
      pool_stopping_ = false;
      // Every thread up front: a limit on threads shows at start, not under load.
      for (std::size_t i = 0; i < thread_limit_; ++i) {
        std::thread thread([this] { work(); });
        threads_.emplace(thread.get_id(), std::move(thread));
        ++idle_;
      }
    }
    reactor_ = std::thread([this] { react(); });
  } catch (...) {
    // No thread for them all (a thread or address-space limit): the ones started end before
    // the members they wait on go, and listen reports the failure.
    finish_serving();
    throw;
  }
  return new AcceptQueue(*this);
}

void HttpServer::finish_serving() {
  if (!started_) return;
  started_ = false;
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
    reactor_exit_ = true;
    wake();
  }
  changed_.notify_all();
  if (reactor_.joinable()) reactor_.join();  // closes every connection it holds
  std::vector<std::thread> threads;
  {
    std::lock_guard lock(pool_mutex_);
    pool_stopping_ = true;
  }
  work_ready_.notify_all();
  // The HTTP threads end once their connections do (stop_and_disconnect shuts those down).
  for (;;) {
    {
      std::lock_guard lock(pool_mutex_);
      for (auto& [id, thread] : threads_) threads.push_back(std::move(thread));
      threads_.clear();
      for (auto& thread : finished_) threads.push_back(std::move(thread));
      finished_.clear();
    }
    if (threads.empty()) break;
    for (std::thread& thread : threads) {
      if (thread.joinable()) thread.join();
    }
    threads.clear();
  }
  {
    std::lock_guard lock(pool_mutex_);
    for (auto& connection : ready_) close_connection(*connection);
    ready_.clear();
    counted_ = idle_ = 0;
  }
  std::lock_guard lock(mutex_);
  ::close(epoll_);
  ::close(wake_);
  epoll_ = wake_ = -1;
}

void HttpServer::stop_and_disconnect(milliseconds grace) {
  stop();
  std::unique_lock lock(mutex_);
  stopping_ = true;
  wake();  // the reactor closes the connections it holds
  // Reading ends at once (a body, a long-poll's wait for the client): those threads return now.
  // An answer being written (a long-poll woken by the shutdown) may finish within `grace`.
  for (const auto& [sock, connection] : serving_) ::shutdown(sock, SHUT_RD);
  changed_.notify_all();
  changed_.wait_for(lock, grace, [this] { return serving_.empty(); });
  for (const auto& [sock, connection] : serving_) ::shutdown(sock, SHUT_RDWR);
}

void HttpServer::close_after_answer(httplib::Response& response) {
  if (!response.has_header("Connection")) response.set_header("Connection", "close");
  close_requested = true;
}

void HttpServer::head_received(std::uint64_t declared_body) {
  if (current_server == nullptr || current_connection == nullptr) return;
  HttpServer& server = *current_server;
  auto deadline = Clock::time_point::max();
  if (declared_body > 0 && server.header_deadline_.count() > 0 && server.body_rate_ > 0) {
    const double seconds = static_cast<double>(declared_body) / static_cast<double>(server.body_rate_);
    deadline = Clock::now() + server.header_deadline_ +
               std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(std::min(seconds, 1e7)));
  }
  std::lock_guard lock(server.mutex_);
  current_connection->deadline = deadline;
}

void HttpServer::body_received() {
  head_received(0);
  if (current_server != nullptr && current_connection != nullptr) current_server->release_upload(*current_connection);
}

std::string_view HttpServer::current_head() {
  if (current_connection == nullptr) return {};
  // begin_head() dropped what came before the head, and the reactor handed the head over whole, so
  // the buffer starts with it (a body read from the socket afterwards replaces it: that is no head error).
  return current_connection->buffer;
}

std::optional<HttpServer::UploadRefusal> HttpServer::admit_body() {
  if (current_server == nullptr || current_connection == nullptr) return std::nullopt;
  HttpServer& server = *current_server;
  Connection& connection = *current_connection;
  {
    std::lock_guard lock(server.mutex_);
    if (connection.upload) return std::nullopt;
    const auto mine = server.uploads_by_client_.find(connection.client);
    const std::size_t from_client = mine == server.uploads_by_client_.end() ? 0 : mine->second;
    if (from_client >= server.uploads_per_client_) return UploadRefusal{true, server.uploads_per_client_};
    if (server.uploads_ >= server.uploads_total_) return UploadRefusal{false, server.uploads_total_};
    ++server.uploads_by_client_[connection.client];
    ++server.uploads_;
    connection.upload = true;
  }
  server.leave_count();  // reading the body, this thread leaves its place to the next request
  return std::nullopt;
}

void HttpServer::release_upload(Connection& connection) {
  {
    std::lock_guard lock(mutex_);
    if (!connection.upload) return;
    connection.upload = false;
    --uploads_;
    if (const auto mine = uploads_by_client_.find(connection.client); mine != uploads_by_client_.end() && --mine->second == 0) {
      uploads_by_client_.erase(mine);
    }
  }
  rejoin_count();
}

// ---- The HTTP threads ----

/// Starts threads for the whole heads that may be served now (fewer than --http-threads
/// requests are counted) and that no idle thread will take: while threads read bodies, there
/// are more threads than --http-threads. Under pool_mutex_.
void HttpServer::spawn_locked() {
  for (std::thread& thread : finished_) thread.join();  // ended already: joined at once
  finished_.clear();
  if (pool_stopping_ || ready_.empty() || counted_ >= thread_limit_) return;
  const std::size_t startable = std::min(ready_.size(), thread_limit_ - counted_);
  while (idle_ < startable) {
    try {
      std::thread thread([this] { work(); });
      threads_.emplace(thread.get_id(), std::move(thread));
      ++idle_;
    } catch (const std::system_error&) {
      return;  // no thread now: the request waits for one to be free
    }
  }
}

void HttpServer::leave_count() {
  {
    std::lock_guard lock(pool_mutex_);
    --counted_;
    spawn_locked();
  }
  work_ready_.notify_one();
}

void HttpServer::rejoin_count() {
  std::lock_guard lock(pool_mutex_);
  ++counted_;  // may exceed --http-threads for a moment: no new request starts until it is back below
}

void HttpServer::work() {
  std::unique_lock lock(pool_mutex_);
  for (;;) {
    const auto can_start = [this] { return pool_stopping_ || (!ready_.empty() && counted_ < thread_limit_); };
    if (!work_ready_.wait_for(lock, extra_thread_idle, can_start)) {
      if (threads_.size() > thread_limit_) break;  // started while others read bodies; idle now
      continue;
    }
    if (ready_.empty()) break;  // stopping, and every whole head served
    std::unique_ptr<Connection> connection = std::move(ready_.front());
    ready_.pop_front();
    --idle_;
    ++counted_;
    lock.unlock();
    serve(std::move(connection));  // leaves counted_ as it found it
    lock.lock();
    --counted_;
    ++idle_;
  }
  --idle_;
  if (const auto self = threads_.find(std::this_thread::get_id()); self != threads_.end()) {
    finished_.push_back(std::move(self->second));
    threads_.erase(self);
  }
}

/// Answers the connection's requests while whole heads are buffered, then gives it back to the
/// reactor (kept alive), to linger (closed after a refusal) or closes it.
void HttpServer::serve(std::unique_ptr<Connection> connection) {
  Connection& c = *connection;
  {
    std::lock_guard lock(mutex_);
    if (stopping_) {
      close_connection(c);
      return;
    }
    c.deadline = Clock::time_point::max();
    serving_.emplace(c.fd, &c);
  }
  current_server = this;
  current_connection = &c;
  const milliseconds read_timeout = std::chrono::duration_cast<milliseconds>(
      std::chrono::seconds(read_timeout_sec_) + std::chrono::microseconds(read_timeout_usec_));
  const milliseconds write_timeout = std::chrono::duration_cast<milliseconds>(
      std::chrono::seconds(write_timeout_sec_) + std::chrono::microseconds(write_timeout_usec_));
  bool keep = false;
  bool linger = false;
  for (;;) {
    close_requested = false;
    bool client_closes = false;
    const bool last = c.served + 1 >= keep_alive_max_count_;
    Stream stream(c, read_timeout, write_timeout);
    bool answered = false;
    try {
      answered = process_request(stream, last, client_closes, nullptr);
    } catch (...) {
      // httplib hands a handler's exceptions to the exception hook; one from httplib itself (no
      // memory for a request's headers) ends this connection, never the process.
      close_requested = false;
    }
    ++c.served;
    release_upload(c);  // a body never read to its end (a refusal, a client gone)
    {
      std::lock_guard lock(mutex_);
      c.deadline = Clock::time_point::max();
      if (stopping_) break;
    }
    if (close_requested) {
      linger = answered;
      break;
    }
    if (!answered || client_closes || last || !c.complete) break;
    c.begin_head();
    const Connection::Head head = c.find_head();
    if (head == Connection::Head::partial) {
      keep = true;  // the reactor waits for the rest of it
      break;
    }
    c.complete = head == Connection::Head::whole;  // pipelined: answered at once
  }
  close_requested = false;
  current_server = nullptr;
  current_connection = nullptr;
  {
    std::lock_guard lock(mutex_);
    serving_.erase(c.fd);
  }
  changed_.notify_all();
  if (keep || linger) {
    hand_back(std::move(connection), linger);
  } else {
    close_connection(c);
  }
}

void HttpServer::hand_back(std::unique_ptr<Connection> connection, bool linger) {
  // A body's read-ahead may have grown the buffer: the reactor keeps only what is pending.
  if (connection->buffer.capacity() > read_chunk) connection->buffer = connection->buffer.substr(connection->start);
  else connection->buffer.erase(0, connection->start);
  connection->start = 0;
  std::lock_guard lock(mutex_);
  if (stopping_) {
    close_connection(*connection);
    return;
  }
  returned_.emplace_back(std::move(connection), linger);
  wake();
}

// ---- Accepting ----

/// Called by httplib's accept loop (through AcceptQueue, on the accepting thread) for each
/// accepted socket: the reactor takes it from here.
bool HttpServer::process_and_close_socket(socket_t sock) {
  try {
    auto connection = std::make_unique<Connection>();
    connection->fd = sock;
    describe_peer(sock, connection->shown, connection->client, connection->port);
    const int flags = ::fcntl(sock, F_GETFL, 0);
    ::fcntl(sock, F_SETFL, flags | O_NONBLOCK);
    std::lock_guard lock(mutex_);
    if (!stopping_ && started_) {
      incoming_.push_back(std::move(connection));
      wake();
      return true;
    }
  } catch (...) {
  }
  ::shutdown(sock, SHUT_RDWR);
  httplib::detail::close_socket(sock);
  return false;
}

// ---- The reactor ----

/// Wakes the reactor. Under mutex_ (finish_serving closes the descriptor under it).
void HttpServer::wake() {
  if (wake_ < 0) return;
  const std::uint64_t one = 1;
  [[maybe_unused]] const ssize_t written = ::write(wake_, &one, sizeof one);
}

void HttpServer::react() {
  std::array<epoll_event, 256> events{};
  for (;;) {
    const int count = ::epoll_wait(epoll_, events.data(), static_cast<int>(events.size()),
                                   static_cast<int>(sweep_interval.count()));
    for (int i = 0; i < count; ++i) {
      const int fd = events[static_cast<std::size_t>(i)].data.fd;
      if (fd == wake_) {
        std::uint64_t value = 0;
        [[maybe_unused]] const ssize_t read = ::read(wake_, &value, sizeof value);
        continue;
      }
      // Looked up each time: an earlier event of this batch may have closed or handed it over.
      if (const auto held = held_.find(fd); held != held_.end()) reactor_read(*held->second);
    }
    std::vector<std::unique_ptr<Connection>> incoming;
    std::vector<std::pair<std::unique_ptr<Connection>, bool>> returned;
    bool stopping = false;
    bool exit = false;
    {
      std::lock_guard lock(mutex_);
      incoming.swap(incoming_);
      returned.swap(returned_);
      stopping = stopping_;
      exit = reactor_exit_;
    }
    const auto now = Clock::now();
    if (stopping) {
      while (!held_.empty()) reactor_close(*held_.begin()->second);
      for (auto& connection : incoming) close_connection(*connection);
      for (auto& [connection, linger] : returned) close_connection(*connection);
      reactor_log(now, true);
      if (exit) return;
      continue;
    }
    for (auto& connection : incoming) {
      connection->until = now + std::chrono::seconds(std::max<time_t>(keep_alive_timeout_sec_, 1));
      reactor_take(std::move(connection));
    }
    for (auto& [connection, linger] : returned) {
      if (linger) {
        // The answer is out; what the client still sends (a refused body) is read and dropped,
        // never parsed, until it closes, 2 s pass or 64 MiB are dropped.
        ::shutdown(connection->fd, SHUT_WR);
        connection->lingering = true;
        connection->buffer.clear();
        connection->buffer.shrink_to_fit();
        connection->until = now + linger_time;
        reactor_take(std::move(connection));
      } else {
        reactor_wait(std::move(connection));
      }
    }
    if (now - swept_at_ >= sweep_interval) reactor_sweep(now);
  }
}

/// A kept-alive connection back from its HTTP thread: it waits for its next head (idle for at
/// most the keep-alive timeout; a head begun, its deadline).
void HttpServer::reactor_wait(std::unique_ptr<Connection> connection) {
  const auto now = Clock::now();
  connection->begin_head();
  connection->head_begun = connection->pending() > 0;
  connection->until = connection->head_begun && header_deadline_.count() > 0
                          ? now + header_deadline_
                          : now + std::chrono::seconds(std::max<time_t>(keep_alive_timeout_sec_, 1));
  // An HTTP thread gives back only a head begun, not whole; looked at here all the same, so a
  // head that is already all here never waits for bytes that will not come.
  if (const auto head = connection->find_head(); head != Connection::Head::partial) {
    reactor_dispatch(std::move(connection), head == Connection::Head::whole);
    return;
  }
  reactor_take(std::move(connection));
}

/// Holds the connection, newest of its client and of all, and closes the oldest ones beyond the limits.
void HttpServer::reactor_take(std::unique_ptr<Connection> connection) {
  Connection& c = *connection;
  epoll_event event{};
  event.events = EPOLLIN | EPOLLRDHUP;
  event.data.fd = c.fd;
  if (::epoll_ctl(epoll_, EPOLL_CTL_ADD, c.fd, &event) != 0) {
    close_connection(c);
    return;
  }
  auto& mine = held_by_client_[c.client];
  c.in_client = mine.insert(mine.end(), &c);
  c.in_order = held_order_.insert(held_order_.end(), &c);
  held_[c.fd] = std::move(connection);
  reactor_evict(c);
}

void HttpServer::reactor_evict(Connection& newest) {
  const std::string client = newest.client;
  for (;;) {
    const auto mine = held_by_client_.find(client);
    if (mine == held_by_client_.end() || mine->second.size() <= waiting_per_client_ || mine->second.front() == &newest) break;
    ++evicted_per_client_;
    evicted_last_client_ = client;
    reactor_close(*mine->second.front());
  }
  while (held_.size() > waiting_total_ && held_order_.front() != &newest) {
    ++evicted_total_;
    reactor_close(*held_order_.front());
  }
  reactor_log(Clock::now(), false);
}

/// Closes a held connection and forgets it (`connection` is gone after).
void HttpServer::reactor_close(Connection& connection) {
  const std::unique_ptr<Connection> released = reactor_release(connection);
  close_connection(*released);
}

std::unique_ptr<HttpServer::Connection> HttpServer::reactor_release(Connection& connection) {
  const socket_t fd = connection.fd;
  ::epoll_ctl(epoll_, EPOLL_CTL_DEL, fd, nullptr);
  held_order_.erase(connection.in_order);
  const auto mine = held_by_client_.find(connection.client);
  mine->second.erase(connection.in_client);
  if (mine->second.empty()) held_by_client_.erase(mine);
  const auto held = held_.find(fd);
  std::unique_ptr<Connection> released = std::move(held->second);
  held_.erase(held);
  return released;
}

/// Reads what a held connection has: a lingering one's bytes are dropped; a waiting one's are
/// buffered, and once its head is whole (or cannot be) it goes to the HTTP threads.
void HttpServer::reactor_read(Connection& c) {
  std::array<char, read_chunk> chunk;
  if (c.lingering) {
    const ssize_t n = ::recv(c.fd, chunk.data(), chunk.size(), MSG_DONTWAIT);
    if (n > 0) c.dropped += static_cast<std::size_t>(n);
    if (n == 0 || (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR) || c.dropped >= linger_bytes) {
      reactor_close(c);
    }
    return;
  }
  const std::size_t room = std::min(chunk.size(), head_limit + 1 - std::min(c.pending(), head_limit));
  const ssize_t n = ::recv(c.fd, chunk.data(), room, MSG_DONTWAIT);
  Connection::Head head = Connection::Head::partial;
  if (n > 0) {
    if (!c.head_begun) {
      c.head_begun = true;
      if (header_deadline_.count() > 0) c.until = Clock::now() + header_deadline_;
      else c.until = Clock::time_point::max();
    }
    try {
      c.buffer.append(chunk.data(), static_cast<std::size_t>(n));
    } catch (const std::bad_alloc&) {
      reactor_close(c);  // no memory for 64 KiB: this client waits, the process goes on
      return;
    }
    head = c.find_head();
    if (head == Connection::Head::partial) return;
  } else if (n == 0) {
    // The client closed. With part of a head sent, httplib answers what arrived (400), as it
    // did when it read the socket itself; with nothing, there is nothing to answer.
    if (c.pending() == 0) {
      reactor_close(c);
      return;
    }
    head = Connection::Head::unreadable;
  } else {
    if (errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR) reactor_close(c);
    return;
  }
  reactor_dispatch(reactor_release(c), head == Connection::Head::whole);
}

/// To the HTTP threads: a whole head (`complete`), or one httplib is to refuse as it stands.
void HttpServer::reactor_dispatch(std::unique_ptr<Connection> connection, bool complete) {
  connection->complete = complete;
  connection->head_begun = false;
  {
    std::lock_guard lock(pool_mutex_);
    ready_.push_back(std::move(connection));
    spawn_locked();
  }
  work_ready_.notify_one();
}

/// Closes the held connections whose time is up (idle, head late, lingering done) and shuts
/// down the served ones whose body is late (the thread reading it then sees its end).
void HttpServer::reactor_sweep(Clock::time_point now) {
  swept_at_ = now;
  for (auto next = held_order_.begin(); next != held_order_.end();) {
    Connection& c = **next;
    ++next;
    if (c.until <= now) reactor_close(c);
  }
  {
    std::lock_guard lock(mutex_);
    for (const auto& [sock, connection] : serving_) {
      if (connection->deadline <= now) ::shutdown(sock, SHUT_RDWR);
    }
  }
  reactor_log(now, false);
}

/// One line for the connections closed for a limit since the last one, at most every 10 s.
void HttpServer::reactor_log(Clock::time_point now, bool force) {
  if (evicted_per_client_ + evicted_total_ == 0) return;
  if (!force && logged_at_ != Clock::time_point{} && now - logged_at_ < log_interval) return;
  logged_at_ = now;
  if (log_) {
    std::string line = "manipid: closed connections waiting for a request head:";
    if (evicted_per_client_ > 0) {
      line += " " + std::to_string(evicted_per_client_) + " over --max-connections-per-client " +
              std::to_string(waiting_per_client_) + " (the last from " + evicted_last_client_ + ")";
    }
    if (evicted_total_ > 0) {
      line += std::string(evicted_per_client_ > 0 ? ";" : "") + " " + std::to_string(evicted_total_) +
              " over --max-connections " + std::to_string(waiting_total_);
    }
    log_(line);
  }
  evicted_per_client_ = evicted_total_ = 0;
}

}  // namespace manipid::api
