// http_server.h — the HTTP server `manipid serve` runs: Debian's cpp-httplib 0.11.4 Server with
// its connection handling taken back, so that a connection holds an HTTP thread only while a
// request of it is being answered, a refusal can close its connection, the listen backlog is
// ours to set, and stopping shuts every open connection down instead of waiting on slow clients.
//
// What 0.11.4 does on its own, and why each part is here:
// - A thread per connection, from the accept on: a client that connects and sends nothing, or
//   trickles its head a byte at a time, holds one of the --http-threads threads (1,000 silent
//   connections held /healthz back ~60 s). Here one reactor thread (epoll) holds every
//   connection while it waits for a request head — new ones, kept-alive ones between requests,
//   and refused ones whose unread bytes are being dropped — and reads heads without blocking;
//   a connection goes to an HTTP thread only once its whole head is buffered (or once it cannot
//   be: a head past 64 KiB, a client gone, which httplib then refuses from what arrived).
//   Silent connections, trickled heads and idle keep-alives hold no thread at all; the
//   keep-alive timeout closes a connection that sends nothing, the header deadline a late head.
// - No bound on the connections one client keeps open: here at most set_connection_limits'
//   `per_client` wait for a head per remote address (and `total` in all); a new one beyond
//   closes that address's oldest waiting one, so a client's fresh request still gets in.
// - A body is read by the thread that serves its request, so a body trickled a byte a second
//   holds a thread for its whole deadline: 33 such bodies held /healthz back 48 s. Here a thread
//   reading a body no longer counts toward --http-threads (another thread serves the next
//   request meanwhile), and the bodies received at once are capped (set_upload_limits, per
//   address and in all): beyond the cap the pre-routing hook refuses before reading (503).
// - After an answer, its keep-alive loop reads the next request on the same connection even
//   when the answer said "Connection: close" (only the *request's* header ends the loop). A
//   refusal before the body is read (401, 411, 413, 415, 400) would leave that body to be parsed
//   as the next request: request smuggling. close_after_answer() ends the connection instead,
//   its unread bytes dropped (never parsed) by the reactor for a while first, so that the client
//   reads its answer rather than a reset.
// - Each request is read through a new stream whose read-ahead is dropped afterwards: pipelined
//   requests were lost. Here the bytes read past a request stay buffered for the next one.
// - listen() is called with a backlog of 5: 64 simultaneous connects got resets.
// - stop() closes the listening socket, then joins every HTTP thread, each blocked until its
//   client sends or its read timeout fires (30 s per read, so never with a trickling client).
// - Per-read timeouts only: a client trickling one byte a second is never late. A head must
//   arrive within set_header_deadline of its first byte (the reactor closes it), and a body at
//   set_minimum_body_rate at least (its connection is shut down when late).
// Requests are still parsed and answered by httplib's own process_request, over a stream
// (http_server.cpp) that serves the buffered head first; the reactor only finds where a head
// ends, as httplib's reader does (a line that is exactly CRLF after the request line).
#pragma once

#include <httplib.h>

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <list>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <thread>
#include <unordered_map>
#include <vector>

namespace manipid::api {

class HttpServer : public httplib::Server {
 public:
  HttpServer();
  ~HttpServer() override;
  HttpServer(const HttpServer&) = delete;
  HttpServer& operator=(const HttpServer&) = delete;

  /// `threads` requests served at once (not counting the threads reading a body, see
  /// set_upload_limits). Connections waiting for a head hold none.
  void set_http_threads(std::size_t threads) { thread_limit_ = std::max<std::size_t>(threads, 1); }

  /// At most `per_client` connections from one remote address, and `total` in all, wait for a
  /// request head (new, or kept alive between requests); a new one beyond either closes the
  /// oldest waiting one (of that address, or of all). `total` is lowered to half the open-file
  /// limit when that is smaller.
  void set_connection_limits(std::size_t per_client, std::size_t total) {
    waiting_per_client_ = std::max<std::size_t>(per_client, 1);
    waiting_total_ = std::max<std::size_t>(total, 1);
  }

  /// At most `per_client` request bodies from one remote address, and `total` in all, are being
  /// received at once (admit_body); the threads reading them are outside set_http_threads.
  void set_upload_limits(std::size_t per_client, std::size_t total) {
    uploads_per_client_ = std::max<std::size_t>(per_client, 1);
    uploads_total_ = std::max<std::size_t>(total, 1);
  }

  /// Where a line goes when connections are closed for a limit (at most one line per 10 s).
  void set_log(std::function<void(const std::string&)> log) { log_ = std::move(log); }

  /// The listen backlog applied when binding (0.11.4 itself listens with 5).
  void set_listen_backlog(int backlog) { backlog_ = backlog; }
  /// The whole request head (line and headers) must arrive within this time of its first byte,
  /// or the connection is closed (0 = no deadline, as in 0.11.4).
  void set_header_deadline(std::chrono::milliseconds deadline) { header_deadline_ = deadline; }

  /// A body must arrive at this rate at least, after its head: its deadline is the header
  /// deadline plus declared length / rate (with a header deadline set; 0.11.4 has only a
  /// per-read timeout, which a byte every few seconds never trips).
  void set_minimum_body_rate(std::uint64_t bytes_per_second) { body_rate_ = bytes_per_second; }

  /// Binds to `port` (0: any free port) and listens with the backlog; returns the port, or -1.
  /// Raises the process's open-file limit to its hard limit: each connection is a descriptor.
  int bind(const std::string& host, int port);

  /// stop(), then shut down every open connection so the HTTP threads return: connections
  /// waiting for a head close at once, reading ends at once (a body, a long-poll); answers
  /// being written get `grace` to finish, then their connections are cut too.
  void stop_and_disconnect(std::chrono::milliseconds grace = std::chrono::seconds(2));

  /// Called by a hook or handler on the request's own thread: the answer carries
  /// "Connection: close" and, once it is written, the connection is closed (its unread bytes
  /// read and dropped for at most 2 s and 64 MiB, so the client gets the answer, not a reset).
  static void close_after_answer(httplib::Response& response);

  /// Called by the hooks: the request's head has arrived, with a body of `declared_body` bytes
  /// still to read (0: none), which gets its own deadline.
  static void head_received(std::uint64_t declared_body = 0);
  /// Called by the handlers (and the error hook): the body is read, no deadline while answering;
  /// the thread counts toward set_http_threads again.
  static void body_received();
  /// Called by the error hook: the bytes of the request head this thread is serving (and maybe what
  /// followed it), to name what httplib could not read in it; empty off an HTTP thread.
  static std::string_view current_head();

  /// Why a body may not be received now: the limit reached, per client address or in all.
  struct UploadRefusal {
    bool per_client = false;
    std::size_t limit = 0;
  };
  /// Called by the pre-routing hooks just before a body is read: takes one of the upload places
  /// (set_upload_limits) for this request, or says which limit is full. While the body is read,
  /// the thread does not count toward set_http_threads. Taking it again is a no-op.
  static std::optional<UploadRefusal> admit_body();

  struct Connection;  ///< one client connection and its buffered bytes (http_server.cpp)

 private:
  class AcceptQueue;
  class Stream;

  bool process_and_close_socket(socket_t sock) override;
  httplib::TaskQueue* start_serving();
  void finish_serving();

  // The reactor thread (owns every connection waiting for a head or lingering).
  void react();
  void reactor_read(Connection& connection);
  void reactor_dispatch(std::unique_ptr<Connection> connection, bool complete);
  void reactor_take(std::unique_ptr<Connection> connection);
  void reactor_wait(std::unique_ptr<Connection> connection);
  void reactor_close(Connection& connection);
  /// Takes a held connection out of the reactor (epoll, the waiting order, its client's list) and hands it back.
  std::unique_ptr<Connection> reactor_release(Connection& connection);
  void reactor_sweep(std::chrono::steady_clock::time_point now);
  void reactor_evict(Connection& newest);
  void reactor_log(std::chrono::steady_clock::time_point now, bool force);
  void wake();

  // The HTTP threads.
  void work();
  void spawn_locked();
  void serve(std::unique_ptr<Connection> connection);
  void hand_back(std::unique_ptr<Connection> connection, bool linger);
  void close_served(std::unique_ptr<Connection> connection);
  void release_upload(Connection& connection);
  void leave_count();
  void rejoin_count();

  int backlog_ = 128;
  std::size_t thread_limit_ = 32;
  std::size_t waiting_per_client_ = 64;
  std::size_t waiting_total_ = 4096;
  std::size_t uploads_per_client_ = 16;
  std::size_t uploads_total_ = 256;
  std::chrono::milliseconds header_deadline_{0};
  std::uint64_t body_rate_ = 256 * 1024;
  std::function<void(const std::string&)> log_;

  // Shared state, under mutex_.
  std::mutex mutex_;
  std::condition_variable changed_;
  bool stopping_ = false;
  bool reactor_exit_ = false;
  std::vector<std::unique_ptr<Connection>> incoming_;  ///< accepted, for the reactor
  std::vector<std::pair<std::unique_ptr<Connection>, bool>> returned_;  ///< served; true: to linger
  /// The connections being served, by socket → their deadline (max() when none), read by the
  /// reactor's sweep and by stop_and_disconnect.
  std::map<socket_t, Connection*> serving_;
  std::map<std::string, std::size_t> uploads_by_client_;
  std::size_t uploads_ = 0;

  // The reactor's own (its thread only, but for the descriptors made before it starts).
  int epoll_ = -1;
  int wake_ = -1;
  std::thread reactor_;
  std::unordered_map<socket_t, std::unique_ptr<Connection>> held_;
  std::list<Connection*> held_order_;  ///< oldest first
  std::unordered_map<std::string, std::list<Connection*>> held_by_client_;
  std::size_t evicted_per_client_ = 0;
  std::size_t evicted_total_ = 0;
  std::string evicted_last_client_;
  std::chrono::steady_clock::time_point logged_at_{};
  std::chrono::steady_clock::time_point swept_at_{};

  // The HTTP threads, under pool_mutex_.
  std::mutex pool_mutex_;
  std::condition_variable work_ready_;
  std::deque<std::unique_ptr<Connection>> ready_;  ///< whole heads waiting for a thread
  std::map<std::thread::id, std::thread> threads_;
  std::vector<std::thread> finished_;  ///< threads that ended, to join
  std::size_t counted_ = 0;  ///< threads serving a request, not reading a body
  std::size_t idle_ = 0;     ///< threads waiting for a request
  bool pool_stopping_ = false;
  bool started_ = false;
};

}  // namespace manipid::api
