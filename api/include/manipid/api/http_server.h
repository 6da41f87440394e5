// http_server.h — the HTTP server `manipid serve` runs: Debian's cpp-httplib 0.11.4 Server with
// the connection loop taken back, so a refusal can close its connection, the listen backlog is
// ours to set, and stopping shuts every open connection down instead of waiting on slow clients.
//
// What 0.11.4 does on its own, and why each part is here:
// - After an answer, its keep-alive loop reads the next request on the same connection even
//   when the answer said "Connection: close" (only the *request's* header ends the loop). A
//   refusal before the body is read (401, 411, 413, 415, 400) would leave that body to be parsed
//   as the next request: request smuggling. close_after_answer() ends the connection instead.
// - listen() is called with a backlog of 5: 64 simultaneous connects got resets.
// - An idle keep-alive connection holds its thread until its timeout, while accepted
//   connections wait for a thread: set_http_threads drops idle ones when one is waiting.
// - stop() closes the listening socket, then joins every HTTP thread, each blocked until its
//   client sends or its read timeout fires (30 s per read, so never with a trickling client).
// - Per-read timeouts only: a client trickling one header byte a second holds a thread for ever.
//   A header deadline (set_header_deadline), and for a body a deadline from a minimum rate
//   (set_minimum_body_rate), shut the connection down when the request is late.
// Nothing here reads or parses HTTP: requests are still read and answered by httplib's own
// process_request; this class only decides when a connection's socket is shut down.
#pragma once

#include <httplib.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <map>
#include <mutex>
#include <string>
#include <thread>

namespace manipid::api {

class HttpServer : public httplib::Server {
 public:
  HttpServer();
  ~HttpServer() override;
  HttpServer(const HttpServer&) = delete;
  HttpServer& operator=(const HttpServer&) = delete;

  /// `threads` connections served at once (the task queue httplib runs connections on). A
  /// connection waiting for a thread makes idle keep-alive connections close at once instead
  /// of holding their threads until their keep-alive timeout.
  void set_http_threads(std::size_t threads);

  /// The listen backlog applied when binding (0.11.4 itself listens with 5).
  void set_listen_backlog(int backlog) { backlog_ = backlog; }
  /// The whole request head (line and headers) must arrive within this time of its first byte,
  /// or the connection is shut down (0 = no deadline, as in 0.11.4).
  void set_header_deadline(std::chrono::milliseconds deadline) { header_deadline_ = deadline; }

  /// Binds to `port` (0: any free port) and listens with the backlog; returns the port, or -1.
  int bind(const std::string& host, int port);

  /// stop(), then shut down every open connection so the HTTP threads return: reading ends
  /// at once (trickling heads, idle keep-alives); answers being written get `grace` to finish,
  /// then their connections are cut too.
  void stop_and_disconnect(std::chrono::milliseconds grace = std::chrono::seconds(2));

  /// Called by a hook or handler on the request's own thread: the answer carries
  /// "Connection: close" and, once it is written, the connection is closed (its unread bytes
  /// read and dropped for at most 2 s and 64 MiB, so the client gets the answer, not a reset).
  static void close_after_answer(httplib::Response& response);

  /// A body must arrive at this rate at least, after its head: its deadline is the header
  /// deadline plus declared length / rate (with a header deadline set; 0.11.4 has only a
  /// per-read timeout, which a byte every few seconds never trips).
  void set_minimum_body_rate(std::uint64_t bytes_per_second) { body_rate_ = bytes_per_second; }

  /// Called by the hooks: the request's head has arrived (its header deadline is met), with a
  /// body of `declared_body` bytes still to read (0: none), which gets its own deadline.
  static void head_received(std::uint64_t declared_body = 0);
  /// Called by the handlers (and the error hook): the body is read, no deadline while answering.
  static void body_received();

 private:
  bool process_and_close_socket(socket_t sock) override;
  bool wait_next_request(socket_t sock, std::chrono::milliseconds idle);
  void watch_deadlines();

  int backlog_ = 128;
  std::atomic<std::size_t> queued_{0};  ///< accepted connections waiting for a thread
  std::chrono::milliseconds header_deadline_{0};
  std::uint64_t body_rate_ = 256 * 1024;
  std::mutex mutex_;
  std::condition_variable changed_;
  bool stopping_ = false;
  /// Every open connection's socket → the time its request head must have arrived by (max() when
  /// none is being read).
  std::map<socket_t, std::chrono::steady_clock::time_point> connections_;
  std::thread watchdog_;
};

}  // namespace manipid::api
