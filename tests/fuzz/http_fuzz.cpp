// http_fuzz.cpp — libFuzzer target for the HTTP surface of `manipid serve`: each input is the
// raw bytes a client sends on one connection. The real HttpServer (http_server.h) with the real
// route table (register_routes: pre-routing guards, error and exception hooks, every route)
// runs in this process on 127.0.0.1, port 0, over the in-memory FakeService of tests/api, set
// up as `manipid serve` sets its server up (api/src/http/http_endpoint.cpp), with a small
// --max-body and a bearer token. Per input: connect, send the bytes, shut the sending side, read
// until the server closes. Requests are read by cpp-httplib itself; this file only checks what
// comes back:
// - nothing, or answers that each start with an "HTTP/1.1 NNN " status line;
// - no 5xx but 503 (the fake service throws nothing: a 500 is a handler or hook that threw),
//   in the answers and in the server's log line for each request;
// - every error answer (4xx, 5xx) is application/problem+json whose body's "status" is the status.
// A failed check aborts (libFuzzer saves the input as a crash), as do ASan/UBSan findings; a
// server that never closes the connection shows as a libFuzzer timeout. With HTTP_FUZZ_SHOW set
// in the environment, every answer is printed (`HTTP_FUZZ_SHOW=1 build/fuzz/http_fuzz FILE`).
// The main build replays the seed corpus and the regressions through this file without libFuzzer
// (tests/fuzz/replay_main.cpp, ctest http_fuzz_replay).
//
// The fake service is made afresh for every input, with the same fixtures (a dataset with
// data, a queued job, a finished job with a cost history), so an input's answers never depend
// on the inputs before it.
#include "fake_service.h"  // tests/api

#include "manipid/api/routes.h"

#include "manipid/api/http_server.h"  // includes httplib.h: after the manipid headers

#include <nlohmann/json.hpp>

#include <netinet/in.h>
#include <poll.h>
#include <pthread.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>
#include <thread>
#include <utility>

namespace {

using namespace manipid;
using namespace manipid::api;

/// The token the /v1 routes ask for (http.dict and the seed corpus carry it).
constexpr const char* token = "fuzz-token";

[[noreturn]] void fail(const std::string& what, std::string_view answer) {
  std::fprintf(stderr, "http_fuzz: %s\n--- answer (%zu bytes, first 2000) ---\n%.*s\n", what.c_str(), answer.size(),
               static_cast<int>(std::min<std::size_t>(answer.size(), 2000)), answer.data());
  std::abort();
}

/// A fresh FakeService with the fixtures every input starts from.
std::shared_ptr<testing::FakeService> fixtures() {
  auto fake = std::make_shared<testing::FakeService>();
  Trajectory data;
  data.t = Eigen::VectorXd::LinSpaced(4, 0.0, 0.03);
  data.q = Eigen::MatrixXd::Constant(4, 2, 0.5);
  data.tau = Eigen::MatrixXd::Constant(4, 2, 1.5);
  DatasetInfo dataset;
  dataset.id = "ds_fixture";
  dataset.name = "fixture";
  dataset.created_at = "2026-01-01T00:00:00.000Z";
  dataset.joints = 2;
  dataset.samples = 4;
  dataset.dt = 0.01;
  dataset.has_torque = true;
  fake->add_dataset(dataset, data);

  JobInfo queued;
  queued.id = "job_queued";
  queued.kind = JobKind::identification;
  queued.state = JobState::queued;
  queued.created_at = "2026-01-01T00:00:00.000Z";
  queued.request = R"({"dataset_id":"ds_fixture"})";
  queued.dataset_id = "ds_fixture";
  fake->add_job(queued);

  JobInfo done = queued;
  done.id = "job_done";
  done.state = JobState::succeeded;
  done.started_at = done.finished_at = "2026-01-01T00:00:01.000Z";
  done.evaluations = 3;
  done.best_cost = 0.25;
  fake->add_job(done, {{0, 1.0, {50, 25, 0.4, 0.8}}, {1, 0.5, {49, 24, 0.4, 0.8}}, {2, 0.25, {48, 23, 0.4, 0.8}}});
  return fake;
}

/// The Service the routes see: every call goes to the current FakeService, replaced by reset().
/// One thing differs from the fake: a history page token that is not one the fake hands out is
/// refused as the real service refuses it (422 on page_token), where the fake's std::stoul
/// would throw std::invalid_argument (a 500 that only the fake can produce).
class FreshService : public Service {
 public:
  FreshService() : current_(fixtures()) {}
  void reset() {
    auto fresh = fixtures();
    std::lock_guard lock(mutex_);
    current_ = std::move(fresh);
  }

  DatasetCreated create_dataset(const Caller& caller, const DatasetUpload& upload,
                                const std::optional<IdempotencyKey>& key) override {
    return fake()->create_dataset(caller, upload, key);
  }
  std::optional<DatasetInfo> dataset(const Caller& caller, const std::string& id) override {
    return fake()->dataset(caller, id);
  }
  std::optional<Trajectory> dataset_data(const Caller& caller, const std::string& id) override {
    return fake()->dataset_data(caller, id);
  }
  Page<DatasetInfo> datasets(const Caller& caller, const PageRequest& page) override {
    return fake()->datasets(caller, page);
  }
  DeleteOutcome delete_dataset(const Caller& caller, const std::string& id) override {
    return fake()->delete_dataset(caller, id);
  }
  RobotCreated create_robot(const Caller& caller, const RobotUpload& upload, std::shared_ptr<const ParsedRobot> parsed,
                            const std::string& description, const std::optional<IdempotencyKey>& key) override {
    return fake()->create_robot(caller, upload, std::move(parsed), description, key);
  }
  std::optional<RobotInfo> robot(const Caller& caller, const std::string& id) override { return fake()->robot(caller, id); }
  std::optional<std::string> robot_urdf(const Caller& caller, const std::string& id) override {
    return fake()->robot_urdf(caller, id);
  }
  std::shared_ptr<const ParsedRobot> parsed_robot(const Caller& caller, const std::string& id) override {
    return fake()->parsed_robot(caller, id);
  }
  Page<RobotInfo> robots(const Caller& caller, const PageRequest& page) override { return fake()->robots(caller, page); }
  DeleteOutcome delete_robot(const Caller& caller, const std::string& id) override {
    return fake()->delete_robot(caller, id);
  }
  SubmitResult submit(const Caller& caller, const JobSubmission& submission,
                      const std::optional<IdempotencyKey>& key) override {
    return fake()->submit(caller, submission, key);
  }
  std::optional<JobInfo> job(const Caller& caller, const std::string& id) override { return fake()->job(caller, id); }
  std::optional<JobInfo> wait(const Caller& caller, const std::string& id, double seconds) override {
    return fake()->wait(caller, id, seconds);
  }
  Page<JobInfo> jobs(const Caller& caller, const JobFilter& filter, const PageRequest& page) override {
    return fake()->jobs(caller, filter, page);
  }
  std::optional<Page<HistoryEntry>> history(const Caller& caller, const std::string& id, const PageRequest& page) override {
    const std::string& token = page.page_token;
    if (token.size() > 9 || !std::all_of(token.begin(), token.end(), [](unsigned char c) { return std::isdigit(c) != 0; })) {
      throw ApiError(ProblemKind::invalid_field, "page_token is not a token this list returned", "page_token");
    }
    return fake()->history(caller, id, page);
  }
  std::optional<HistoryOverview> history_overview(const Caller& caller, const std::string& id, long max_points) override {
    return fake()->history_overview(caller, id, max_points);
  }
  std::optional<JobInfo> cancel(const Caller& caller, const std::string& id) override { return fake()->cancel(caller, id); }
  DeleteOutcome delete_job(const Caller& caller, const std::string& id) override {
    return fake()->delete_job(caller, id);
  }
  std::string metrics() override { return fake()->metrics(); }
  bool accepting() const override { return fake()->accepting(); }
  std::optional<std::string> degraded() const override { return fake()->degraded(); }

 private:
  std::shared_ptr<testing::FakeService> fake() const {
    std::lock_guard lock(mutex_);
    return current_;
  }
  mutable std::mutex mutex_;
  std::shared_ptr<testing::FakeService> current_;
};

/// The server's log line for each request ("ADDRESS METHOD TARGET STATUS N bytes T ms", written
/// whether or not the answer reached the client) and for each exception a handler let out
/// ("internal error on PATH: WHAT"): no 5xx but 503, no internal error.
void check_log_line(const std::string& line) {
  if (line.rfind("internal error on ", 0) == 0) fail("the server logged: " + line, {});
  const std::size_t bytes = line.rfind(" bytes ");
  const std::size_t size_at = bytes == std::string::npos || bytes == 0 ? std::string::npos : line.rfind(' ', bytes - 1);
  const std::size_t status_at = size_at == std::string::npos || size_at == 0 ? std::string::npos : line.rfind(' ', size_at - 1);
  if (status_at == std::string::npos || size_at - status_at != 4) fail("a log line without a status: " + line, {});
  const int status = std::atoi(line.c_str() + status_at + 1);
  if (status >= 500 && status != 503) fail("the server logged status " + std::to_string(status) + ": " + line, {});
}

/// The server, started once: HttpServer configured as manipid serve configures it (api/src/http/http_endpoint.cpp), but small.
struct Server {
  FreshService service;
  HttpServer http;
  std::thread thread;
  int port = -1;

  Server() {
    http.set_http_threads(2);
    http.set_tcp_nodelay(true);
    http.set_keep_alive_max_count(1000);
    http.set_keep_alive_timeout(2);
    http.set_read_timeout(2);
    http.set_write_timeout(2);
    http.set_header_deadline(std::chrono::seconds(2));
    RouteOptions options;
    options.max_body = 64 * 1024;
    options.token = token;
    options.max_wait_seconds = 0.01;
    options.max_waiters = 1;
    options.log = check_log_line;
    register_routes(http, service, options);
    port = http.bind("127.0.0.1", 0);
    if (port <= 0) fail("cannot bind 127.0.0.1:0", {});
    // libFuzzer's -timeout is a SIGALRM every few seconds, with a handler and no SA_RESTART:
    // one that lands on the listening thread ends its accept() with EINTR, and 0.11.4's
    // listen loop takes any accept error but EMFILE for the end (it closes the socket; every
    // later input then failed with "cannot connect", in CI after ~6,100 inputs). The listening
    // thread and the HTTP threads it starts block every signal, so the alarm goes to the
    // fuzzer's thread, as a signal does in `manipid serve`, which installs no handler.
    thread = std::thread([this] {
      sigset_t all;
      sigfillset(&all);
      pthread_sigmask(SIG_BLOCK, &all, nullptr);
      http.listen_after_bind();
    });
    while (!http.is_running()) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
};

/// What the server sent on one connection until it closed it.
struct Answers {
  std::string bytes;
  bool reset = false;  ///< the connection ended in a reset: the last answer may be cut short
};

/// Sends `request` on a new connection, half-closes it and returns everything the server sent
/// until it closed (a reset ends the answer like a close: a refusal may close before reading all).
Answers round_trip(int port, std::string_view request) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  if (fd < 0) fail("socket() failed", {});
  timeval limit{30, 0};  // past libFuzzer's -timeout: a stuck server is reported as a timeout
  ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &limit, sizeof limit);
  ::setsockopt(fd, SOL_SOCKET, SO_SNDTIMEO, &limit, sizeof limit);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(static_cast<std::uint16_t>(port));
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (::connect(fd, reinterpret_cast<sockaddr*>(&address), sizeof address) != 0) {
    int error = errno;
    if (error == EINTR) {  // the alarm: the connect goes on; its outcome is the socket's error
      pollfd descriptor{fd, POLLOUT, 0};
      while (::poll(&descriptor, 1, 30000) < 0 && errno == EINTR) descriptor.revents = 0;
      socklen_t length = sizeof error;
      if (descriptor.revents == 0) error = ETIMEDOUT;
      else ::getsockopt(fd, SOL_SOCKET, SO_ERROR, &error, &length);
    }
    if (error != 0) fail(std::string("cannot connect to the server: ") + std::strerror(error), {});
  }
  for (std::size_t sent = 0; sent < request.size();) {
    const ssize_t n = ::send(fd, request.data() + sent, request.size() - sent, MSG_NOSIGNAL);
    if (n < 0 && errno == EINTR) continue;  // libFuzzer's timer signal: SO_SNDTIMEO calls are not restarted
    if (n <= 0) break;  // the server closed early (a refusal): its answer is still read below
    sent += static_cast<std::size_t>(n);
  }
  // cpp-httplib 0.11.4 writes no answer to a client it sees half-closed (its is_writable peeks
  // the socket and takes the end of stream for a dead peer), so the sending side is shut only
  // once the server has been quiet for 1 ms: every answer it was about to write is out first
  // (measured: 343 execs/s; 212 with 2 ms). A handler slower than that loses its answer to the
  // half-close; its status is still checked in the server's log line (check_log_line).
  Answers answer;
  char buffer[16384];
  // HTTP_FUZZ_QUIET_MS sets another wait: the replay of saved inputs (ctest http_fuzz_replay, a
  // slower -Og build) waits 200 ms, so that every answer is read and checked.
  static const int quiet_ms = std::getenv("HTTP_FUZZ_QUIET_MS") ? std::max(1, std::atoi(std::getenv("HTTP_FUZZ_QUIET_MS"))) : 1;
  for (pollfd descriptor{fd, POLLIN, 0};; descriptor.revents = 0) {
    const int ready = ::poll(&descriptor, 1, quiet_ms);
    if (ready < 0 && errno == EINTR) continue;
    if (ready == 0) break;
    const ssize_t n = ::recv(fd, buffer, sizeof buffer, 0);
    if (n > 0) {
      answer.bytes.append(buffer, static_cast<std::size_t>(n));
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && errno == ECONNRESET) answer.reset = true;
    ::close(fd);  // the server closed (a refusal closes its connection)
    return answer;
  }
  ::shutdown(fd, SHUT_WR);
  for (;;) {
    const ssize_t n = ::recv(fd, buffer, sizeof buffer, 0);
    if (n > 0) {
      answer.bytes.append(buffer, static_cast<std::size_t>(n));
    } else if (n == 0) {
      break;
    } else if (errno == ECONNRESET) {
      answer.reset = true;
      break;
    } else if (errno != EINTR) {
      const int error = errno;
      ::close(fd);
      fail(error == EAGAIN ? "no end of the answer within 30 s" : std::string("recv: ") + std::strerror(error), answer.bytes);
    }
  }
  ::close(fd);
  return answer;
}

std::string lower(std::string_view text) {
  std::string out(text);
  std::transform(out.begin(), out.end(), out.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return out;
}

/// The value of header `name` (lower case) in `head` (lower-cased status line and headers), or empty.
std::string header(const std::string& head, const std::string& name) {
  const std::size_t at = head.find("\r\n" + name + ":");
  if (at == std::string::npos) return {};
  std::size_t start = at + 3 + name.size();
  while (start < head.size() && head[start] == ' ') ++start;
  return head.substr(start, head.find("\r\n", start) - start);
}

/// Checks each answer in `answers` (several when requests were pipelined). Answers are split
/// by their Content-Length; an answer to HEAD has none of the body it announces, so when the
/// bytes after a body do not start a status line, the next answer is looked for right after
/// the head instead; when neither place starts one, the rest is left unchecked. After a reset
/// the last answer may be cut short anywhere: what is there is checked.
void check_answers(const Answers& received) {
  const std::string& answers = received.bytes;
  std::size_t at = 0;
  while (at < answers.size()) {
    const std::string_view rest(answers.data() + at, answers.size() - at);
    if (received.reset && rest.size() < 13 && std::string_view("HTTP/1.1 ").substr(0, rest.size()) == rest.substr(0, 9)) {
      return;  // cut short by the reset
    }
    if (rest.size() < 13 || rest.substr(0, 9) != "HTTP/1.1 " || !std::isdigit(static_cast<unsigned char>(rest[9])) ||
        !std::isdigit(static_cast<unsigned char>(rest[10])) || !std::isdigit(static_cast<unsigned char>(rest[11])) ||
        rest[12] != ' ') {
      if (at == 0) fail("the answer does not start with an HTTP/1.1 status line", answers);
      return;  // after a HEAD answer with a body length: not ours to split further
    }
    const int status = std::stoi(std::string(rest.substr(9, 3)));
    const std::size_t head_end = rest.find("\r\n\r\n");
    if (head_end == std::string_view::npos) {
      if (received.reset) return;
      fail("an answer's head has no end", answers);
    }
    const std::string head = lower(rest.substr(0, head_end + 2));
    const std::size_t body_start = head_end + 4;
    if (status >= 500 && status != 503) fail("status " + std::to_string(status), answers);
    const std::string length_text = header(head, "content-length");
    std::size_t length = 0;
    if (!length_text.empty()) length = std::stoul(length_text);
    if (status >= 100 && status < 200) {  // 100 Continue: no body, the final answer follows
      at += body_start;
      continue;
    }
    if (status >= 400) {
      if (header(head, "content-type") != "application/problem+json") fail("an error answer is not problem+json", answers);
      if (length_text.empty()) fail("an error answer without Content-Length", answers);
    }
    const bool body_here = body_start + length <= rest.size();
    const std::size_t next = at + body_start + length;
    const bool next_starts = next >= answers.size() || answers.compare(next, 5, "HTTP/") == 0;
    if (body_here && next_starts) {
      if (status >= 400 && length > 0) {
        const auto problem = nlohmann::json::parse(rest.substr(body_start, length), nullptr, false);
        if (!problem.is_object() || !problem.contains("status") || problem["status"] != status) {
          fail("an error answer's body is not a problem with its status", answers);
        }
      }
      at = next;
    } else {
      at += body_start;  // HEAD: the head announces a body that is not sent (or a reset cut it)
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static Server* server = new Server();  // never stopped: it serves until the process exits
  static const bool show = std::getenv("HTTP_FUZZ_SHOW") != nullptr;  // print every answer
  server->service.reset();
  const Answers answers = round_trip(server->port, std::string_view(reinterpret_cast<const char*>(data), size));
  if (show) std::fprintf(stderr, "%s%s\n", answers.bytes.c_str(), answers.reset ? "\n(reset)" : "");
  check_answers(answers);
  return 0;
}
