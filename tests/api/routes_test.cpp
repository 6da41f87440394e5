// routes_test.cpp — the HTTP routes (register_routes) against an in-memory Service
// (fake_service.h) behind a real cpp-httplib server on port 0: each route's answer, every
// problem+json the routes and the cpp-httplib 0.11.4 guards produce, and what reached the
// service (nothing, for a refused request). No SQLite, no workers, no timing asserts.
#include "bag_writer.h"
#include "fake_service.h"

#include "manipid/api/dashboard.h"
#include "manipid/api/job_kinds.h"
#include "manipid/api/robot_cache.h"
#include "manipid/api/robot_result.h"
#include "manipid/api/robot_requests.h"
#include "manipid/api/routes.h"
#include "manipid/core/robot/parameters.h"
#include "manipid/core/robot/payload.h"
#include "manipid/core/robot/rnea.h"

#include "manipid/api/http_server.h"  // includes httplib.h: after the manipid headers (it breaks Eigen if first)

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <mutex>
#include <numbers>
#include <string>
#include <thread>
#include <vector>

namespace manipid::api {
namespace {

using testing::FakeService;
using testing::Script;
using Json = nlohmann::json;
using namespace std::string_literals;

// ---- Helpers -----------------------------------------------------------------------------

std::string lower(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return text;
}

/// An answer read off a raw socket (for what httplib::Client will not send: a POST without
/// Content-Length, a chunked body, a made-up method).
struct RawAnswer {
  int status = 0;
  std::string head;  ///< status line and headers, lower case
  std::string body;
  bool has_header(const std::string& name, const std::string& value) const {
    return head.find("\r\n" + lower(name) + ": " + lower(value) + "\r\n") != std::string::npos;
  }
};

/// A client connection on a raw socket: each exchange sends a request as is and reads one
/// answer, its head then Content-Length bytes of body (not until the server closes, so
/// keep-alive can be tested). Exchanges on one connection are served in order by one server thread.
class RawConnection {
 public:
  explicit RawConnection(int port) : fd_(::socket(AF_INET, SOCK_STREAM, 0)) {
    EXPECT_GE(fd_, 0);
    timeval limit{30, 0};  // a net against a hang, not a timing assert
    ::setsockopt(fd_, SOL_SOCKET, SO_RCVTIMEO, &limit, sizeof limit);
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_port = htons(static_cast<uint16_t>(port));
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    connected_ = ::connect(fd_, reinterpret_cast<sockaddr*>(&address), sizeof address) == 0;
    EXPECT_TRUE(connected_) << "cannot connect to port " << port;
  }
  ~RawConnection() { ::close(fd_); }
  RawConnection(const RawConnection&) = delete;
  RawConnection& operator=(const RawConnection&) = delete;

  RawAnswer exchange(const std::string& request) {
    RawAnswer answer;
    if (!connected_) return answer;
    for (std::size_t sent = 0; sent < request.size();) {
      const ssize_t n = ::send(fd_, request.data() + sent, request.size() - sent, MSG_NOSIGNAL);
      if (n <= 0) break;
      sent += static_cast<std::size_t>(n);
    }
    std::size_t end = std::string::npos;
    std::size_t length = 0;
    char buffer[4096];
    for (;;) {
      if (end == std::string::npos && (end = pending_.find("\r\n\r\n")) != std::string::npos) {
        answer.head = lower(pending_.substr(0, end + 2));
        const auto field = answer.head.find("\r\ncontent-length: ");
        if (field != std::string::npos) length = std::stoul(answer.head.substr(field + 18));
      }
      if (end != std::string::npos && pending_.size() >= end + 4 + length) break;
      const ssize_t n = ::recv(fd_, buffer, sizeof buffer, 0);
      if (n <= 0) break;
      pending_.append(buffer, static_cast<std::size_t>(n));
    }
    if (end == std::string::npos || pending_.size() < end + 4 + length) {
      ADD_FAILURE() << "no complete answer: '" << pending_ << "'";
      return answer;
    }
    answer.body = pending_.substr(end + 4, length);
    pending_.erase(0, end + 4 + length);
    if (answer.head.rfind("http/1.1 ", 0) == 0) answer.status = std::stoi(answer.head.substr(9, 3));
    return answer;
  }

  /// Reads until the server closes the connection: true, with nothing more received.
  bool closed_by_server() {
    char buffer[4096];
    for (;;) {
      const ssize_t n = ::recv(fd_, buffer, sizeof buffer, 0);
      if (n == 0 || (n < 0 && errno == ECONNRESET)) return pending_.empty();
      if (n < 0) return false;  // the 30 s net: still open
      pending_.append(buffer, static_cast<std::size_t>(n));
    }
  }

 private:
  int fd_;
  bool connected_ = false;
  std::string pending_;  ///< received, not yet returned
};

/// Checks a problem+json answer: status in the line and the body, code, field (empty: none),
/// type, title and detail present. Returns the body for further checks.
Json expect_problem(int status, const std::string& content_type, const std::string& body, int expected_status,
                    const std::string& code, const std::string& field) {
  EXPECT_EQ(status, expected_status) << body;
  EXPECT_EQ(content_type, "application/problem+json") << body;
  const Json problem = Json::parse(body, nullptr, false);
  if (problem.is_discarded() || !problem.is_object()) {
    ADD_FAILURE() << "not a JSON object: " << body;
    return Json::object();
  }
  EXPECT_EQ(problem.value("status", 0), expected_status) << body;
  EXPECT_EQ(problem.value("code", ""), code) << body;
  EXPECT_EQ(problem.value("field", ""), field) << body;
  EXPECT_EQ(problem.value("type", "").rfind("/problems/", 0), 0u) << body;
  EXPECT_FALSE(problem.value("title", "").empty()) << body;
  EXPECT_FALSE(problem.value("detail", "").empty()) << body;
  return problem;
}

Json expect_problem(const httplib::Result& result, int expected_status, const std::string& code, const std::string& field) {
  if (!result) {
    ADD_FAILURE() << "no answer: " << httplib::to_string(result.error());
    return Json::object();
  }
  return expect_problem(result->status, result->get_header_value("Content-Type"), result->body, expected_status, code, field);
}

Json expect_problem(const RawAnswer& answer, int expected_status, const std::string& code, const std::string& field) {
  const auto start = answer.head.find("\r\ncontent-type: ");
  const std::string type =
      start == std::string::npos ? "" : answer.head.substr(start + 16, answer.head.find("\r\n", start + 2) - start - 16);
  return expect_problem(answer.status, type, answer.body, expected_status, code, field);
}

Json json_of(const httplib::Result& result) {
  if (!result) return Json();
  return Json::parse(result->body, nullptr, false);
}

/// t = 0, dt, ...; q smooth per joint; tau and ref when asked.
Trajectory trajectory(int joints, int samples, double dt, bool torque = true, bool reference = false) {
  Trajectory data;
  data.t.resize(samples);
  data.q.resize(samples, joints);
  if (torque) data.tau.resize(samples, joints);
  if (reference) data.ref.resize(samples, joints);
  for (int i = 0; i < samples; ++i) {
    data.t[i] = i * dt;
    for (int j = 0; j < joints; ++j) {
      data.q(i, j) = 0.1 * (j + 1) * std::sin(2.0 * data.t[i] + j);
      if (torque) data.tau(i, j) = 10.0 * j + std::cos(data.t[i]);
      if (reference) data.ref(i, j) = 0.1 * (j + 1);
    }
  }
  return data;
}

DatasetInfo dataset_info(const std::string& id, int joints, int samples, bool torque = true, bool reference = true) {
  DatasetInfo info;
  info.id = id;
  info.name = "fixture " + id;
  info.created_at = "2026-01-01T00:00:00.000Z";
  info.joints = joints;
  info.samples = samples;
  info.dt = 0.001;
  info.has_torque = torque;
  info.has_reference = reference;
  return info;
}

JobInfo job_info(const std::string& id, JobKind kind, JobState state) {
  JobInfo job;
  job.id = id;
  job.kind = kind;
  job.state = state;
  job.created_at = "2026-01-01T00:00:00.000Z";
  job.request = R"({"dataset_id":"ds_paper"})";
  job.dataset_id = kind == JobKind::identification ? "ds_paper" : "";
  return job;
}

std::vector<HistoryEntry> history_of(int count) {
  std::vector<HistoryEntry> entries;
  for (int i = 0; i < count; ++i) entries.push_back({i, 100.0 / (i + 1), {50.0, 25.0 + i, 0.4, 0.8}});
  return entries;
}

// ---- The server under test ---------------------------------------------------------------

/// register_routes over a FakeService on the real HttpServer bound to 127.0.0.1:0, served
/// from a thread (0.11.4 has no wait_until_ready: bind_to_any_port + listen_after_bind, then
/// spin on is_running()).
class RouteServer : public ::testing::Test {
 protected:
  virtual RouteOptions options() const {
    RouteOptions routes;
    routes.max_body = 16 * 1024;
    return routes;
  }

  void SetUp() override {
    RouteOptions routes = options();
    routes.log = [this](const std::string& line) {
      std::lock_guard lock(log_mutex_);
      log_ += line + "\n";
    };
    register_routes(server_, fake_, routes);
    server_.set_keep_alive_max_count(100);
    port_ = server_.bind("127.0.0.1", 0);
    ASSERT_GT(port_, 0);
    listener_ = std::thread([this] {
      server_.listen_after_bind();
      listen_returned_ = true;
    });
    while (!server_.is_running() && !listen_returned_) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    ASSERT_TRUE(server_.is_running()) << "listen_after_bind returned at once";
  }

  void TearDown() override {
    server_.stop();
    if (listener_.joinable()) listener_.join();
  }

  httplib::Client client() const {
    httplib::Client client("127.0.0.1", port_);
    client.set_read_timeout(30, 0);
    return client;
  }

  httplib::Result get(const std::string& path, const httplib::Headers& headers = {}) const { return client().Get(path, headers); }

  httplib::Result post(const std::string& path, const std::string& body, const std::string& content_type = "application/json",
                       const httplib::Headers& headers = {}) const {
    return client().Post(path, headers, body, content_type.c_str());
  }

  /// One request on a fresh raw connection.
  RawAnswer raw(const std::string& request) const { return RawConnection(port_).exchange(request); }

  std::string log() const {
    std::lock_guard lock(log_mutex_);
    return log_;
  }

  FakeService fake_;
  HttpServer server_;
  int port_ = 0;

 private:
  std::thread listener_;
  std::atomic<bool> listen_returned_{false};
  mutable std::mutex log_mutex_;
  std::string log_;
};

using Routes = RouteServer;

class RoutesWithToken : public RouteServer {
 protected:
  RouteOptions options() const override {
    RouteOptions routes = RouteServer::options();
    routes.token = "s3cret";
    return routes;
  }
};

/// Named tokens (manipid serve --token-file): alice and bob own their resources; carol is an admin.
class RoutesWithNamedTokens : public RouteServer {
 protected:
  RouteOptions options() const override {
    RouteOptions routes = RouteServer::options();
    routes.tokens = {{"alice", "alice-token-0123456789", false},
                     {"bob", "bob-token-0123456789ab", false},
                     {"carol", "carol-token-0123456789", true}};
    return routes;
  }
  /// The headers of a request with `name`'s token.
  static httplib::Headers as(const std::string& name) {
    return {{"Authorization", "Bearer " + name + "-token-" + (name == "bob" ? "0123456789ab" : "0123456789")}};
  }
};

// ---- Datasets ----------------------------------------------------------------------------

TEST_F(Routes, DatasetUploadAsJsonAnswers201WithLocation) {
  const auto result = post("/v1/datasets", R"({"name": "two joints", "dt": 0.001, "q": [[0, 1, 2], [0, 1, 2]]})");
  ASSERT_TRUE(result);
  EXPECT_EQ(result->status, 201) << result->body;
  EXPECT_EQ(result->get_header_value("Content-Type"), "application/json");
  EXPECT_EQ(result->get_header_value("Location"), "/v1/datasets/ds_1");
  EXPECT_FALSE(result->has_header("Idempotent-Replayed"));
  const Json body = json_of(result);
  EXPECT_EQ(body["id"], "ds_1");
  EXPECT_EQ(body["joints"], 2);
  EXPECT_EQ(body["samples"], 3);
  ASSERT_EQ(fake_.uploads().size(), 1u);
  EXPECT_EQ(fake_.uploads()[0].upload.name, "two joints");
  EXPECT_FALSE(fake_.uploads()[0].key);
}

TEST_F(Routes, CurlsSlipsGetTheCommandThatWorks) {
  // `curl --data-binary @run.csv` without a Content-Type: labelled form-urlencoded, which cpp-httplib reads
  // only up to 8 KiB. A 12 KB CSV is not too large (--max-body): its label is wrong, and the answer says so.
  std::string csv = "t,q1,tau1\n";
  for (int i = 0; csv.size() < 12'000; ++i) csv += std::to_string(0.001 * i) + ",0.123456789012,1.234567890123\n";
  const Json form = expect_problem(post("/v1/datasets", csv, "application/x-www-form-urlencoded"), 415, "UNSUPPORTED_MEDIA", "");
  EXPECT_NE(form["detail"].get<std::string>().find("-H 'Content-Type: text/csv'"), std::string::npos) << form;
  EXPECT_EQ(post("/v1/datasets", csv, "text/csv")->status, 201);
  // `curl -d @run.csv` drops the line ends: one line, whatever else is wrong with it.
  const Json one_line = expect_problem(post("/v1/datasets", "t,q1,tau10,0,10.001,0.1,1", "application/x-www-form-urlencoded"),
                                       422, "INVALID_FIELD", "body");
  EXPECT_NE(one_line["detail"].get<std::string>().find("curl -d @file drops the file's line ends"), std::string::npos) << one_line;
}

TEST_F(Routes, DatasetUploadAsCsvTakesItsNameFromTheQuery) {
  const std::string csv = "t,q1,tau1\n0,0,1\n0.001,0.1,1\n0.002,0.2,1\n";
  auto result = post("/v1/datasets?name=bench%20run", csv, "text/csv");
  ASSERT_TRUE(result);
  EXPECT_EQ(result->status, 201) << result->body;
  // curl --data-binary labels it form-urlencoded: CSV when it does not look like JSON.
  result = post("/v1/datasets", csv, "application/x-www-form-urlencoded");
  ASSERT_TRUE(result);
  EXPECT_EQ(result->status, 201) << result->body;
  result = post("/v1/datasets", R"({"dt": 0.001, "q": [[0, 1]]})", "application/x-www-form-urlencoded");
  ASSERT_TRUE(result);
  EXPECT_EQ(result->status, 201) << result->body;
  const auto uploads = fake_.uploads();
  ASSERT_EQ(uploads.size(), 3u);
  EXPECT_EQ(uploads[0].upload.name, "bench run");
  EXPECT_EQ(uploads[0].upload.trajectory.samples(), 3);
  EXPECT_TRUE(uploads[0].upload.trajectory.has_torque());
  EXPECT_EQ(uploads[1].upload.trajectory.samples(), 3);
  EXPECT_EQ(uploads[2].upload.trajectory.samples(), 2);
  expect_problem(post("/v1/datasets?name=" + std::string(201, 'n'), csv, "text/csv"), 422, "INVALID_FIELD", "name");
}

TEST_F(Routes, DatasetUploadReplayedUnderItsIdempotencyKeySaysSo) {
  fake_.script([](Script& s) { s.replay = true; });
  const std::string body = R"({"dt": 0.001, "q": [[0, 1, 2]]})";
  const auto result = post("/v1/datasets", body, "application/json", {{"Idempotency-Key", "\"upload-1\""}});
  ASSERT_TRUE(result);
  EXPECT_EQ(result->status, 201);
  EXPECT_EQ(result->get_header_value("Idempotent-Replayed"), "true");
  ASSERT_EQ(fake_.uploads().size(), 1u);
  const auto key = fake_.uploads()[0].key;
  ASSERT_TRUE(key);
  EXPECT_EQ(key->key, "upload-1");  // the sf-string's quotes are not part of the key
  EXPECT_EQ(key->fingerprint.size(), 64u);
}

TEST_F(Routes, DatasetUploadErrorsNameTheirField) {
  expect_problem(post("/v1/datasets", "<xml/>", "application/xml"), 415, "UNSUPPORTED_MEDIA", "Content-Type");
  const Json malformed = expect_problem(post("/v1/datasets", R"({"dt": 0.001, "q": [[1,2])"), 400, "MALFORMED_BODY", "body");
  EXPECT_EQ(malformed["instance"], "/v1/datasets");
  EXPECT_NE(malformed["detail"].get<std::string>().find("not valid JSON"), std::string::npos);
  expect_problem(post("/v1/datasets", "[1, 2]"), 400, "MALFORMED_BODY", "body");
  expect_problem(post("/v1/datasets", R"({"dt": 0.001, "q": [[NaN, 1]]})"), 400, "MALFORMED_BODY", "body");
  EXPECT_EQ(fake_.calls(), 0);  // nothing reached the service
  const Json ragged = expect_problem(post("/v1/datasets", R"({"dt": 0.001, "q": [[0, 1, 2], [0, 1]]})"), 422,
                                     "INVALID_FIELD", "q[1]");
  EXPECT_NE(ragged["detail"].get<std::string>().find("2 samples"), std::string::npos) << ragged;
  const Json csv = expect_problem(post("/v1/datasets", "t,q1\n0,1,2\n", "text/csv"), 422, "INVALID_FIELD", "csv");
  EXPECT_EQ(csv["detail"], "line 2: expected 2 fields, got 3");
  expect_problem(post("/v1/datasets", "{}", "application/json", {{"Idempotency-Key", std::string(300, 'k')}}), 422,
                 "INVALID_FIELD", "Idempotency-Key");
  EXPECT_TRUE(fake_.uploads().empty());
}

TEST_F(Routes, DatasetAsJsonOrCsv) {
  fake_.add_dataset(dataset_info("ds_a", 2, 4, true, false), trajectory(2, 4, 0.5));
  auto result = get("/v1/datasets/ds_a");
  ASSERT_TRUE(result);
  EXPECT_EQ(result->status, 200);
  EXPECT_EQ(result->get_header_value("Content-Type"), "application/json");
  const Json body = json_of(result);
  EXPECT_EQ(body["id"], "ds_a");
  EXPECT_EQ(body["samples"], 4);
  EXPECT_EQ(body["links"]["self"], "/v1/datasets/ds_a");
  for (const auto& [path, headers] : std::vector<std::pair<std::string, httplib::Headers>>{
           {"/v1/datasets/ds_a?format=csv", {}}, {"/v1/datasets/ds_a", {{"Accept", "text/csv"}}}}) {
    result = get(path, headers);
    ASSERT_TRUE(result);
    EXPECT_EQ(result->status, 200) << path;
    EXPECT_EQ(result->get_header_value("Content-Type"), "text/csv") << path;
    EXPECT_EQ(result->body.substr(0, result->body.find('\n')), "t,q1,q2,tau1,tau2") << path;
    EXPECT_EQ(std::count(result->body.begin(), result->body.end(), '\n'), 5) << path;
  }
  result = get("/v1/datasets/ds_a?format=json", {{"Accept", "text/csv"}});  // ?format= decides
  ASSERT_TRUE(result);
  EXPECT_EQ(result->get_header_value("Content-Type"), "application/json");
  expect_problem(get("/v1/datasets/ds_a?format=xml"), 422, "INVALID_FIELD", "format");
  const Json missing = expect_problem(get("/v1/datasets/ds_0000000000000000"), 404, "NOT_FOUND", "id");
  EXPECT_EQ(missing["detail"], "no dataset ds_0000000000000000");
  expect_problem(get("/v1/datasets/ds_0000000000000000?format=csv"), 404, "NOT_FOUND", "id");
}

TEST_F(Routes, DatasetDataForDrawing) {
  fake_.add_dataset(dataset_info("ds_a", 2, 9, true, false), trajectory(2, 9, 0.5));
  auto result = get("/v1/datasets/ds_a/data");
  ASSERT_TRUE(result);
  EXPECT_EQ(result->status, 200);
  Json body = json_of(result);
  EXPECT_EQ(body["t"].size(), 9u);
  EXPECT_EQ(body["q"].size(), 2u);  // one array per joint, as uploads take it
  EXPECT_EQ(body["tau"].size(), 2u);
  EXPECT_FALSE(body.contains("ref"));
  result = get("/v1/datasets/ds_a/data?max_points=3");
  ASSERT_TRUE(result);
  body = json_of(result);
  // ceil(9 / 3) = 3: samples 0, 3, 6, and always the last, 8.
  EXPECT_EQ(body["t"], Json::parse("[0.0, 1.5, 3.0, 4.0]"));
  result = get("/v1/datasets/ds_a/data?max_points=3", {{"Accept", "text/csv"}});
  ASSERT_TRUE(result);
  EXPECT_EQ(result->get_header_value("Content-Type"), "text/csv");
  EXPECT_EQ(std::count(result->body.begin(), result->body.end(), '\n'), 5);
  for (const std::string& bad : {"1"s, "x"s, "1000001"s, "-5"s, "3.5"s}) {
    const Json problem = expect_problem(get("/v1/datasets/ds_a/data?max_points=" + bad), 422, "INVALID_FIELD", "max_points");
    EXPECT_EQ(problem["detail"], "max_points must be an integer from 2 to 1000000, got '" + bad + "'");
  }
  expect_problem(get("/v1/datasets/ds_0000000000000000/data"), 404, "NOT_FOUND", "id");
}

TEST_F(Routes, DatasetListPagesAsAsked) {
  fake_.add_dataset(dataset_info("ds_a", 2, 4));
  fake_.add_dataset(dataset_info("ds_b", 2, 4));
  fake_.script([](Script& s) { s.next_page_token = "after-a"; });
  auto result = get("/v1/datasets?page_size=1&page_token=start");
  ASSERT_TRUE(result);
  EXPECT_EQ(result->status, 200);
  Json body = json_of(result);
  ASSERT_EQ(body["items"].size(), 1u);
  EXPECT_EQ(body["items"][0]["id"], "ds_a");
  EXPECT_EQ(body["next_page_token"], "after-a");
  fake_.script([](Script&) {});
  result = get("/v1/datasets?page_size=0");  // AIP-158: 0 means the default
  ASSERT_TRUE(result);
  body = json_of(result);
  EXPECT_EQ(body["items"].size(), 2u);
  EXPECT_FALSE(body.contains("next_page_token"));  // omitted on the last page, never empty
  const auto pages = fake_.page_requests();
  ASSERT_EQ(pages.size(), 2u);
  EXPECT_EQ(pages[0].page_size, 1);
  EXPECT_EQ(pages[0].page_token, "start");
  EXPECT_EQ(pages[1].page_size, 50);
  expect_problem(get("/v1/datasets?page_size=-1"), 422, "INVALID_FIELD", "page_size");
  expect_problem(get("/v1/datasets?page_size=1000001"), 422, "INVALID_FIELD", "page_size");
  expect_problem(get("/v1/datasets?page_size=ten"), 422, "INVALID_FIELD", "page_size");
  EXPECT_EQ(fake_.page_requests().size(), 2u);
}

TEST_F(Routes, DatasetDeleteAnswersByOutcome) {
  fake_.add_dataset(dataset_info("ds_a", 2, 4));
  auto result = client().Delete("/v1/datasets/ds_a");
  ASSERT_TRUE(result);
  EXPECT_EQ(result->status, 204);
  EXPECT_TRUE(result->body.empty());
  expect_problem(client().Delete("/v1/datasets/ds_a"), 404, "NOT_FOUND", "id");
  fake_.script([](Script& s) { s.delete_outcome = DeleteOutcome::conflict; });
  const Json problem = expect_problem(client().Delete("/v1/datasets/ds_b"), 409, "CONFLICT", "id");
  EXPECT_EQ(problem["detail"], "dataset ds_b is the input of a queued or running job");
}

// ---- Submissions and presets -------------------------------------------------------------

TEST_F(Routes, IdentificationOfADatasetIsQueued) {
  fake_.add_dataset(dataset_info("ds_paper", 4, 9701));
  const std::string request = R"({"dataset_id": "ds_paper", "free": ["m2", "m3"], "half_length": 100, "band": 0.2})";
  const auto result = post("/v1/identifications", request);
  ASSERT_TRUE(result);
  EXPECT_EQ(result->status, 202) << result->body;
  EXPECT_EQ(result->get_header_value("Content-Type"), "application/json");
  EXPECT_EQ(result->get_header_value("Location"), "/v1/jobs/job_1");
  EXPECT_EQ(result->get_header_value("Retry-After"), "1");  // queued: not terminal
  EXPECT_FALSE(result->has_header("Idempotent-Replayed"));
  const Json job = json_of(result);
  EXPECT_EQ(job["id"], "job_1");
  EXPECT_EQ(job["kind"], "identification");
  EXPECT_EQ(job["state"], "queued");
  const auto submissions = fake_.submissions();
  ASSERT_EQ(submissions.size(), 1u);
  EXPECT_EQ(submissions[0].kind, JobKind::identification);
  EXPECT_EQ(submissions[0].dataset_id, "ds_paper");
  EXPECT_EQ(Json::parse(submissions[0].request_json), Json::parse(request));  // the body as accepted
  EXPECT_FALSE(submissions[0].key);
}

TEST_F(Routes, IdentificationRequestsAreValidatedBeforeAnythingIsQueued) {
  fake_.add_dataset(dataset_info("ds_small", 4, 50, true, false));
  expect_problem(post("/v1/identifications", R"({"dataset_id": "ds_0000000000000000"})"), 422, "INVALID_FIELD", "dataset_id");
  const Json few = expect_problem(post("/v1/identifications", R"({"dataset_id": "ds_small", "half_length": 100, "band": 0.2})"),
                                  422, "INVALID_FIELD", "half_length");
  EXPECT_NE(few["detail"].get<std::string>().find("202"), std::string::npos) << few;
  expect_problem(post("/v1/identifications", R"({"dataset_id": "ds_small", "max_evaluation": 10})"), 422, "INVALID_FIELD",
                 "max_evaluation");
  expect_problem(post("/v1/identifications", R"({"dataset_id": "ds_small", "free": ["m9"]})"), 422, "INVALID_FIELD", "free[0]");
  expect_problem(post("/v1/identifications", R"({"dataset_id": )"), 400, "MALFORMED_BODY", "body");
  expect_problem(post("/v1/identifications", "dataset_id=ds_small", "text/plain"), 415, "UNSUPPORTED_MEDIA", "Content-Type");
  const Json empty = expect_problem(post("/v1/identifications", ""), 400, "MALFORMED_BODY", "body");
  EXPECT_EQ(empty["detail"], "the request body is empty; expected a JSON object");
  EXPECT_TRUE(fake_.submissions().empty());
}

TEST_F(Routes, SimulationIsQueuedWithoutADataset) {
  const auto result = post("/v1/simulations", R"({"preset": "cedro2009", "duration": 0.5})", "application/merge-patch+json");
  ASSERT_TRUE(result);
  EXPECT_EQ(result->status, 202) << result->body;  // any +json media type is JSON
  EXPECT_EQ(result->get_header_value("Location"), "/v1/jobs/job_1");
  EXPECT_EQ(json_of(result)["kind"], "simulation");
  const auto submissions = fake_.submissions();
  ASSERT_EQ(submissions.size(), 1u);
  EXPECT_EQ(submissions[0].kind, JobKind::simulation);
  EXPECT_EQ(submissions[0].dataset_id, "");
  expect_problem(post("/v1/simulations", R"({"preset": "nope"})"), 422, "INVALID_FIELD", "preset");
  EXPECT_EQ(fake_.submissions().size(), 1u);
}

TEST_F(Routes, SimulateAndIdentifyInOneRequestNeedsNoDataset) {
  const auto result = post("/v1/identifications", R"({"simulation": {"duration": 1.0}, "preset": "cedro2009"})");
  ASSERT_TRUE(result);
  EXPECT_EQ(result->status, 202) << result->body;
  ASSERT_EQ(fake_.submissions().size(), 1u);
  EXPECT_EQ(fake_.submissions()[0].dataset_id, "");
}

TEST_F(Routes, IdempotencyKeyFingerprintsTheRequest) {
  const std::string first = R"({"duration": 0.5})";
  const std::string second = R"({"duration": 0.6})";
  const httplib::Headers key = {{"Idempotency-Key", "lab-run-42"}};
  ASSERT_TRUE(post("/v1/simulations", first, "application/json", key));
  ASSERT_TRUE(post("/v1/simulations", first, "application/json", key));
  ASSERT_TRUE(post("/v1/simulations", second, "application/json", key));
  const auto submissions = fake_.submissions();
  ASSERT_EQ(submissions.size(), 3u);
  for (const auto& submission : submissions) {
    ASSERT_TRUE(submission.key);
    EXPECT_EQ(submission.key->key, "lab-run-42");
  }
  EXPECT_EQ(submissions[0].key->fingerprint, submissions[1].key->fingerprint);  // a retry
  EXPECT_NE(submissions[0].key->fingerprint, submissions[2].key->fingerprint);  // another request

  fake_.script([](Script& s) { s.replay = true; });
  const auto replayed = post("/v1/simulations", first, "application/json", key);
  ASSERT_TRUE(replayed);
  EXPECT_EQ(replayed->status, 202);
  EXPECT_EQ(replayed->get_header_value("Idempotent-Replayed"), "true");

  fake_.script([](Script& s) { s.submit_error = ProblemKind::idempotency_mismatch; });
  expect_problem(post("/v1/simulations", second, "application/json", key), 422, "IDEMPOTENCY_MISMATCH", "");
  for (const std::string& bad : {std::string(256, 'k'), std::string("two words"), std::string("\"\"")}) {
    expect_problem(post("/v1/simulations", first, "application/json", {{"Idempotency-Key", bad}}), 422, "INVALID_FIELD",
                   "Idempotency-Key");
  }
}

TEST_F(Routes, FullQueueAnswers429WithRetryAfter) {
  fake_.script([](Script& s) { s.submit_error = ProblemKind::queue_full; });
  const auto result = post("/v1/simulations", R"({"duration": 0.5})");
  expect_problem(result, 429, "QUEUE_FULL", "");
  ASSERT_TRUE(result);
  EXPECT_EQ(result->get_header_value("Retry-After"), "5");
}

TEST_F(Routes, ShuttingDownAnswers503WithRetryAfter) {
  fake_.script([](Script& s) { s.submit_error = ProblemKind::shutting_down; });
  const auto result = post("/v1/simulations", R"({"duration": 0.5})");
  expect_problem(result, 503, "SHUTTING_DOWN", "");
  ASSERT_TRUE(result);
  EXPECT_EQ(result->get_header_value("Retry-After"), "5");
  fake_.set_accepting(false);
  const auto health = get("/healthz");
  ASSERT_TRUE(health);
  EXPECT_EQ(health->status, 503);
  EXPECT_EQ(json_of(health), Json::parse(R"({"status": "shutting down"})"));
}

TEST_F(Routes, AFullDiskIs507WithRetryAfterAndHealthSaysDegraded) {
  fake_.script([](Script& s) { s.submit_error = ProblemKind::insufficient_storage; });
  const auto result = post("/v1/simulations", R"({"duration": 0.5})");
  expect_problem(result, 507, "INSUFFICIENT_STORAGE", "");
  ASSERT_TRUE(result);
  EXPECT_EQ(result->get_header_value("Retry-After"), "5");
  fake_.set_degraded("the disk holding the database is full");
  auto health = get("/healthz");
  ASSERT_TRUE(health);
  EXPECT_EQ(health->status, 200);  // reads still answer
  EXPECT_EQ(json_of(health), Json::parse(R"({"status": "degraded", "detail": "the disk holding the database is full"})"));
  fake_.set_degraded(std::nullopt);
  health = get("/healthz");
  ASSERT_TRUE(health);
  EXPECT_EQ(json_of(health), Json::parse(R"({"status": "ok"})"));
}

TEST_F(Routes, PresetsAndTheirErrors) {
  auto result = get("/v1/presets");
  ASSERT_TRUE(result);
  EXPECT_EQ(result->status, 200);
  const Json items = json_of(result)["items"];
  EXPECT_TRUE(std::any_of(items.begin(), items.end(), [](const Json& preset) { return preset["name"] == "cedro2009"; }))
      << items;
  result = get("/v1/presets/cedro2009?kinetic_energy=paper");
  ASSERT_TRUE(result);
  EXPECT_EQ(result->status, 200);
  const Json paper = json_of(result);
  EXPECT_EQ(paper["kinetic_energy"], "paper");
  EXPECT_EQ(paper["joints"], 4);
  EXPECT_EQ(paper["kp"], Json::parse("[3800, 40000, 10000, 500]"));
  const Json unknown = expect_problem(get("/v1/presets/puma560"), 404, "NOT_FOUND", "name");
  EXPECT_NE(unknown["detail"].get<std::string>().find("cedro2009"), std::string::npos) << unknown;  // lists the known
  expect_problem(get("/v1/presets/cedro2009?kinetic_energy=full"), 422, "INVALID_FIELD", "kinetic_energy");
}

// ---- Jobs --------------------------------------------------------------------------------

TEST_F(Routes, JobHasAnETagAndAnswers304WhenUnchanged) {
  fake_.add_job(job_info("job_q", JobKind::identification, JobState::queued));
  JobInfo done = job_info("job_done", JobKind::identification, JobState::succeeded);
  done.result = R"({"final_cost": 1.5})";
  fake_.add_job(done);

  auto result = get("/v1/jobs/job_q");
  ASSERT_TRUE(result);
  EXPECT_EQ(result->status, 200);
  EXPECT_EQ(result->get_header_value("Content-Type"), "application/json");
  EXPECT_EQ(result->get_header_value("Retry-After"), "1");
  const std::string etag = result->get_header_value("ETag");
  ASSERT_EQ(etag.size(), 34u);  // a quoted 32-digit hash
  EXPECT_EQ(etag.front(), '"');
  EXPECT_EQ(etag.back(), '"');
  Json job = json_of(result);
  EXPECT_EQ(job["id"], "job_q");
  EXPECT_EQ(job["state"], "queued");
  EXPECT_EQ(job["request"], Json::parse(R"({"dataset_id": "ds_paper"})"));

  result = get("/v1/jobs/job_q", {{"If-None-Match", etag}});
  ASSERT_TRUE(result);
  EXPECT_EQ(result->status, 304);
  EXPECT_TRUE(result->body.empty());
  EXPECT_EQ(result->get_header_value("ETag"), etag);
  result = get("/v1/jobs/job_q", {{"If-None-Match", "\"something else\""}});
  ASSERT_TRUE(result);
  EXPECT_EQ(result->status, 200);

  result = get("/v1/jobs/job_done");
  ASSERT_TRUE(result);
  EXPECT_EQ(result->status, 200);
  EXPECT_FALSE(result->has_header("Retry-After"));  // terminal
  EXPECT_NE(result->get_header_value("ETag"), etag);
  EXPECT_EQ(json_of(result)["result"]["final_cost"], 1.5);

  const Json missing = expect_problem(get("/v1/jobs/job_0000000000000000"), 404, "NOT_FOUND", "id");
  EXPECT_EQ(missing["detail"], "no job job_0000000000000000");
  EXPECT_EQ(missing["instance"], "/v1/jobs/job_0000000000000000");
}

TEST_F(Routes, JobLongPollIsCappedAndValidated) {
  fake_.add_job(job_info("job_q", JobKind::identification, JobState::running));
  for (const std::string& wait : {"5"s, "0.25"s, "0"s, "3600"s}) {
    const auto result = get("/v1/jobs/job_q?wait=" + wait);
    ASSERT_TRUE(result);
    EXPECT_EQ(result->status, 200) << wait;
  }
  EXPECT_EQ(fake_.waits(), (std::vector<double>{5.0, 0.25, 0.0, 30.0}));  // capped at max_wait_seconds
  for (const std::string& bad : {"soon"s, "-1"s, "inf"s, "nan"s, "1e400"s, "5s"s}) {
    const Json problem = expect_problem(get("/v1/jobs/job_q?wait=" + bad), 422, "INVALID_FIELD", "wait");
    EXPECT_EQ(problem["detail"], "wait must be a number of seconds >= 0, got '" + bad + "'");
  }
  EXPECT_EQ(fake_.waits().size(), 4u);
  expect_problem(get("/v1/jobs/job_0000000000000000?wait=1"), 404, "NOT_FOUND", "id");
}

/// Every long-poll slot taken.
class RoutesWithoutWaiters : public RouteServer {
 protected:
  RouteOptions options() const override {
    RouteOptions routes = RouteServer::options();
    routes.max_waiters = 0;
    return routes;
  }
};

TEST_F(RoutesWithoutWaiters, LongPollsBeyondMaxWaitersAreAnsweredAtOnceAndSaySo) {
  fake_.add_job(job_info("job_q", JobKind::identification, JobState::running));
  const auto result = get("/v1/jobs/job_q?wait=5");
  ASSERT_TRUE(result);
  EXPECT_EQ(result->status, 200);
  EXPECT_EQ(result->get_header_value("Manipid-Wait"), "declined");
  EXPECT_EQ(result->get_header_value("Retry-After"), "1");
  EXPECT_TRUE(fake_.waits().empty());  // it did not wait
  const auto plain = get("/v1/jobs/job_q?wait=0");  // a wait of 0 takes no slot
  ASSERT_TRUE(plain);
  EXPECT_FALSE(plain->has_header("Manipid-Wait"));
}

TEST_F(Routes, JobListFiltersAndLeavesTheRequestOut) {
  fake_.add_job(job_info("job_a", JobKind::identification, JobState::running));
  fake_.add_job(job_info("job_b", JobKind::simulation, JobState::succeeded));
  auto result = get("/v1/jobs?state=succeeded&kind=simulation&page_size=10");
  ASSERT_TRUE(result);
  EXPECT_EQ(result->status, 200);
  Json body = json_of(result);
  ASSERT_EQ(body["items"].size(), 1u);
  EXPECT_EQ(body["items"][0]["id"], "job_b");
  EXPECT_FALSE(body["items"][0].contains("request"));  // lists stay light
  EXPECT_FALSE(body.contains("next_page_token"));
  const auto filters = fake_.filters();
  ASSERT_EQ(filters.size(), 1u);
  EXPECT_EQ(filters[0].state, JobState::succeeded);
  EXPECT_EQ(filters[0].kind, JobKind::simulation);
  EXPECT_EQ(fake_.page_requests().back().page_size, 10);

  fake_.script([](Script& s) { s.next_page_token = "next"; });
  result = get("/v1/jobs");
  ASSERT_TRUE(result);
  body = json_of(result);
  EXPECT_EQ(body["items"].size(), 2u);
  EXPECT_EQ(body["next_page_token"], "next");
  EXPECT_EQ(fake_.page_requests().back().page_size, 50);

  expect_problem(get("/v1/jobs?state=done"), 422, "INVALID_FIELD", "state");
  expect_problem(get("/v1/jobs?kind=robot"), 422, "INVALID_FIELD", "kind");
  expect_problem(get("/v1/jobs?page_size=-1"), 422, "INVALID_FIELD", "page_size");
  expect_problem(get("/v1/jobs?robot_id="), 422, "INVALID_FIELD", "robot_id");
  EXPECT_EQ(fake_.filters().size(), 2u);

  JobInfo on_robot = job_info("job_c", JobKind::excitation, JobState::succeeded);
  on_robot.robot_id = "rb_1";
  fake_.add_job(on_robot);
  fake_.script([](Script&) {});
  result = get("/v1/jobs?robot_id=rb_1&kind=excitation");
  ASSERT_TRUE(result);
  body = json_of(result);
  ASSERT_EQ(body["items"].size(), 1u);
  EXPECT_EQ(body["items"][0]["id"], "job_c");
  EXPECT_EQ(fake_.filters().back().robot_id, "rb_1");
}

TEST_F(Routes, ARobotIdentificationIsAKindOfItsOwn) {
  JobInfo robot_job = job_info("job_robot", JobKind::robot_identification, JobState::queued);
  robot_job.robot_id = "rb_1";
  robot_job.dataset_id = "ds_run";
  fake_.add_job(robot_job);
  fake_.add_job(job_info("job_paper", JobKind::identification, JobState::queued));
  auto listed = get("/v1/jobs?kind=robot_identification");
  ASSERT_TRUE(listed);
  ASSERT_EQ(listed->status, 200) << listed->body;
  Json body = json_of(listed);
  ASSERT_EQ(body["items"].size(), 1u);
  EXPECT_EQ(body["items"][0]["id"], "job_robot");
  EXPECT_EQ(body["items"][0]["kind"], "robot_identification");
  EXPECT_EQ(fake_.filters().back().kind, JobKind::robot_identification);
  listed = get("/v1/jobs?kind=identification");
  ASSERT_TRUE(listed);
  body = json_of(listed);
  ASSERT_EQ(body["items"].size(), 1u);
  EXPECT_EQ(body["items"][0]["id"], "job_paper");
  const Json refused = expect_problem(get("/v1/jobs?kind=robot"), 422, "INVALID_FIELD", "kind");
  EXPECT_NE(refused["detail"].get<std::string>().find("robot_identification"), std::string::npos) << refused;

  // Its resource: the robot, its fit and identified URDF, no cost history.
  const auto got = get("/v1/jobs/job_robot");
  ASSERT_TRUE(got);
  const Json job = json_of(got);
  EXPECT_EQ(job["kind"], "robot_identification");
  EXPECT_EQ(job["links"]["robot"], "/v1/robots/rb_1");
  EXPECT_EQ(job["links"]["fit"], "/v1/jobs/job_robot/fit");
  EXPECT_EQ(job["links"]["urdf"], "/v1/jobs/job_robot/urdf");
  EXPECT_FALSE(job["links"].contains("history"));
  EXPECT_FALSE(job["links"].contains("validation"));  // it names no validation dataset
  // Not finished: no fit yet, no URDF.
  expect_problem(get("/v1/jobs/job_robot/fit"), 409, "CONFLICT", "id");
  expect_problem(get("/v1/jobs/job_robot/urdf"), 409, "CONFLICT", "id");

  // The paper's identification has no validation view and no URDF, whatever its row says.
  JobInfo paper = job_info("job_paper_done", JobKind::identification, JobState::succeeded);
  paper.validation_dataset_id = "ds_other";
  paper.result = "{}";
  fake_.add_job(paper);
  const Json paper_links = json_of(get("/v1/jobs/job_paper_done"))["links"];
  EXPECT_EQ(paper_links["history"], "/v1/jobs/job_paper_done/history");
  EXPECT_FALSE(paper_links.contains("validation"));
  EXPECT_FALSE(paper_links.contains("urdf"));
  expect_problem(get("/v1/jobs/job_paper_done/validation"), 409, "CONFLICT", "id");
  expect_problem(get("/v1/jobs/job_paper_done/urdf"), 409, "CONFLICT", "id");
  // Kinds without an estimate have no fit, and say what they are.
  fake_.add_job(job_info("job_design", JobKind::excitation, JobState::succeeded));
  const Json no_fit = expect_problem(get("/v1/jobs/job_design/fit"), 409, "CONFLICT", "id");
  EXPECT_NE(no_fit["detail"].get<std::string>().find("is an excitation"), std::string::npos) << no_fit;
}

TEST(JobKinds, EveryKindHasItsEntryAndPresetIdentificationsStayIdentifications) {
  for (const JobKind kind : kJobKinds) EXPECT_EQ(job_kind_handler(kind).kind, kind);
  EXPECT_EQ(identification_kind(Json{{"robot_id", "rb_1"}, {"dataset_id", "ds_1"}}), JobKind::robot_identification);
  EXPECT_EQ(identification_kind(Json{{"dataset_id", "ds_1"}}), JobKind::identification);
  EXPECT_EQ(identification_kind(Json{{"payload", true}, {"robot_id", "rb_1"}}), JobKind::payload_identification);
  EXPECT_EQ(identification_kind(Json{{"payload", false}}), JobKind::payload_identification);  // refused by its parser
  EXPECT_STREQ(job_kind_handler(JobKind::payload_identification).doing, "identifying the payload");
  EXPECT_TRUE(job_kind_handler(JobKind::payload_identification).on_robot);
  EXPECT_TRUE(job_kind_handler(JobKind::payload_identification).writes_urdf);
  EXPECT_FALSE(job_kind_handler(JobKind::payload_identification).has_history);
  EXPECT_EQ(kind_with_article(JobKind::robot_identification), "a robot_identification");
  EXPECT_EQ(kind_with_article(JobKind::identification), "an identification");
  EXPECT_STREQ(job_kind_handler(JobKind::robot_identification).doing, "identifying the robot");
  EXPECT_TRUE(job_kind_handler(JobKind::robot_identification).on_robot);
  EXPECT_FALSE(job_kind_handler(JobKind::identification).on_robot);
}

TEST_F(Routes, JobHistoryInPagesAsCsvAndThinned) {
  fake_.add_job(job_info("job_h", JobKind::identification, JobState::succeeded), history_of(5));

  auto result = get("/v1/jobs/job_h/history?page_size=2");
  ASSERT_TRUE(result);
  EXPECT_EQ(result->status, 200);
  Json page = json_of(result);
  ASSERT_EQ(page["items"].size(), 2u);
  EXPECT_EQ(page["items"][1]["index"], 1);
  EXPECT_EQ(page["items"][1]["cost"], 50.0);
  EXPECT_EQ(page["items"][1]["parameters"], Json::parse(R"({"m1": 50.0, "m2": 26.0, "l1": 0.4, "l2": 0.8})"));
  EXPECT_EQ(page["next_page_token"], "2");
  result = get("/v1/jobs/job_h/history?page_size=2&page_token=4");
  ASSERT_TRUE(result);
  page = json_of(result);
  EXPECT_EQ(page["items"].size(), 1u);
  EXPECT_FALSE(page.contains("next_page_token"));
  result = get("/v1/jobs/job_h/history");
  ASSERT_TRUE(result);
  EXPECT_EQ(json_of(result)["items"].size(), 5u);
  EXPECT_EQ(fake_.page_requests().back().page_size, 1000);  // the history's default page

  // CSV without paging: the whole history (read from the service a page at a time).
  result = get("/v1/jobs/job_h/history", {{"Accept", "text/csv"}});
  ASSERT_TRUE(result);
  EXPECT_EQ(result->status, 200);
  EXPECT_EQ(result->get_header_value("Content-Type"), "text/csv");
  EXPECT_EQ(result->body.substr(0, result->body.find('\n')), "index,cost,m1,m2,l1,l2");
  EXPECT_EQ(std::count(result->body.begin(), result->body.end(), '\n'), 6);
  // CSV with paging: one page, and the next page's token in a header.
  result = get("/v1/jobs/job_h/history?format=csv&page_size=2");
  ASSERT_TRUE(result);
  EXPECT_EQ(std::count(result->body.begin(), result->body.end(), '\n'), 3);
  EXPECT_EQ(result->get_header_value("X-Next-Page-Token"), "2");

  // Thinned for drawing.
  result = get("/v1/jobs/job_h/history?max_points=2");
  ASSERT_TRUE(result);
  EXPECT_EQ(result->status, 200);
  const Json overview = json_of(result);
  EXPECT_EQ(overview["total"], 5);
  EXPECT_EQ(overview["stride"], 3);
  EXPECT_EQ(overview["best_index"], 0);
  EXPECT_EQ(overview["items"].size(), 2u);
  EXPECT_EQ(fake_.overview_requests(), std::vector<long>{2});
  result = get("/v1/jobs/job_h/history?max_points=2&format=csv");
  ASSERT_TRUE(result);
  EXPECT_EQ(result->get_header_value("Content-Type"), "text/csv");
  EXPECT_EQ(std::count(result->body.begin(), result->body.end(), '\n'), 3);
}

TEST_F(Routes, JobHistoryParameterErrors) {
  fake_.add_job(job_info("job_h", JobKind::identification, JobState::succeeded), history_of(5));
  expect_problem(get("/v1/jobs/job_h/history?max_points=1"), 422, "INVALID_FIELD", "max_points");
  expect_problem(get("/v1/jobs/job_h/history?max_points=x"), 422, "INVALID_FIELD", "max_points");
  const Json both = expect_problem(get("/v1/jobs/job_h/history?max_points=10&page_size=5"), 422, "INVALID_FIELD", "max_points");
  EXPECT_EQ(both["detail"], "max_points cannot be combined with page_size or page_token");
  expect_problem(get("/v1/jobs/job_h/history?max_points=10&page_token=2"), 422, "INVALID_FIELD", "max_points");
  expect_problem(get("/v1/jobs/job_h/history?format=xml"), 422, "INVALID_FIELD", "format");
  expect_problem(get("/v1/jobs/job_h/history?page_size=many"), 422, "INVALID_FIELD", "page_size");
  expect_problem(get("/v1/jobs/job_0000000000000000/history"), 404, "NOT_FOUND", "id");
  expect_problem(get("/v1/jobs/job_0000000000000000/history?format=csv"), 404, "NOT_FOUND", "id");
  expect_problem(get("/v1/jobs/job_0000000000000000/history?max_points=10"), 404, "NOT_FOUND", "id");
}

TEST_F(Routes, JobFitAtTheEstimate) {
  fake_.add_dataset(dataset_info("ds_paper", 4, 301), trajectory(4, 301, 0.001));
  JobInfo done = job_info("job_fit", JobKind::identification, JobState::succeeded);
  done.result = R"({"point": {"m1": 50, "m2": 25, "m3": 15, "m4": 5, "l1": 0.4, "l2": 0.8, "l3": 0.6, "l4": 0.2},
                    "filter": {"half_length": 20, "band": 0.5, "dt": 0.001}, "torque_source": "measured"})";
  fake_.add_job(done);
  const auto result = get("/v1/jobs/job_fit/fit?max_points=50");
  ASSERT_TRUE(result);
  ASSERT_EQ(result->status, 200) << result->body;
  const Json fit = json_of(result);
  EXPECT_EQ(fit["samples"], 301 - 41);
  EXPECT_EQ(fit["filter"], Json::parse(R"({"half_length": 20, "band": 0.5, "dt": 0.001})"));
  EXPECT_EQ(fit["torque_source"], "measured");
  EXPECT_EQ(fit["parameters"]["m2"], 25.0);
  EXPECT_LE(fit["t"].size(), 51u);
  ASSERT_EQ(fit["joints"].size(), 4u);
  EXPECT_EQ(fit["joints"][0]["measured"].size(), fit["t"].size());
  // The default is 2000 points: all 260 here.
  const auto everything = get("/v1/jobs/job_fit/fit");
  ASSERT_TRUE(everything);
  EXPECT_EQ(json_of(everything)["t"].size(), 260u);
}

TEST_F(Routes, JobFitConflicts) {
  fake_.add_job(job_info("job_sim", JobKind::simulation, JobState::succeeded));
  fake_.add_job(job_info("job_run", JobKind::identification, JobState::running));
  JobInfo broken = job_info("job_broken", JobKind::identification, JobState::succeeded);
  broken.result = "not json";
  fake_.add_job(broken);
  JobInfo orphan = job_info("job_orphan", JobKind::identification, JobState::succeeded);
  orphan.result = "{}";
  orphan.dataset_id = "ds_deleted";
  fake_.add_job(orphan);
  fake_.add_dataset(dataset_info("ds_paper", 4, 301), trajectory(4, 301, 0.001));

  Json problem = expect_problem(get("/v1/jobs/job_sim/fit"), 409, "CONFLICT", "id");
  EXPECT_EQ(problem["detail"], "job job_sim is a simulation; only identifications have a fit");
  problem = expect_problem(get("/v1/jobs/job_run/fit"), 409, "CONFLICT", "id");
  EXPECT_EQ(problem["detail"], "job job_run is running and has no estimate to fit yet");
  problem = expect_problem(get("/v1/jobs/job_broken/fit"), 409, "CONFLICT", "id");
  EXPECT_EQ(problem["detail"], "job job_broken has no usable stored result");
  expect_problem(get("/v1/jobs/job_orphan/fit"), 409, "CONFLICT", "dataset_id");
  expect_problem(get("/v1/jobs/job_0000000000000000/fit"), 404, "NOT_FOUND", "id");
  expect_problem(get("/v1/jobs/job_sim/fit?max_points=1"), 422, "INVALID_FIELD", "max_points");
}

TEST_F(Routes, JobCancelAndDelete) {
  fake_.add_job(job_info("job_a", JobKind::identification, JobState::running));
  fake_.add_job(job_info("job_b", JobKind::identification, JobState::queued));

  expect_problem(client().Delete("/v1/jobs/job_a"), 409, "CONFLICT", "id");  // running: cancel it first
  auto result = post("/v1/jobs/job_a/cancel", "");  // httplib::Client sends Content-Length: 0
  ASSERT_TRUE(result);
  EXPECT_EQ(result->status, 200) << result->body;
  EXPECT_EQ(json_of(result)["state"], "cancelled");
  EXPECT_FALSE(result->has_header("Retry-After"));
  result = post("/v1/jobs/job_b:cancel", "");
  ASSERT_TRUE(result);
  EXPECT_EQ(result->status, 200);
  EXPECT_EQ(json_of(result)["state"], "cancelled");
  expect_problem(post("/v1/jobs/job_0000000000000000/cancel", ""), 404, "NOT_FOUND", "id");

  result = client().Delete("/v1/jobs/job_a");
  ASSERT_TRUE(result);
  EXPECT_EQ(result->status, 204);
  expect_problem(client().Delete("/v1/jobs/job_a"), 404, "NOT_FOUND", "id");
  expect_problem(get("/v1/jobs/job_a"), 404, "NOT_FOUND", "id");
}

// ---- The cpp-httplib 0.11.4 guards -------------------------------------------------------

TEST_F(Routes, BodilessCancelIsAnsweredBeforeAnyRead) {
  // curl -X POST sends no Content-Length; 0.11.4 would wait for a body until the peer closes.
  fake_.add_job(job_info("job_a", JobKind::identification, JobState::running));
  RawAnswer answer = raw("POST /v1/jobs/job_a/cancel HTTP/1.1\r\nHost: test\r\nConnection: close\r\n\r\n");
  EXPECT_EQ(answer.status, 200) << answer.head << answer.body;
  EXPECT_TRUE(answer.has_header("Content-Type", "application/json")) << answer.head;
  EXPECT_EQ(Json::parse(answer.body)["state"], "cancelled");
  answer = raw("POST /v1/jobs/job_a:cancel HTTP/1.1\r\nHost: test\r\nConnection: close\r\n\r\n");
  EXPECT_EQ(answer.status, 200) << answer.head << answer.body;
  answer = raw("POST /v1/jobs/job_0000000000000000/cancel HTTP/1.1\r\nHost: test\r\nConnection: close\r\n\r\n");
  expect_problem(answer, 404, "NOT_FOUND", "id");
}

TEST_F(Routes, BodilessPostIsRefusedWith411) {
  const RawAnswer answer = raw("POST /v1/datasets HTTP/1.1\r\nHost: test\r\nContent-Type: text/csv\r\n\r\n");
  const Json problem = expect_problem(answer, 411, "LENGTH_REQUIRED", "Content-Length");
  EXPECT_EQ(problem["instance"], "/v1/datasets");
  EXPECT_TRUE(answer.has_header("Connection", "close")) << answer.head;
  EXPECT_EQ(fake_.calls(), 0);
}

TEST_F(Routes, LengthlessPutAndPatchAreRefusedWith411) {
  // 0.11.4 reads them until the peer closes, like a POST, though no route takes them.
  for (const std::string& method : {"PUT"s, "PATCH"s}) {
    const RawAnswer answer = raw(method + " /v1/jobs/job_a HTTP/1.1\r\nHost: test\r\n\r\nand a body that never ends");
    expect_problem(answer, 411, "LENGTH_REQUIRED", "Content-Length");
    EXPECT_TRUE(answer.has_header("Connection", "close")) << answer.head;
  }
  EXPECT_EQ(fake_.calls(), 0);
}

TEST_F(Routes, ChunkedBodyIsRefusedBeforeItIsRead) {
  const RawAnswer answer = raw(
      "POST /v1/datasets HTTP/1.1\r\nHost: test\r\nContent-Type: text/csv\r\nTransfer-Encoding: chunked\r\n\r\n"
      "5\r\nt,q1\n\r\n0\r\n\r\n");
  const Json problem = expect_problem(answer, 411, "LENGTH_REQUIRED", "Transfer-Encoding");
  EXPECT_EQ(problem["detail"], "send the body with a Content-Length, not chunked");
  EXPECT_TRUE(answer.has_header("Connection", "close")) << answer.head;
  EXPECT_EQ(fake_.calls(), 0);
}

TEST_F(Routes, ARefusedBodyIsNeverReadAsTheNextRequest) {
  // cpp-httplib 0.11.4 alone read a refused request's body as the next request (smuggling).
  const std::string smuggled = "GET /v1/jobs HTTP/1.1\r\nHost: test\r\n\r\n";
  RawConnection connection(port_);
  const RawAnswer answer = connection.exchange("POST /v1/datasets HTTP/1.1\r\nHost: test\r\nContent-Type: application/json\r\n"
                                               "Content-Encoding: gzip\r\nContent-Length: " +
                                               std::to_string(smuggled.size()) + "\r\n\r\n" + smuggled);
  expect_problem(answer, 415, "UNSUPPORTED_MEDIA", "Content-Encoding");
  EXPECT_TRUE(answer.has_header("Connection", "close")) << answer.head;
  EXPECT_TRUE(connection.closed_by_server());  // and the GET never answered
  EXPECT_EQ(fake_.calls(), 0);
}

TEST_F(Routes, TwoContentLengthsAre400AndClose) {
  RawConnection connection(port_);
  const RawAnswer answer = connection.exchange(
      "POST /v1/datasets HTTP/1.1\r\nHost: test\r\nContent-Type: text/csv\r\nContent-Length: 5\r\n"
      "Content-Length: 5\r\n\r\nt,q1\n");
  const Json problem = expect_problem(answer, 400, "MALFORMED_BODY", "Content-Length");
  EXPECT_EQ(problem["detail"], "send one Content-Length header, not 2");
  EXPECT_TRUE(connection.closed_by_server());
  EXPECT_EQ(fake_.calls(), 0);
}

TEST_F(Routes, CompressedBodyIsRefusedWith415) {
  const auto result = post("/v1/datasets", "{}", "application/json", {{"Content-Encoding", "gzip"}});
  const Json problem = expect_problem(result, 415, "UNSUPPORTED_MEDIA", "Content-Encoding");
  EXPECT_EQ(problem["detail"], "compressed request bodies are not accepted");
  ASSERT_TRUE(result);
  EXPECT_EQ(result->get_header_value("Connection"), "close");
  EXPECT_EQ(fake_.calls(), 0);
}

TEST_F(Routes, BodyOverMaxBodyIs413) {
  const std::string big = "t,q1\n" + std::string(16 * 1024, '0');
  const auto result = post("/v1/datasets", big, "text/csv");
  const Json problem = expect_problem(result, 413, "PAYLOAD_TOO_LARGE", "body");
  EXPECT_EQ(problem["detail"], "the body is larger than this server accepts (--max-body 16384 bytes)");
  EXPECT_EQ(fake_.calls(), 0);
}

TEST_F(Routes, UnknownRouteIsAProblem) {
  Json problem = expect_problem(get("/v1/nothing-here"), 404, "NOT_FOUND", "");
  EXPECT_EQ(problem["detail"], "no route GET /v1/nothing-here");
  EXPECT_EQ(problem["instance"], "/v1/nothing-here");
  problem = expect_problem(get("/jobs/not%20an%20id"), 404, "NOT_FOUND", "");
  expect_problem(post("/v1/nothing-here", "{}"), 404, "NOT_FOUND", "");
  expect_problem(get("/v1/jobs/" + std::string(65, 'j')), 404, "NOT_FOUND", "");  // ids are at most 64 characters
  EXPECT_EQ(fake_.calls(), 0);
}

TEST_F(Routes, AMethodAKnownPathDoesNotTakeIs405WithAllow) {
  fake_.add_job(job_info("job_a", JobKind::identification, JobState::running));
  const struct {
    httplib::Result result;
    const char* method;
    const char* path;
    const char* allow;
  } cases[] = {
      {client().Put("/v1/jobs/job_a", "{}", "application/json"), "PUT", "/v1/jobs/job_a", "DELETE, GET, HEAD"},
      {client().Delete("/v1/jobs"), "DELETE", "/v1/jobs", "GET, HEAD"},
      {post("/v1/jobs", "{}"), "POST", "/v1/jobs", "GET, HEAD"},
      {get("/v1/simulations"), "GET", "/v1/simulations", "POST"},
      {get("/v1/jobs/job_a/cancel"), "GET", "/v1/jobs/job_a/cancel", "POST"},
      {client().Patch("/v1/datasets", "{}", "application/json"), "PATCH", "/v1/datasets", "GET, HEAD, POST"},
      {client().Options("/healthz"), "OPTIONS", "/healthz", "GET, HEAD"},
  };
  for (const auto& c : cases) {
    const Json problem = expect_problem(c.result, 405, "METHOD_NOT_ALLOWED", "");
    ASSERT_TRUE(c.result) << c.method << " " << c.path;
    EXPECT_EQ(c.result->get_header_value("Allow"), c.allow) << c.method << " " << c.path;
    EXPECT_EQ(problem["detail"], std::string("method ") + c.method + " not allowed on " + c.path + "; allowed: " + c.allow);
  }
  EXPECT_EQ(fake_.calls(), 0);
  // A path no route takes stays a 404, whatever the method.
  const auto result = client().Put("/v1/nothing-here", "{}", "application/json");
  expect_problem(result, 404, "NOT_FOUND", "");
  ASSERT_TRUE(result);
  EXPECT_FALSE(result->has_header("Allow"));
}

TEST_F(Routes, BrotliIsNeverChosen) {
  // 0.11.4's Brotli is quality 11 (seconds of a server thread for a large body): gzip instead.
  fake_.add_job(job_info("job_q", JobKind::identification, JobState::queued));
  auto plain = client();
  plain.set_decompress(false);
  const struct {
    const char* accept;
    const char* encoding;  ///< expected Content-Encoding, "" for none
  } cases[] = {{"gzip, deflate, br", "gzip"}, {"br", ""}, {"BR;q=1.0, gzip;q=0.5", "gzip"}, {"identity", ""}, {"br, gzip", "gzip"}};
  for (const auto& c : cases) {
    const auto result = plain.Get("/v1/jobs/job_q", {{"Accept-Encoding", c.accept}});
    ASSERT_TRUE(result) << c.accept;
    EXPECT_EQ(result->status, 200) << c.accept;
    EXPECT_EQ(result->get_header_value("Content-Encoding"), c.encoding) << c.accept;
    if (std::string(c.encoding) == "gzip") {
      ASSERT_GE(result->body.size(), 2u);
      EXPECT_EQ(static_cast<unsigned char>(result->body[0]), 0x1f) << c.accept;  // the gzip magic
      EXPECT_EQ(static_cast<unsigned char>(result->body[1]), 0x8b) << c.accept;
    } else {
      EXPECT_EQ(Json::parse(result->body)["id"], "job_q") << c.accept;
    }
  }
}

TEST_F(Routes, ServiceExceptionIs500AndLeaksNothing) {
  fake_.add_dataset(dataset_info("ds_a", 2, 4));
  fake_.script([](Script& s) { s.throw_what = "sqlite: database /srv/secret/manipid.db is locked"; });
  auto result = get("/v1/datasets/ds_a");
  Json problem = expect_problem(result, 500, "INTERNAL", "");
  EXPECT_EQ(problem["detail"], "internal error; see the server log");
  ASSERT_TRUE(result);
  EXPECT_EQ(result->body.find("secret"), std::string::npos) << result->body;
  EXPECT_FALSE(result->has_header("EXCEPTION_WHAT"));
  EXPECT_NE(log().find("internal error on /v1/datasets/ds_a: sqlite: database /srv/secret/manipid.db is locked"),
            std::string::npos)
      << log();

  // Not a std::exception: past `guarded`, caught by the exception handler (the net under the net).
  fake_.script([](Script& s) { s.throw_non_standard = true; });
  result = get("/v1/datasets/ds_a");
  problem = expect_problem(result, 500, "INTERNAL", "");
  EXPECT_EQ(problem["detail"], "internal error; see the server log");
  ASSERT_TRUE(result);
  EXPECT_FALSE(result->has_header("EXCEPTION_WHAT"));

  // Out of memory is not a bug of the request: 503 with Retry-After, and the server serves on.
  fake_.script([](Script& s) { s.throw_bad_alloc = true; });
  result = get("/v1/jobs");
  problem = expect_problem(result, 503, "MEMORY_BUSY", "");
  EXPECT_EQ(problem["detail"], "the server ran out of memory while handling this request; try again later");
  ASSERT_TRUE(result);
  EXPECT_EQ(result->get_header_value("Retry-After"), "5");

  fake_.script([](Script&) {});
  result = get("/v1/datasets/ds_a");  // and the server serves on
  ASSERT_TRUE(result);
  EXPECT_EQ(result->status, 200);
}

// ---- Static files, health, metrics -------------------------------------------------------

TEST_F(Routes, HealthAndTheOpenApiDocument) {
  auto result = get("/healthz");
  ASSERT_TRUE(result);
  EXPECT_EQ(result->status, 200);
  EXPECT_EQ(json_of(result), Json::parse(R"({"status": "ok"})"));
  result = get("/openapi.json");
  ASSERT_TRUE(result);
  EXPECT_EQ(result->status, 200);
  EXPECT_EQ(result->get_header_value("Content-Type"), "application/json");
  const Json document = json_of(result);
  EXPECT_EQ(document["openapi"].get<std::string>().substr(0, 2), "3.");
  for (const char* path : {"/v1/datasets", "/v1/identifications", "/v1/simulations", "/v1/jobs/{id}",
                           "/v1/jobs/{id}/history", "/v1/jobs/{id}/fit", "/v1/datasets/{id}/data"}) {
    EXPECT_TRUE(document["paths"].contains(path)) << path;
  }
}

TEST_F(Routes, MetricsCountRequestsByMethodAndStatus) {
  // One keep-alive connection: the server thread logs each request before it reads the next.
  httplib::Client connection("127.0.0.1", port_);
  connection.set_keep_alive(true);
  for (int i = 0; i < 3; ++i) ASSERT_TRUE(connection.Get("/healthz"));
  ASSERT_TRUE(connection.Get("/v1/nothing"));
  ASSERT_TRUE(connection.Post("/v1/simulations", R"({"preset": "nope"})", "application/json"));
  const auto result = connection.Get("/metrics");
  ASSERT_TRUE(result);
  EXPECT_EQ(result->status, 200);
  EXPECT_EQ(result->get_header_value("Content-Type"), "text/plain; version=0.0.4");
  const std::string& text = result->body;
  EXPECT_NE(text.find("manipid_queue_depth 7\n"), std::string::npos) << text;  // the service's part
  EXPECT_NE(text.find("# TYPE manipid_http_requests_total counter\n"), std::string::npos) << text;
  EXPECT_NE(text.find("manipid_http_requests_total{method=\"GET\",status=\"200\"} 3\n"), std::string::npos) << text;
  EXPECT_NE(text.find("manipid_http_requests_total{method=\"GET\",status=\"404\"} 1\n"), std::string::npos) << text;
  EXPECT_NE(text.find("manipid_http_requests_total{method=\"POST\",status=\"422\"} 1\n"), std::string::npos) << text;
  // One log line per request: address, method, target, status, bytes, time.
  EXPECT_NE(log().find("127.0.0.1 GET /v1/nothing 404 "), std::string::npos) << log();
}

TEST_F(Routes, MetricsNeverEchoAMethodHttplibRefused) {
  // 0.11.4 logs a request whose method it refused (400), with that method as sent.
  // The refusal closes its connection (what follows an unreadable request line is not
  // trusted), after the request is logged: /metrics then comes on a new connection.
  RawConnection connection(port_);
  const RawAnswer refused = connection.exchange("A\"}x /v1/jobs HTTP/1.1\r\nHost: test\r\n\r\n" + "GET /metrics HTTP/1.1\r\nHost: test\r\n\r\n"s);
  expect_problem(refused, 400, "MALFORMED_BODY", "");
  EXPECT_TRUE(refused.has_header("Connection", "close")) << refused.head;
  EXPECT_TRUE(connection.closed_by_server());
  const RawAnswer answer = raw("GET /metrics HTTP/1.1\r\nHost: test\r\n\r\n");
  EXPECT_EQ(answer.status, 200);
  EXPECT_EQ(answer.body.find("A\"}x"), std::string::npos) << answer.body;
  EXPECT_NE(answer.body.find("manipid_http_requests_total{method=\"other\",status=\"400\"} 1\n"), std::string::npos)
      << answer.body;
}

TEST_F(Routes, DashboardIsServed) {
  for (const char* path : {"/", "/jobs/job_0123456789abcdef"}) {
    const auto result = get(path);
    ASSERT_TRUE(result) << path;
    EXPECT_EQ(result->status, 200) << path;
    EXPECT_EQ(result->get_header_value("Content-Type").rfind("text/html", 0), 0u) << path;
    EXPECT_EQ(result->get_header_value("Cache-Control"), "no-cache") << path;
    EXPECT_EQ(result->get_header_value("X-Content-Type-Options"), "nosniff") << path;
    EXPECT_NE(result->get_header_value("Content-Security-Policy").find("default-src 'self'"), std::string::npos) << path;
  }
  if (dashboard_complete()) {
    const auto script = get("/assets/app.js");
    ASSERT_TRUE(script);
    EXPECT_EQ(script->status, 200);
    EXPECT_EQ(script->get_header_value("Content-Type").rfind("text/javascript", 0), 0u);
    EXPECT_FALSE(script->has_header("Content-Security-Policy"));
  }
  const Json problem = expect_problem(get("/assets/secret.db"), 404, "NOT_FOUND", "path");
  EXPECT_EQ(problem["detail"], "no file /assets/secret.db");
  expect_problem(get("/assets/..%2Fmanipid.db"), 404, "NOT_FOUND", "");
}

// ---- The bearer token --------------------------------------------------------------------

// ---- Robots ------------------------------------------------------------------------------

/// A small, valid two-joint arm.
const char* const kTwoJointUrdf = R"(<robot name="two">
  <link name="base"/>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/><axis xyz="0 0 1"/>
    <limit lower="-2" upper="2" velocity="2" effort="50"/></joint>
  <link name="l1"><inertial><origin xyz="0.1 0 0"/><mass value="2"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.02"/></inertial></link>
  <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/><origin xyz="0.3 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-2" upper="2" velocity="2" effort="50"/></joint>
  <link name="l2"><inertial><origin xyz="0.1 0 0"/><mass value="1"/><inertia ixx="0.005" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
</robot>)";

TEST_F(Routes, ARobotUploadsAsXmlOrJsonAndComesBackByteForByte) {
  const auto xml = post("/v1/robots?name=arm&tip=l2", kTwoJointUrdf, "application/xml", {{"Idempotency-Key", "r1"}});
  ASSERT_TRUE(xml);
  EXPECT_EQ(xml->status, 201) << xml->body;
  EXPECT_EQ(xml->get_header_value("Location"), "/v1/robots/rb_1");
  const Json robot = json_of(xml);
  EXPECT_EQ(robot["name"], "arm");
  EXPECT_EQ(robot["robot_name"], "two");
  EXPECT_EQ(robot["tip_link"], "l2");
  ASSERT_EQ(robot["joints"].size(), 2u);
  EXPECT_EQ(robot["joints"][1]["axis"], Json::array({0.0, 1.0, 0.0}));
  EXPECT_EQ(robot["joints"][1]["body_links"], Json::array({"l2"}));
  EXPECT_EQ(robot["parameters"]["names"].size(), 24u);  // 2 × 10 inertial + viscous and Coulomb per joint
  EXPECT_EQ(robot["parameters"]["urdf_values"]["m2"], 1.0);
  EXPECT_GT(robot["base_parameters"]["count"], 0);
  EXPECT_EQ(robot["links"]["urdf"], "/v1/robots/rb_1?format=urdf");
  const auto back = get("/v1/robots/rb_1?format=urdf");
  ASSERT_TRUE(back);
  EXPECT_EQ(back->status, 200);
  EXPECT_EQ(back->get_header_value("Content-Type"), "application/xml");
  EXPECT_EQ(back->body, kTwoJointUrdf);

  const Json body = {{"urdf", kTwoJointUrdf}, {"base", "base"}};
  const auto json = post("/v1/robots", body.dump());
  ASSERT_TRUE(json);
  EXPECT_EQ(json->status, 201) << json->body;
  EXPECT_EQ(json_of(json)["name"], "two");  // the URDF's name when none is given
  const Json list = json_of(get("/v1/robots"));
  EXPECT_EQ(list["items"].size(), 2u);
  EXPECT_EQ(json_of(get("/v1/robots/rb_2"))["base_link"], "base");
}

TEST_F(Routes, ALabsLogIsReadWithItsColumnMapAndUnits) {
  const std::string log = "stamp;j2/pos;j1/pos;j1/eff;j2/eff\n"
                          "1700000000000000000;90;0;1;2\n1700000000001000000;91;1;1;2\n1700000000002000000;92;2;1;2\n";
  // Without the map: the columns it has and the map that would read them.
  const Json missing = expect_problem(post("/v1/datasets", log, "text/csv"), 422, "INVALID_FIELD", "t");
  EXPECT_NE(missing["detail"].get<std::string>().find("stamp, j2/pos"), std::string::npos) << missing;

  ASSERT_EQ(post("/v1/robots?name=arm", kTwoJointUrdf, "application/xml")->status, 201);
  const std::string query = "/v1/datasets?robot_id=rb_1&time_unit=ns&angle_unit=deg&columns=" +
                            httplib::detail::encode_query_param("stamp=t,{joint}/pos=q{j},{joint}/eff=tau{j}");
  const auto result = post(query, log, "text/csv");
  ASSERT_TRUE(result);
  EXPECT_EQ(result->status, 201) << result->body;
  const auto uploads = fake_.uploads();
  ASSERT_EQ(uploads.size(), 1u);
  const Trajectory& run = uploads[0].upload.trajectory;
  EXPECT_NEAR(run.t[2], 0.002, 256e-9);  // from the first stamp, in seconds
  EXPECT_DOUBLE_EQ(run.q(1, 1), 91.0 * std::numbers::pi / 180.0);  // j2 is joint 2 wherever its column is
  EXPECT_DOUBLE_EQ(run.tau(0, 1), 2.0);

  expect_problem(post("/v1/datasets?columns=" + httplib::detail::encode_query_param("stamp=t,{joint}/pos=q{j}"), log,
                      "text/csv"),
                 422, "INVALID_FIELD", "columns");
  expect_problem(post("/v1/datasets?time_unit=h", log, "text/csv"), 422, "INVALID_FIELD", "time_unit");
  expect_problem(post("/v1/datasets?robot_id=rb_9&columns=stamp%3Dt", log, "text/csv"), 422, "INVALID_FIELD", "robot_id");
}

TEST_F(Routes, AROS2BagIsADatasetItsJointsMatchedByTheRobotsNames) {
  test_support::BagWriter writer;
  const int topic = writer.topic("/joint_states", "sensor_msgs/msg/JointState");
  for (int k = 0; k < 20; ++k) {
    test_support::Message message;
    message.sec = 1'700'000'000;
    message.nanosec = static_cast<std::uint32_t>(k * 2'000'000);
    message.name = {"j2", "j1"};
    message.position = {0.02 * k, 0.01 * k};
    message.effort = {2.0, 1.0};
    writer.message(topic, k, test_support::serialise(message));
  }
  const std::string bag = writer.bytes();
  ASSERT_EQ(post("/v1/robots?name=arm", kTwoJointUrdf, "application/xml")->status, 201);
  const auto result = post("/v1/datasets?robot_id=rb_1&name=bagged", bag, "application/vnd.sqlite3");
  ASSERT_TRUE(result);
  EXPECT_EQ(result->status, 201) << result->body;
  // curl --data-binary's label: the SQLite header decides.
  EXPECT_EQ(post("/v1/datasets", bag, "application/x-www-form-urlencoded")->status, 201);
  const auto uploads = fake_.uploads();
  ASSERT_EQ(uploads.size(), 2u);
  EXPECT_EQ(uploads[0].upload.name, "bagged");
  const Trajectory& run = uploads[0].upload.trajectory;
  ASSERT_LT(bag.size(), 8192u);  // cpp-httplib reads a form-urlencoded body up to 8 KiB
  EXPECT_EQ(run.samples(), 20);
  EXPECT_EQ(run.t[19], 0.038);
  EXPECT_EQ(run.q(10, 0), 0.1);  // j1, the robot's first joint
  EXPECT_EQ(run.tau(10, 1), 2.0);
  EXPECT_EQ(uploads[1].upload.trajectory.q(10, 0), 0.2);  // no robot: the bag's order

  const Json other = expect_problem(post("/v1/datasets?topic=/tf", bag, "application/vnd.sqlite3"), 422, "INVALID_FIELD", "topic");
  EXPECT_NE(other["detail"].get<std::string>().find("no topic /tf in the bag"), std::string::npos) << other;
  expect_problem(post("/v1/datasets", "t,q1\n0,1\n", "application/vnd.sqlite3"), 422, "INVALID_FIELD", "bag");
}

TEST_F(Routes, TextThatIsNotUtf8IsRefusedBeforeAnythingIsStored) {
  // ?name=%FF decodes to one byte no JSON can hold: once stored, it broke every later list (issue 29).
  const std::string csv = "t,q1,tau1\n0,0,1\n0.001,0.1,1\n0.002,0.2,1\n";
  Json problem = expect_problem(post("/v1/datasets?name=%FF", csv, "text/csv"), 422, "INVALID_FIELD", "name");
  EXPECT_NE(problem["detail"].get<std::string>().find("not valid UTF-8"), std::string::npos) << problem;
  expect_problem(post("/v1/robots?name=%C3%28", kTwoJointUrdf, "application/xml"), 422, "INVALID_FIELD", "name");
  std::string urdf = kTwoJointUrdf;
  urdf.insert(urdf.find("<link"), "<!-- \xFF -->");
  expect_problem(post("/v1/robots", urdf, "application/xml"), 422, "INVALID_FIELD", "urdf");
  expect_problem(post("/v1/robots?tip=%ED%A0%80", kTwoJointUrdf, "application/xml"), 422, "INVALID_FIELD", "tip");  // a surrogate
  EXPECT_TRUE(fake_.uploads().empty());
  EXPECT_EQ(json_of(get("/v1/robots"))["items"].size(), 0u);
  // UTF-8 names are names like any other.
  EXPECT_EQ(post("/v1/datasets?name=Gel%C3%A4nde", csv, "text/csv")->status, 201);
  EXPECT_EQ(fake_.uploads().at(0).upload.name, "Gel\xC3\xA4nde");
}

TEST_F(Routes, BadRobotsAreRefusedNamingTheFieldAndNothingIsStored) {
  expect_problem(post("/v1/robots", "<robot name='x'><link", "application/xml"), 422, "INVALID_FIELD", "urdf");
  expect_problem(post("/v1/robots?tip=nowhere", kTwoJointUrdf, "application/xml"), 422, "INVALID_FIELD", "tip");
  const std::string negative = std::string(kTwoJointUrdf).replace(std::string(kTwoJointUrdf).find("value=\"1\""), 9, "value=\"-1\"");
  const Json problem = expect_problem(post("/v1/robots", negative, "text/xml"), 422, "INVALID_FIELD", "urdf");
  EXPECT_NE(problem["detail"].get<std::string>().find("l2"), std::string::npos) << problem["detail"];
  expect_problem(post("/v1/robots", R"({"name": "no document"})"), 422, "INVALID_FIELD", "urdf");
  expect_problem(post("/v1/robots", R"({"urdf": 3})"), 422, "INVALID_FIELD", "urdf");
  expect_problem(post("/v1/robots", kTwoJointUrdf, "text/csv"), 415, "UNSUPPORTED_MEDIA", "Content-Type");
  EXPECT_TRUE(json_of(get("/v1/robots"))["items"].empty());
  expect_problem(get("/v1/robots/rb_9"), 404, "NOT_FOUND", "id");
  expect_problem(get("/v1/robots/rb_9?format=urdf"), 404, "NOT_FOUND", "id");
  expect_problem(get("/v1/robots/rb_9?format=yaml"), 422, "INVALID_FIELD", "format");
}

TEST_F(Routes, ARobotInUseIsNotDeleted) {
  ASSERT_EQ(post("/v1/robots", kTwoJointUrdf, "application/xml")->status, 201);
  fake_.script([](Script& s) { s.delete_outcome = DeleteOutcome::conflict; });
  expect_problem(client().Delete("/v1/robots/rb_1"), 409, "CONFLICT", "id");
  fake_.script([](Script&) {});
  EXPECT_EQ(client().Delete("/v1/robots/rb_1")->status, 204);
  expect_problem(client().Delete("/v1/robots/rb_1"), 404, "NOT_FOUND", "id");
}

TEST_F(Routes, ARobotIdentificationIsCheckedAgainstTheRobotAndBothDatasets) {
  ASSERT_EQ(post("/v1/robots", kTwoJointUrdf, "application/xml")->status, 201);
  fake_.add_dataset(dataset_info("ds_two", 2, 5000));
  fake_.add_dataset(dataset_info("ds_second", 2, 4000));
  fake_.add_dataset(dataset_info("ds_four", 4, 5000));
  fake_.add_dataset(dataset_info("ds_no_tau", 2, 5000, false, true));
  const Json request = {{"robot_id", "rb_1"}, {"dataset_id", "ds_two"}, {"validation_dataset_id", "ds_second"},
                        {"friction", {"viscous", "coulomb", "offset"}}, {"physical", true}, {"trim", {0.5, 0.5}}};
  const auto queued = post("/v1/identifications", request.dump());
  ASSERT_TRUE(queued);
  EXPECT_EQ(queued->status, 202) << queued->body;
  const auto submissions = fake_.submissions();
  ASSERT_EQ(submissions.size(), 1u);
  EXPECT_EQ(submissions[0].kind, JobKind::robot_identification);
  EXPECT_EQ(submissions[0].robot_id, "rb_1");
  EXPECT_EQ(submissions[0].dataset_id, "ds_two");
  EXPECT_EQ(submissions[0].validation_dataset_id, "ds_second");
  EXPECT_EQ(json_of(queued)["robot_id"], "rb_1");
  EXPECT_EQ(json_of(queued)["kind"], "robot_identification");
  EXPECT_EQ(json_of(queued)["links"]["urdf"], "/v1/jobs/" + json_of(queued)["id"].get<std::string>() + "/urdf");

  const auto refused = [&](Json body, const std::string& field) {
    return expect_problem(post("/v1/identifications", body.dump()), 422, "INVALID_FIELD", field);
  };
  const Json four = refused({{"robot_id", "rb_1"}, {"dataset_id", "ds_four"}}, "dataset_id");
  EXPECT_NE(four["detail"].get<std::string>().find("4 joints, the robot two has 2"), std::string::npos) << four;
  refused({{"robot_id", "rb_1"}, {"dataset_id", "ds_two"}, {"validation_dataset_id", "ds_four"}}, "validation_dataset_id");
  refused({{"robot_id", "rb_1"}, {"dataset_id", "ds_no_tau"}}, "dataset_id");
  refused({{"robot_id", "rb_7"}, {"dataset_id", "ds_two"}}, "robot_id");
  refused({{"robot_id", "rb_1"}, {"dataset_id", "ds_nothing"}}, "dataset_id");
  refused({{"robot_id", "rb_1"}, {"dataset_id", "ds_two"}, {"free", {"m2"}}}, "free");
  refused({{"robot_id", "rb_1"}, {"dataset_id", "ds_two"}, {"friction", {"sticky"}}}, "friction");
  refused({{"robot_id", "rb_1"}, {"dataset_id", "ds_two"}, {"trim", {1}}}, "trim");
  refused({{"robot_id", "rb_1"}, {"dataset_id", "ds_two"}, {"band", 0.1}}, "half_length");
  refused({{"robot_id", "rb_1"}, {"dataset_id", "ds_two"}, {"weights", "inverse-variance"}}, "weights");
  refused({{"robot_id", "rb_1"}}, "dataset_id");
  EXPECT_EQ(fake_.submissions().size(), 1u);  // nothing more was queued
}

TEST_F(Routes, ARobotIdentificationTakesSeveralRunsAndTheHeldOutOptions) {
  ASSERT_EQ(post("/v1/robots", kTwoJointUrdf, "application/xml")->status, 201);
  fake_.add_dataset(dataset_info("ds_a", 2, 5000));
  fake_.add_dataset(dataset_info("ds_b", 2, 4000));
  fake_.add_dataset(dataset_info("ds_c", 2, 3000));
  fake_.add_dataset(dataset_info("ds_four", 4, 5000));
  const Json request = {{"robot_id", "rb_1"},          {"dataset_ids", {"ds_a", "ds_b"}},
                        {"validation_dataset_ids", {"ds_c"}}, {"comparison_cutoff", 3},
                        {"ridge", "auto"},             {"judge_cutoff", 4},
                        {"judge_trim", 0.5},           {"torque_joints", {1, 2}}};
  const auto queued = post("/v1/identifications", request.dump());
  ASSERT_TRUE(queued);
  EXPECT_EQ(queued->status, 202) << queued->body;
  ASSERT_EQ(fake_.submissions().size(), 1u);
  // The job's datasets are the first of each list (what protects them from deletion while it waits).
  EXPECT_EQ(fake_.submissions()[0].dataset_id, "ds_a");
  EXPECT_EQ(fake_.submissions()[0].validation_dataset_id, "ds_c");
  const RobotIdentificationSpec spec = robot_identification_from_json(request);
  EXPECT_EQ(spec.dataset_ids, (std::vector<std::string>{"ds_a", "ds_b"}));
  EXPECT_EQ(spec.options.comparison_cutoff_hz, 3.0);
  EXPECT_LT(spec.options.ridge, 0.0);  // chosen
  EXPECT_EQ(spec.options.judge.cutoff_hz, 4.0);
  EXPECT_EQ(spec.options.judge.trim_seconds, 0.5);
  EXPECT_EQ(spec.options.torque_joints, (std::vector<int>{0, 1}));
  // Friction is chosen unless given.
  EXPECT_TRUE(spec.options.friction_auto);
  EXPECT_FALSE(robot_identification_from_json(Json{{"robot_id", "rb_1"}, {"dataset_id", "ds_a"}, {"friction", {"viscous"}}})
                   .options.friction_auto);
  EXPECT_EQ(robot_identification_from_json(Json{{"robot_id", "rb_1"}, {"dataset_id", "ds_a"}, {"ridge", 0}}).options.ridge, 0.0);

  const auto refused = [&](Json body, const std::string& field) {
    return expect_problem(post("/v1/identifications", body.dump()), 422, "INVALID_FIELD", field);
  };
  refused({{"robot_id", "rb_1"}, {"dataset_ids", {"ds_a", "ds_four"}}}, "dataset_ids[1]");
  refused({{"robot_id", "rb_1"}, {"dataset_ids", {"ds_a", "ds_nothing"}}}, "dataset_ids[1]");
  refused({{"robot_id", "rb_1"}, {"dataset_id", "ds_a"}, {"dataset_ids", {"ds_b"}}}, "dataset_ids");
  refused({{"robot_id", "rb_1"}, {"dataset_ids", Json::array()}}, "dataset_ids");
  refused({{"robot_id", "rb_1"}, {"dataset_id", "ds_a"}, {"torque_joints", {3}}}, "torque_joints");
  refused({{"robot_id", "rb_1"}, {"dataset_id", "ds_a"}, {"torque_joints", {0}}}, "torque_joints[0]");
  refused({{"robot_id", "rb_1"}, {"dataset_id", "ds_a"}, {"comparison_cutoff", -1}}, "comparison_cutoff");
  refused({{"robot_id", "rb_1"}, {"dataset_id", "ds_a"}, {"ridge", "some"}}, "ridge");
  refused({{"robot_id", "rb_1"}, {"dataset_id", "ds_a"}, {"judge_cutoff", 0}}, "judge_cutoff");
  // The former comparison filter's fields name their replacement.
  const Json old = refused({{"robot_id", "rb_1"}, {"dataset_id", "ds_a"}, {"comparison_band", 0.1}}, "comparison_band");
  EXPECT_NE(old["detail"].get<std::string>().find("comparison_cutoff"), std::string::npos) << old;
  EXPECT_EQ(fake_.submissions().size(), 1u);  // nothing more was queued
}

TEST_F(Routes, AnExcitationIsQueuedForAnExistingRobotOnly) {
  ASSERT_EQ(post("/v1/robots", kTwoJointUrdf, "application/xml")->status, 201);
  const auto queued = post("/v1/excitations", R"({"robot_id": "rb_1", "period": 8, "harmonics": 4, "duration": 16})");
  ASSERT_TRUE(queued);
  EXPECT_EQ(queued->status, 202) << queued->body;
  ASSERT_EQ(fake_.submissions().size(), 1u);
  EXPECT_EQ(fake_.submissions()[0].kind, JobKind::excitation);
  EXPECT_EQ(fake_.submissions()[0].robot_id, "rb_1");
  EXPECT_EQ(json_of(queued)["kind"], "excitation");
  expect_problem(post("/v1/excitations", R"({"robot_id": "rb_9"})"), 422, "INVALID_FIELD", "robot_id");
  expect_problem(post("/v1/excitations", R"({"robot_id": "rb_1", "harmonics": 1})"), 422, "INVALID_FIELD", "harmonics");
  expect_problem(post("/v1/excitations", R"({"robot_id": "rb_1", "duration": 15})"), 422, "INVALID_FIELD", "duration");
  expect_problem(post("/v1/excitations", R"({"robot_id": "rb_1", "max_acceleration": [1, 2, 3]})"), 422, "INVALID_FIELD",
                 "max_acceleration");
  expect_problem(post("/v1/excitations", R"({"period": 10})"), 422, "INVALID_FIELD", "robot_id");
  EXPECT_EQ(fake_.submissions().size(), 1u);
}

TEST_F(Routes, OnlyASucceededRobotIdentificationHasAnIdentifiedUrdf) {
  ASSERT_EQ(post("/v1/robots", kTwoJointUrdf, "application/xml")->status, 201);
  JobInfo excitation = job_info("job_excitation", JobKind::excitation, JobState::succeeded);
  excitation.robot_id = "rb_1";
  excitation.result = R"({"dataset_id": "ds_made", "criterion": "condition"})";
  fake_.add_job(excitation);
  JobInfo running = job_info("job_running", JobKind::robot_identification, JobState::running);
  running.robot_id = "rb_1";
  fake_.add_job(running);
  fake_.add_job(job_info("job_paper", JobKind::identification, JobState::succeeded));
  for (const char* id : {"job_excitation", "job_running", "job_paper"}) {
    const Json problem = expect_problem(get(std::string("/v1/jobs/") + id + "/urdf"), 409, "CONFLICT", "id");
    EXPECT_NE(problem["detail"].get<std::string>().find("not a succeeded robot or payload identification"), std::string::npos)
        << problem;
  }
  expect_problem(get("/v1/jobs/job_none/urdf"), 404, "NOT_FOUND", "id");
}

TEST_F(RoutesWithToken, TheApiNeedsTheBearerToken) {
  fake_.add_job(job_info("job_a", JobKind::identification, JobState::running));
  for (const httplib::Headers& headers : std::vector<httplib::Headers>{
           {}, {{"Authorization", "Bearer wrong!"}}, {{"Authorization", "bearer s3cret"}}, {{"Authorization", "s3cret"}}}) {
    const auto result = get("/v1/jobs", headers);
    const Json problem = expect_problem(result, 401, "UNAUTHORIZED", "Authorization");
    EXPECT_EQ(problem["detail"], "this server needs 'Authorization: Bearer <token>'");
    ASSERT_TRUE(result);
    EXPECT_EQ(result->get_header_value("WWW-Authenticate"), "Bearer");
  }
  expect_problem(get("/v1"), 401, "UNAUTHORIZED", "Authorization");
  expect_problem(get("/v1/no-such-route"), 401, "UNAUTHORIZED", "Authorization");  // before routing
  EXPECT_EQ(fake_.calls(), 0);
  const auto result = get("/v1/jobs", {{"Authorization", "Bearer s3cret"}});
  ASSERT_TRUE(result);
  EXPECT_EQ(result->status, 200);
  const auto posted = post("/v1/simulations", R"({"duration": 0.5})", "application/json", {{"Authorization", "Bearer s3cret"}});
  ASSERT_TRUE(posted);
  EXPECT_EQ(posted->status, 202);
}

TEST_F(RoutesWithNamedTokens, EachTokenActsForItsNameAndAnotherOwnersJobIsAMissingOne) {
  JobInfo alices = job_info("job_alice", JobKind::identification, JobState::queued);
  alices.owner = "alice";
  JobInfo bobs = job_info("job_bob", JobKind::identification, JobState::queued);
  bobs.owner = "bob";
  fake_.add_job(alices);
  fake_.add_job(bobs);
  // The token names the caller; the service is asked for that owner's only.
  Json list = json_of(get("/v1/jobs", as("alice")));
  ASSERT_EQ(list["items"].size(), 1u) << list;
  EXPECT_EQ(list["items"][0]["id"], "job_alice");
  EXPECT_EQ(list["items"][0]["owner"], "alice");
  ASSERT_FALSE(fake_.callers().empty());
  EXPECT_EQ(fake_.callers().back().owner, "alice");
  EXPECT_FALSE(fake_.callers().back().admin);
  // Bob's job answers alice exactly as a job that does not exist.
  const Json hidden = expect_problem(get("/v1/jobs/job_bob", as("alice")), 404, "NOT_FOUND", "id");
  const Json missing = expect_problem(get("/v1/jobs/job_none", as("alice")), 404, "NOT_FOUND", "id");
  EXPECT_EQ(hidden["detail"], "no job job_bob");
  EXPECT_EQ(hidden["title"], missing["title"]);
  expect_problem(client().Delete("/v1/jobs/job_bob", as("alice")), 404, "NOT_FOUND", "id");
  expect_problem(post("/v1/jobs/job_bob/cancel", "", "application/json", as("alice")), 404, "NOT_FOUND", "id");
  RawAnswer bodiless = raw("POST /v1/jobs/job_bob/cancel HTTP/1.1\r\nHost: test\r\nAuthorization: Bearer "
                           "alice-token-0123456789\r\nConnection: close\r\n\r\n");
  expect_problem(bodiless, 404, "NOT_FOUND", "id");
  EXPECT_EQ(json_of(get("/v1/jobs/job_bob", as("bob")))["state"], "queued");  // untouched
  // The admin sees both, and acts as carol.
  list = json_of(get("/v1/jobs", as("carol")));
  EXPECT_EQ(list["items"].size(), 2u) << list;
  EXPECT_TRUE(fake_.callers().back().admin);
  EXPECT_EQ(fake_.callers().back().owner, "carol");
  // The log names whom each request acted for, never the token.
  EXPECT_NE(log().find("GET /v1/jobs 200"), std::string::npos) << log();
  EXPECT_NE(log().find(" by alice\n"), std::string::npos) << log();
  EXPECT_EQ(log().find("-token-"), std::string::npos) << log();
}

TEST_F(RoutesWithNamedTokens, ASubmissionNamingAnotherOwnersDatasetIsRefusedAsIfItWereNotThere) {
  DatasetInfo bobs = dataset_info("ds_bob", 4, 9701);
  bobs.owner = "bob";
  fake_.add_dataset(bobs);
  const auto refused = post("/v1/identifications", R"({"dataset_id": "ds_bob"})", "application/json", as("alice"));
  const Json hidden = expect_problem(refused, 422, "INVALID_FIELD", "dataset_id");
  EXPECT_EQ(hidden["detail"], "no dataset ds_bob");
  expect_problem(get("/v1/datasets/ds_bob", as("alice")), 404, "NOT_FOUND", "id");
  EXPECT_TRUE(fake_.submissions().empty());
  const auto his = post("/v1/identifications", R"({"dataset_id": "ds_bob"})", "application/json", as("bob"));
  ASSERT_TRUE(his);
  EXPECT_EQ(his->status, 202) << his->body;
  EXPECT_EQ(json_of(his)["owner"], "bob");
}

TEST_F(RoutesWithNamedTokens, MetricsAreTheAdminsAndUnknownTokensAre401) {
  expect_problem(get("/metrics"), 401, "UNAUTHORIZED", "Authorization");
  expect_problem(get("/metrics", as("alice")), 403, "FORBIDDEN", "Authorization");
  const auto metrics = get("/metrics", as("carol"));
  ASSERT_TRUE(metrics);
  EXPECT_EQ(metrics->status, 200);
  for (const httplib::Headers& headers : std::vector<httplib::Headers>{
           {}, {{"Authorization", "Bearer alice-token-012345678"}}, {{"Authorization", "Bearer alice"}},
           {{"Authorization", "alice-token-0123456789"}}}) {
    expect_problem(get("/v1/jobs", headers), 401, "UNAUTHORIZED", "Authorization");
  }
}

TEST_F(RoutesWithToken, StaticFilesAreNotBehindTheTokenMetricsAre) {
  for (const char* path : {"/", "/jobs/job_0123456789abcdef", "/robots", "/robots/rb_1", "/healthz", "/openapi.json"}) {
    const auto result = get(path);
    ASSERT_TRUE(result) << path;
    EXPECT_EQ(result->status, 200) << path;
  }
  expect_problem(get("/assets/missing.js"), 404, "NOT_FOUND", "path");  // not 401
  // /metrics tells the lab's job counts, memory and request rates: behind the token like /v1.
  expect_problem(get("/metrics"), 401, "UNAUTHORIZED", "Authorization");
  const auto metrics = get("/metrics", {{"Authorization", "Bearer s3cret"}});
  ASSERT_TRUE(metrics);
  EXPECT_EQ(metrics->status, 200);
}

// A stored robot is parsed once per process: the same document, base and tip give the same parsed robot
// (one object, not a new parse); another tip or document another one; a refusal is not kept.
TEST(RobotCache, OneParsePerRobotIdBoundedAndShared) {
  RobotCache cache(3, 1u << 20);
  int loads = 0;
  const auto robot = [](const std::string& id, const std::string& tip = "") {
    RobotInfo info;
    info.id = id;
    info.name = "two";
    info.tip = tip;
    return info;
  };
  const auto document = [&loads](std::string urdf) {
    return [&loads, urdf] {
      ++loads;
      return std::optional<std::string>(urdf);
    };
  };
  const std::shared_ptr<const ParsedRobot> first = cache.get(robot("rb_1"), document(kTwoJointUrdf));
  ASSERT_TRUE(first);
  EXPECT_EQ(first->model.joint_count(), 2);
  EXPECT_EQ(cache.get(robot("rb_1"), document(kTwoJointUrdf)).get(), first.get());
  EXPECT_EQ(loads, 1);  // the document is read once, at the first use
  const std::shared_ptr<const ParsedRobot> shorter = cache.get(robot("rb_2", "l1"), document(kTwoJointUrdf));
  EXPECT_NE(shorter.get(), first.get());
  EXPECT_EQ(shorter->model.joint_count(), 1);
  // A robot without its document (deleted meanwhile): none, nothing kept.
  EXPECT_FALSE(cache.get(robot("rb_gone"), [] { return std::optional<std::string>(); }));
  // A refusal throws each time and is not kept.
  const std::string broken = std::string(kTwoJointUrdf).substr(0, 60);
  EXPECT_THROW((void)cache.get(robot("rb_broken"), document(broken)), InputError);
  EXPECT_THROW((void)cache.get(robot("rb_broken"), document(broken)), InputError);
  EXPECT_EQ(cache.size(), 2u);
  // One parsed at its upload is kept under its id: no document read.
  const auto uploaded = std::make_shared<const ParsedRobot>(parse_robot({"two", kTwoJointUrdf, "", ""}));
  cache.keep("rb_3", uploaded, std::string(kTwoJointUrdf).size());
  loads = 0;
  EXPECT_EQ(cache.get(robot("rb_3"), document(kTwoJointUrdf)).get(), uploaded.get());
  EXPECT_EQ(loads, 0);
  // Beyond its entries the least recently used goes (rb_2 here: rb_1 was used after it), and is parsed afresh.
  EXPECT_EQ(cache.get(robot("rb_1"), document(kTwoJointUrdf)).get(), first.get());
  (void)cache.get(robot("rb_4"), document(kTwoJointUrdf));
  EXPECT_EQ(cache.size(), 3u);
  EXPECT_EQ(cache.get(robot("rb_1"), document(kTwoJointUrdf)).get(), first.get());
  const std::shared_ptr<const ParsedRobot> again = cache.get(robot("rb_2", "l1"), document(kTwoJointUrdf));
  EXPECT_NE(again.get(), shorter.get());
  EXPECT_EQ(again->model.joint_count(), 1);
  // A document larger than the cache's bytes is parsed, not kept.
  RobotCache small(4, 16);
  EXPECT_TRUE(small.get(robot("rb_1"), document(kTwoJointUrdf)));
  EXPECT_EQ(small.size(), 0u);
}

TEST(RobotCache, ThreadsAskingForOneRobotShareOneModel) {
  RobotCache cache;
  RobotInfo info;
  info.id = "rb_1";
  info.name = "two";
  std::vector<std::shared_ptr<const ParsedRobot>> seen(8);
  std::vector<std::thread> threads;
  for (std::size_t i = 0; i < seen.size(); ++i) {
    threads.emplace_back([&, i] { seen[i] = cache.get(info, [] { return std::optional<std::string>(kTwoJointUrdf); }); });
  }
  for (std::thread& thread : threads) thread.join();
  for (const auto& parsed : seen) EXPECT_EQ(parsed.get(), seen.front().get());  // the first kept wins for all
  EXPECT_EQ(cache.size(), 1u);
}

// The robot fit's friction view: on a noise-free run whose torque has viscous and Coulomb friction, what the
// rigid-body model leaves of the measured torque lies on the point's law fv·q̇ + fc·sign(q̇) to 1 % wherever
// |q̇| is over 80 % of its peak. Nearer its sign changes the judge's low-pass smooths (and rings after) the
// Coulomb step: at half the peak the points are still 10 % off the law on joint 1.
TEST_F(Routes, ARobotFitShowsWhatFrictionMustExplainOnTheFittedLaw) {
  ASSERT_EQ(post("/v1/robots", kTwoJointUrdf, "application/xml")->status, 201);
  const robot::Model model = parse_robot({"two", kTwoJointUrdf, "", ""}).model;
  const robot::ParameterLayout layout;  // viscous and Coulomb
  const int n = model.joint_count();
  ASSERT_EQ(n, 2);
  Eigen::VectorXd pi = robot::standard_parameters(model, layout);
  const double fv[] = {0.8, 0.3}, fc[] = {1.5, 0.6};
  for (int k = 0; k < n; ++k) {
    pi[layout.viscous_begin(n) + k] = fv[k];
    pi[layout.coulomb_begin(n) + k] = fc[k];
  }
  const double dt = 0.002, pi2 = 2.0 * std::numbers::pi;
  const int samples = 4001;  // 8 s
  const double frequency[] = {0.5, 0.35};
  Trajectory data;
  data.t.resize(samples);
  data.q.resize(samples, n);
  data.tau.resize(samples, n);
  for (int i = 0; i < samples; ++i) {
    const double t = i * dt;
    data.t[i] = t;
    Eigen::VectorXd q(n), qd(n), qdd(n);
    for (int k = 0; k < n; ++k) {
      const double w = pi2 * frequency[k];
      q[k] = 0.8 * std::sin(w * t + k);
      qd[k] = 0.8 * w * std::cos(w * t + k);
      qdd[k] = -0.8 * w * w * std::sin(w * t + k);
    }
    data.q.row(i) = q.transpose();
    data.tau.row(i) = robot::inverse_dynamics(model, layout, pi, q, qd, qdd).transpose();
  }
  fake_.add_dataset(dataset_info("ds_run", n, samples), data);
  const std::vector<std::string> names = robot::standard_parameter_names(model, layout);
  Json point = Json::object();
  for (std::size_t i = 0; i < names.size(); ++i) point[names[i]] = pi[static_cast<Eigen::Index>(i)];
  const auto stored = [&](const std::string& id, const Json& friction, const Json& values) {
    JobInfo job = job_info(id, JobKind::robot_identification, JobState::succeeded);
    job.robot_id = "rb_1";
    job.dataset_id = "ds_run";
    job.request = Json{{"robot_id", "rb_1"}, {"dataset_id", "ds_run"}, {"friction", friction}}.dump();
    job.result = Json{{"parameters", {{"friction", friction}, {"armature", false}}},
                      {"point", values},
                      {"judge", {{"cutoff_hz", 5.0}, {"trim_seconds", 0.3}}},
                      {"filters", {{"differentiation", {{"dt", dt}}}}},
                      {"torque_joints", {"j1", "j2"}}}
                     .dump();
    fake_.add_job(job);
  };
  stored("job_friction", {"viscous", "coulomb"}, point);

  const auto answer = get("/v1/jobs/job_friction/fit?max_points=500");
  ASSERT_TRUE(answer);
  ASSERT_EQ(answer->status, 200) << answer->body;
  const Json fit = json_of(answer);
  ASSERT_TRUE(fit.contains("friction")) << fit.dump().substr(0, 300);
  const Json& friction = fit["friction"];
  EXPECT_EQ(friction["terms"], Json::array({"viscous", "coulomb"}));
  ASSERT_EQ(friction["joints"].size(), 2u);
  for (int k = 0; k < n; ++k) {
    const Json& joint = friction["joints"][static_cast<std::size_t>(k)];
    EXPECT_EQ(joint["joint"], k + 1);
    EXPECT_EQ(joint["name"], k == 0 ? "j1" : "j2");
    EXPECT_EQ(joint["law"], Json({{"fv", fv[k]}, {"fc", fc[k]}}));
    ASSERT_EQ(joint["qd"].size(), fit["t"].size());
    ASSERT_EQ(joint["torque"].size(), fit["t"].size());
    const double peak = 0.8 * pi2 * frequency[k];
    int away = 0;
    double worst = 0.0, widest = 0.0;
    for (std::size_t i = 0; i < joint["qd"].size(); ++i) {
      const double qd = joint["qd"][i].get<double>(), torque = joint["torque"][i].get<double>();
      widest = std::max(widest, std::abs(qd));
      if (std::abs(qd) < 0.8 * peak) continue;
      ++away;
      const double law = fv[k] * qd + fc[k] * (qd > 0 ? 1.0 : -1.0);
      worst = std::max(worst, std::abs(torque - law) / std::abs(law));
    }
    EXPECT_NEAR(widest, peak, 0.02 * peak) << "joint " << k + 1;  // q̇ is the joint's, in rad/s
    EXPECT_GT(away, 100) << "joint " << k + 1;
    EXPECT_LT(worst, 0.01) << "joint " << k + 1 << ": the points leave the law by " << worst;
  }

  // Without friction terms there is nothing for a law to explain: no "friction" block.
  const robot::ParameterLayout none{false, false, false, false};
  const std::vector<std::string> rigid = robot::standard_parameter_names(model, none);
  Json rigid_point = Json::object();
  for (const std::string& name : rigid) rigid_point[name] = point[name];
  stored("job_rigid", Json::array(), rigid_point);
  const auto without = get("/v1/jobs/job_rigid/fit?max_points=50");
  ASSERT_TRUE(without);
  ASSERT_EQ(without->status, 200) << without->body;
  EXPECT_FALSE(json_of(without).contains("friction"));
}

namespace {

/// A succeeded robot identification of `robot_id` whose result's point is `model`'s URDF values (viscous and
/// Coulomb friction): what a payload identification's arm_job_id names.
JobInfo arm_job(const robot::Model& model, const std::string& id, const std::string& robot_id, JobState state) {
  const robot::ParameterLayout layout;
  const Eigen::VectorXd pi = robot::standard_parameters(model, layout);
  const std::vector<std::string> names = robot::standard_parameter_names(model, layout);
  Json point = Json::object();
  for (std::size_t i = 0; i < names.size(); ++i) point[names[i]] = pi[static_cast<Eigen::Index>(i)];
  JobInfo job = job_info(id, JobKind::robot_identification, state);
  job.robot_id = robot_id;
  job.dataset_id = "ds_arm";
  if (state == JobState::succeeded) {
    job.result = Json{{"parameters", {{"friction", {"viscous", "coulomb"}}, {"armature", false}}},
                      {"point", point},
                      {"judge", {{"cutoff_hz", 5.0}, {"trim_seconds", 0.3}}},
                      {"filters", {{"differentiation", {{"dt", 0.002}}}}},
                      {"torque_joints", {"j1", "j2"}}}
                     .dump();
  }
  return job;
}

}  // namespace

TEST_F(Routes, APayloadIdentificationIsCheckedAgainstTheRobotItsRunsAndItsArm) {
  ASSERT_EQ(post("/v1/robots", kTwoJointUrdf, "application/xml")->status, 201);  // rb_1
  ASSERT_EQ(post("/v1/robots", kTwoJointUrdf, "application/xml")->status, 201);  // rb_2
  const robot::Model model = parse_robot({"two", kTwoJointUrdf, "", ""}).model;
  fake_.add_dataset(dataset_info("ds_tool", 2, 5000));
  fake_.add_dataset(dataset_info("ds_check", 2, 4000));
  fake_.add_dataset(dataset_info("ds_four", 4, 5000));
  fake_.add_dataset(dataset_info("ds_no_tau", 2, 5000, false, true));
  fake_.add_job(arm_job(model, "job_arm", "rb_1", JobState::succeeded));
  fake_.add_job(arm_job(model, "job_other_robot", "rb_2", JobState::succeeded));
  fake_.add_job(arm_job(model, "job_running", "rb_1", JobState::running));
  fake_.add_job(arm_job(model, "job_failed", "rb_1", JobState::failed));
  JobInfo design = job_info("job_design", JobKind::excitation, JobState::succeeded);
  design.robot_id = "rb_1";
  fake_.add_job(design);
  JobInfo broken = arm_job(model, "job_broken", "rb_1", JobState::succeeded);
  broken.result = R"({"point": {}})";
  fake_.add_job(broken);

  const Json request = {{"payload", true}, {"robot_id", "rb_1"}, {"dataset_ids", {"ds_tool"}},
                        {"validation_dataset_id", "ds_check"}, {"arm_job_id", "job_arm"}, {"known_mass", 1.5},
                        {"known_centre_of_mass", {0.0, 0.01, 0.05}}, {"physical", true}, {"trim", {0.2, 0.3}}, {"dt", 0.002},
                        {"comparison_cutoff", 4}, {"judge_cutoff", 3}, {"judge_trim", 0.2}, {"torque_joints", {2}}};
  const auto queued = post("/v1/identifications", request.dump());
  ASSERT_TRUE(queued);
  ASSERT_EQ(queued->status, 202) << queued->body;
  ASSERT_EQ(fake_.submissions().size(), 1u);
  EXPECT_EQ(fake_.submissions()[0].kind, JobKind::payload_identification);
  EXPECT_EQ(fake_.submissions()[0].robot_id, "rb_1");
  EXPECT_EQ(fake_.submissions()[0].dataset_id, "ds_tool");
  EXPECT_EQ(fake_.submissions()[0].validation_dataset_id, "ds_check");
  const Json job = json_of(queued);
  EXPECT_EQ(job["kind"], "payload_identification");
  const std::string self = "/v1/jobs/" + job["id"].get<std::string>();
  EXPECT_EQ(job["links"]["robot"], "/v1/robots/rb_1");
  EXPECT_EQ(job["links"]["fit"], self + "/fit");
  EXPECT_EQ(job["links"]["validation"], self + "/validation");
  EXPECT_EQ(job["links"]["urdf"], self + "/urdf");
  EXPECT_FALSE(job["links"].contains("history"));
  // The request as the runner reads it: the rules the robot identification's fields follow.
  const PayloadIdentificationSpec spec = payload_identification_from_json(request);
  EXPECT_EQ(spec.arm_job_id, "job_arm");
  EXPECT_EQ(spec.dataset_ids, std::vector<std::string>{"ds_tool"});
  EXPECT_EQ(spec.options.known_mass, 1.5);
  EXPECT_EQ(*spec.options.known_centre_of_mass, Eigen::Vector3d(0.0, 0.01, 0.05));
  EXPECT_TRUE(spec.options.physical);
  EXPECT_FALSE(payload_identification_from_json(Json{{"payload", true}, {"robot_id", "rb_1"}, {"dataset_id", "ds_tool"}})
                   .options.physical);
  EXPECT_EQ(payload_identification_from_json(Json{{"payload", true}, {"robot_id", "rb_1"}, {"dataset_id", "ds_tool"},
                                                  {"weights", "per-joint"}}).options.weighting,
            estimation::JointWeighting::per_joint);
  EXPECT_EQ(spec.options.preparation.trim_start, 0.2);
  EXPECT_EQ(spec.options.preparation.trim_end, 0.3);
  EXPECT_EQ(spec.options.preparation.uniform.dt, 0.002);
  EXPECT_EQ(spec.options.comparison_cutoff_hz, 4.0);
  EXPECT_EQ(spec.options.judge.cutoff_hz, 3.0);
  EXPECT_EQ(spec.options.judge.trim_seconds, 0.2);
  EXPECT_EQ(spec.options.torque_joints, std::vector<int>{1});
  // Without an arm the URDF's values are the arm.
  const auto plain = post("/v1/identifications", R"({"payload": true, "robot_id": "rb_1", "dataset_id": "ds_tool"})");
  ASSERT_TRUE(plain);
  EXPECT_EQ(plain->status, 202) << plain->body;

  const auto refused = [&](Json body, const std::string& field, const std::string& says) {
    const Json problem = expect_problem(post("/v1/identifications", body.dump()), 422, "INVALID_FIELD", field);
    EXPECT_NE(problem["detail"].get<std::string>().find(says), std::string::npos) << problem;
  };
  const Json base = {{"payload", true}, {"robot_id", "rb_1"}, {"dataset_id", "ds_tool"}};
  const auto with = [&](const char* key, Json value) {
    Json body = base;
    body[key] = std::move(value);
    return body;
  };
  refused({{"payload", true}, {"dataset_id", "ds_tool"}}, "robot_id", "missing robot_id");
  refused({{"payload", true}, {"robot_id", "rb_1"}}, "dataset_id", "missing dataset_id");
  refused(with("payload", false), "payload", "payload must be true");
  refused(with("robot_id", "rb_9"), "robot_id", "rb_9");
  refused(with("dataset_id", "ds_four"), "dataset_id", "4 joints, the robot two has 2");
  refused(with("dataset_id", "ds_no_tau"), "dataset_id", "no tau");
  refused(with("validation_dataset_id", "ds_nothing"), "validation_dataset_id", "no dataset");
  refused(with("known_mass", 0), "known_mass", "known_mass");
  refused(with("known_mass", -1), "known_mass", "known_mass");
  refused(with("known_centre_of_mass", {1, 2}), "known_centre_of_mass", "[x, y, z]");
  refused(with("torque_joints", {3}), "torque_joints", "has 2");
  refused(with("physical", "yes"), "physical", "true or false");
  refused(with("comparison_cutoff", "auto"), "comparison_cutoff", "comparison_cutoff");
  refused(with("friction", {"viscous"}), "friction", "arm_job_id");
  refused(with("ridge", 0), "ridge", "arm's identification");
  refused(with("weights", "inverse-variance"), "weights", "unit");
  refused(with("free", {"m2"}), "free", "paper's preset");
  refused(with("known_mas", 1), "known_mas", "did you mean");
  refused(with("arm_job_id", ""), "arm_job_id", "empty");
  refused(with("arm_job_id", "job_nothing"), "arm_job_id", "no job job_nothing");
  refused(with("arm_job_id", "job_design"), "arm_job_id", "is an excitation, not a robot_identification");
  refused(with("arm_job_id", "job_other_robot"), "arm_job_id", "identified robot rb_2, not rb_1");
  refused(with("arm_job_id", "job_running"), "arm_job_id", "is running: submit the payload identification once");
  refused(with("arm_job_id", "job_failed"), "arm_job_id", "failed: it has no arm to use");
  refused(with("arm_job_id", "job_broken"), "arm_job_id", "no usable result");
  EXPECT_EQ(fake_.submissions().size(), 2u);  // nothing more was queued
}

TEST_F(Routes, APayloadJobsViewsShowTheTorqueWithAndWithoutItAndItsUrdf) {
  ASSERT_EQ(post("/v1/robots?name=arm", kTwoJointUrdf, "application/xml")->status, 201);
  const robot::Model model = parse_robot({"two", kTwoJointUrdf, "", ""}).model;
  const int n = model.joint_count();
  const robot::ArmParameters arm = urdf_arm(model);
  const robot::InertialParameters tool =
      robot::InertialParameters::from_centre_of_mass(0.8, Eigen::Vector3d(0.02, 0.01, 0.04),
                                                     Eigen::Matrix3d(Eigen::Vector3d(2e-3, 3e-3, 1e-3).asDiagonal()));
  const Eigen::VectorXd loaded = robot::with_payload(model, arm, tool.vector());
  const double dt = 0.002, pi2 = 2.0 * std::numbers::pi;
  const int samples = 4001;
  Trajectory data;
  data.t.resize(samples);
  data.q.resize(samples, n);
  data.tau.resize(samples, n);
  for (int i = 0; i < samples; ++i) {
    const double t = i * dt;
    data.t[i] = t;
    Eigen::VectorXd q(n), qd(n), qdd(n);
    for (int k = 0; k < n; ++k) {
      const double w = pi2 * (0.4 + 0.15 * k);
      q[k] = 0.8 * std::sin(w * t + k);
      qd[k] = 0.8 * w * std::cos(w * t + k);
      qdd[k] = -0.8 * w * w * std::sin(w * t + k);
    }
    data.q.row(i) = q.transpose();
    data.tau.row(i) = robot::inverse_dynamics(model, arm.layout, loaded, q, qd, qdd).transpose();
  }
  fake_.add_dataset(dataset_info("ds_tool", n, samples), data);
  const auto stored = [&](const std::string& id, bool detected) {
    Json parameters = Json::array();
    for (std::size_t i = 0; i < 10; ++i) {
      parameters.push_back({{"name", robot::PayloadResult::names()[i]}, {"estimate", tool.vector()[static_cast<Eigen::Index>(i)]}});
    }
    JobInfo job = job_info(id, JobKind::payload_identification, JobState::succeeded);
    job.robot_id = "rb_1";
    job.dataset_id = "ds_tool";
    job.validation_dataset_id = "ds_tool";
    job.request = Json{{"payload", true}, {"robot_id", "rb_1"}, {"dataset_id", "ds_tool"}}.dump();
    job.result = Json{{"detected", detected}, {"mass", 0.8}, {"parameters", parameters}, {"torque_joints", {"j1", "j2"}},
                      {"arm_point", Json::parse(arm_point_json(model, arm).dump())}}
                     .dump();
    fake_.add_job(job);
  };
  stored("job_payload", true);
  stored("job_none", false);

  for (const char* view : {"fit", "validation"}) {
    const auto answer = get(std::string("/v1/jobs/job_payload/") + view + "?max_points=300");
    ASSERT_TRUE(answer);
    ASSERT_EQ(answer->status, 200) << answer->body;
    const Json fit = json_of(answer);
    ASSERT_EQ(fit["joints"].size(), 2u);
    for (const Json& joint : fit["joints"]) {
      EXPECT_EQ(joint["arm_only"].size(), fit["t"].size());
      EXPECT_EQ(joint["model"].size(), fit["t"].size());
    }
    // The true payload predicts the run (the judge's states and low-pass on both sides); the arm alone does not.
    const double with_payload = fit["overall_relative_error"].get<double>();
    const double arm_only = fit["arm_only"]["overall_relative_error"].get<double>();
    EXPECT_LT(with_payload, 0.01) << view;
    EXPECT_GT(arm_only, 5 * with_payload) << view;
    EXPECT_EQ(fit["judge"]["cutoff_hz"], 5.0);
  }
  const auto urdf = get("/v1/jobs/job_payload/urdf");
  ASSERT_TRUE(urdf);
  ASSERT_EQ(urdf->status, 200) << urdf->body;
  EXPECT_EQ(urdf->get_header_value("Content-Disposition"), "attachment; filename=\"arm-payload.urdf\"");
  EXPECT_NE(urdf->body.find("<link name=\"manipid_payload\">"), std::string::npos) << urdf->body;
  EXPECT_NE(urdf->body.find("job job_payload"), std::string::npos) << urdf->body;
  // The document with the payload mounted predicts the loaded arm.
  const robot::Model mounted = parse_robot({"two", urdf->body, "", ""}).model;
  EXPECT_LT((robot::standard_parameters(mounted, arm.layout) - loaded).norm(), 1e-9 * loaded.norm());
  const Json none = expect_problem(get("/v1/jobs/job_none/urdf"), 409, "CONFLICT", "id");
  EXPECT_NE(none["detail"].get<std::string>().find("no payload"), std::string::npos) << none;
}

TEST(RobotResultDecoder, ReadsAStoredResultAndNamesWhatIsMissing) {
  const robot::Model model = parse_robot({"two", kTwoJointUrdf, "", ""}).model;
  const robot::ParameterLayout layout{true, false, false, false};  // viscous only
  const std::vector<std::string> names = robot::standard_parameter_names(model, layout);
  Json point = Json::object(), prior = Json::object();
  for (std::size_t i = 0; i < names.size(); ++i) {
    point[names[i]] = 0.5 + static_cast<double>(i);
    prior[names[i]] = -1.0 - static_cast<double>(i);
  }
  const Json stored = {{"parameters", {{"friction", {"viscous"}}, {"armature", false}}},
                       {"point", point},
                       {"prior", prior},
                       {"judge", {{"cutoff_hz", 4.0}, {"trim_seconds", 0.25}}},
                       {"filters", {{"differentiation", {{"dt", 0.002}}}}},
                       {"torque_joints", {"j2"}}};
  const RobotResult result = decode_robot_result(model, stored);
  EXPECT_TRUE(result.layout.viscous);
  EXPECT_FALSE(result.layout.coulomb);
  ASSERT_EQ(result.point.size(), static_cast<Eigen::Index>(names.size()));
  EXPECT_EQ(result.point[1], 1.5);
  EXPECT_EQ(result.prior[1], -2.0);
  EXPECT_EQ(result.judge.cutoff_hz, 4.0);
  EXPECT_EQ(result.judge.trim_seconds, 0.25);
  EXPECT_EQ(result.dt, 0.002);
  EXPECT_EQ(result.torque_joints, std::vector<int>{1});
  // Without a prior: zeros.
  Json without_prior = stored;
  without_prior.erase("prior");
  EXPECT_TRUE(decode_robot_result(model, without_prior).prior.isZero());
  // What is missing or of the wrong type is named, as InputError("result").
  const auto refused = [&](Json broken, const std::string& says) {
    try {
      (void)decode_robot_result(model, broken);
      ADD_FAILURE() << "accepted " << broken.dump();
    } catch (const InputError& error) {
      EXPECT_EQ(error.field(), "result");
      EXPECT_NE(std::string(error.what()).find(says), std::string::npos) << error.what();
    }
  };
  Json no_judge = stored;
  no_judge.erase("judge");
  refused(no_judge, "judge");
  Json short_point = stored;
  short_point["point"].erase(names.back());
  refused(short_point, "point." + names.back());
  Json text_dt = stored;
  text_dt["filters"]["differentiation"]["dt"] = "0.002";
  refused(text_dt, "filters.differentiation.dt");
  Json stranger = stored;
  stranger["torque_joints"] = {"j9"};
  refused(stranger, "a joint the robot does not have");
  Json armature_text = stored;
  armature_text["parameters"]["armature"] = "no";
  refused(armature_text, "parameters");
  refused(Json::array(), "not an object");
}

TEST_F(RoutesWithToken, BodilessCancelNeedsTheTokenToo) {
  fake_.add_job(job_info("job_a", JobKind::identification, JobState::running));
  RawAnswer answer = raw("POST /v1/jobs/job_a/cancel HTTP/1.1\r\nHost: test\r\nConnection: close\r\n\r\n");
  expect_problem(answer, 401, "UNAUTHORIZED", "Authorization");
  EXPECT_EQ(fake_.calls(), 0);
  answer = raw("POST /v1/jobs/job_a/cancel HTTP/1.1\r\nHost: test\r\nAuthorization: Bearer s3cret\r\nConnection: close\r\n\r\n");
  EXPECT_EQ(answer.status, 200) << answer.head << answer.body;
  EXPECT_EQ(Json::parse(answer.body)["state"], "cancelled");
}

}  // namespace
}  // namespace manipid::api
