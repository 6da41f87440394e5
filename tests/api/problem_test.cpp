// problem_test.cpp — the error table (api/problem.h): status, code, title and type of every
// kind, the problem+json shape, and the job state/kind names of records.h.
#include "manipid/api/problem.h"
#include "manipid/api/records.h"

#include <gtest/gtest.h>

#include <set>
#include <string>
#include <vector>

namespace manipid::api {
namespace {

struct ExpectedRow {
  ProblemKind kind;
  int status;
  const char* code;
};

const std::vector<ExpectedRow>& table() {
  static const std::vector<ExpectedRow> rows = {
      {ProblemKind::malformed_body, 400, "MALFORMED_BODY"},
      {ProblemKind::invalid_field, 422, "INVALID_FIELD"},
      {ProblemKind::unsupported_media, 415, "UNSUPPORTED_MEDIA"},
      {ProblemKind::length_required, 411, "LENGTH_REQUIRED"},
      {ProblemKind::payload_too_large, 413, "PAYLOAD_TOO_LARGE"},
      {ProblemKind::uri_too_long, 414, "URI_TOO_LONG"},
      {ProblemKind::unauthorized, 401, "UNAUTHORIZED"},
      {ProblemKind::not_found, 404, "NOT_FOUND"},
      {ProblemKind::method_not_allowed, 405, "METHOD_NOT_ALLOWED"},
      {ProblemKind::conflict, 409, "CONFLICT"},
      {ProblemKind::idempotency_mismatch, 422, "IDEMPOTENCY_MISMATCH"},
      {ProblemKind::queue_full, 429, "QUEUE_FULL"},
      {ProblemKind::shutting_down, 503, "SHUTTING_DOWN"},
      {ProblemKind::insufficient_storage, 507, "INSUFFICIENT_STORAGE"},
      {ProblemKind::memory_busy, 503, "MEMORY_BUSY"},
      {ProblemKind::store_unavailable, 503, "STORE_UNAVAILABLE"},
      {ProblemKind::uploads_busy, 503, "UPLOADS_BUSY"},
      {ProblemKind::internal, 500, "INTERNAL"},
      {ProblemKind::job_failed, 500, "JOB_FAILED"},
      {ProblemKind::not_computable, 422, "NOT_COMPUTABLE"},
      {ProblemKind::worker_lost, 500, "WORKER_LOST"},
      {ProblemKind::forbidden, 403, "FORBIDDEN"},
  };
  return rows;
}

TEST(ProblemTable, EveryKindHasItsStatusCodeAndTitle) {
  std::set<std::string> codes, titles;
  for (const ExpectedRow& row : table()) {
    SCOPED_TRACE(row.code);
    EXPECT_EQ(status_of(row.kind), row.status);
    EXPECT_STREQ(code_of(row.kind), row.code);
    const std::string title = title_of(row.kind);
    EXPECT_FALSE(title.empty());
    EXPECT_TRUE(codes.insert(row.code).second) << "duplicate code";
    EXPECT_TRUE(titles.insert(title).second) << "duplicate title";
  }
  EXPECT_STREQ(title_of(ProblemKind::invalid_field), "A field of the request is invalid");
}

TEST(ProblemTable, JsonHasTheRfc9457MembersForEveryKind) {
  for (const ExpectedRow& row : table()) {
    SCOPED_TRACE(row.code);
    const nlohmann::json body = problem_to_json(Problem{row.kind, "something went wrong", ""});
    EXPECT_EQ(body.size(), 5u) << body.dump();
    EXPECT_EQ(body.at("status"), row.status);
    EXPECT_EQ(body.at("code"), row.code);
    EXPECT_EQ(body.at("title"), title_of(row.kind));
    EXPECT_EQ(body.at("detail"), "something went wrong");
    EXPECT_FALSE(body.contains("field"));
    EXPECT_FALSE(body.contains("instance"));
  }
}

TEST(ProblemTable, TypeIsTheCodeInKebabCase) {
  EXPECT_EQ(problem_to_json(Problem{ProblemKind::invalid_field, "x", ""}).at("type"), "/problems/invalid-field");
  EXPECT_EQ(problem_to_json(Problem{ProblemKind::idempotency_mismatch, "x", ""}).at("type"),
            "/problems/idempotency-mismatch");
  EXPECT_EQ(problem_to_json(Problem{ProblemKind::internal, "x", ""}).at("type"), "/problems/internal");
  EXPECT_EQ(problem_to_json(Problem{ProblemKind::payload_too_large, "x", ""}).at("type"), "/problems/payload-too-large");
}

TEST(ProblemTable, FieldAndInstanceAppearOnlyWhenGiven) {
  const nlohmann::json body =
      problem_to_json(Problem{ProblemKind::invalid_field, "initial.m2 must not be negative, got -1", "initial.m2"},
                      "/v1/jobs");
  EXPECT_EQ(body.size(), 7u);
  EXPECT_EQ(body.at("field"), "initial.m2");
  EXPECT_EQ(body.at("instance"), "/v1/jobs");
  EXPECT_EQ(body.at("status"), 422);

  const nlohmann::json without = problem_to_json(Problem{ProblemKind::not_found, "no dataset ds_1", ""}, "");
  EXPECT_FALSE(without.contains("field"));
  EXPECT_FALSE(without.contains("instance"));
}

TEST(ProblemTable, EmptyDetailFallsBackToTheTitle) {
  const nlohmann::json body = problem_to_json(Problem{ProblemKind::queue_full, "", ""});
  EXPECT_EQ(body.at("detail"), title_of(ProblemKind::queue_full));
}

TEST(ProblemTable, InvalidUtf8InUserTextStillSerialises) {
  // A CSV header can carry any bytes; the error answer quoting it must still be valid JSON.
  const std::string bad = "missing column q\xff\xfe";
  const nlohmann::json body = problem_to_json(Problem{ProblemKind::invalid_field, bad, "q\xff"}, "/v1/\xc3");
  std::string text;
  ASSERT_NO_THROW(text = body.dump());
  EXPECT_EQ(body.at("detail"), "missing column q\xEF\xBF\xBD\xEF\xBF\xBD");
  EXPECT_EQ(body.at("field"), "q\xEF\xBF\xBD");
  EXPECT_EQ(body.at("instance"), "/v1/\xEF\xBF\xBD");
  // Valid multi-byte text passes unchanged.
  const nlohmann::json good = problem_to_json(Problem{ProblemKind::invalid_field, "Ωg ≤ π", ""});
  EXPECT_EQ(good.at("detail"), "Ωg ≤ π");
}

TEST(ProblemTable, LongDetailsAreCutAtACharacterBoundary) {
  // Whatever a message builder quoted, a detail stays a sentence: at most 400 bytes.
  std::string accents;
  for (int i = 0; i < 500; ++i) accents += "\xC3\xA9";  // é, two bytes each
  for (const std::string& detail : {std::string(1000, 'a'), accents}) {
    const nlohmann::json body = problem_to_json(Problem{ProblemKind::invalid_field, detail, "f"});
    const std::string text = body.at("detail").get<std::string>();
    EXPECT_LE(text.size(), 400u);
    EXPECT_EQ(text.substr(text.size() - 3), "...");
    EXPECT_EQ(text.substr(0, 10), detail.substr(0, 10));
    EXPECT_NO_THROW(body.dump());  // still valid UTF-8: not cut inside a character
  }
  const std::string short_detail = "dt must be positive";
  EXPECT_EQ(problem_to_json(Problem{ProblemKind::invalid_field, short_detail, "dt"}).at("detail"), short_detail);
}

TEST(ProblemTable, OutOfRangeKindIsInternal) {
  const auto unknown = static_cast<ProblemKind>(999);
  EXPECT_EQ(status_of(unknown), 500);
  EXPECT_STREQ(code_of(unknown), "INTERNAL");
}

TEST(ProblemFrom, InputErrorBecomesInvalidFieldWithItsField) {
  const Problem problem = problem_from(InputError("q3", "q3 is NaN at sample 4"));
  EXPECT_EQ(problem.kind, ProblemKind::invalid_field);
  EXPECT_EQ(problem.detail, "q3 is NaN at sample 4");
  EXPECT_EQ(problem.field, "q3");
  const nlohmann::json body = problem_to_json(problem);
  EXPECT_EQ(body.at("status"), 422);
  EXPECT_EQ(body.at("field"), "q3");
}

TEST(ProblemFrom, ApiErrorCarriesItsProblem) {
  try {
    throw ApiError(ProblemKind::conflict, "job job_1 is running", "id");
  } catch (const ApiError& error) {
    EXPECT_EQ(error.problem().kind, ProblemKind::conflict);
    EXPECT_EQ(error.problem().detail, "job job_1 is running");
    EXPECT_EQ(error.problem().field, "id");
    EXPECT_STREQ(error.what(), "job job_1 is running");
  }
}

TEST(Records, JobStatesRoundTrip) {
  const std::vector<std::pair<JobState, const char*>> states = {{JobState::queued, "queued"},
                                                                {JobState::running, "running"},
                                                                {JobState::succeeded, "succeeded"},
                                                                {JobState::failed, "failed"},
                                                                {JobState::cancelled, "cancelled"}};
  for (const auto& [state, name] : states) {
    EXPECT_STREQ(to_string(state), name);
    EXPECT_EQ(parse_job_state(name), state);
  }
  EXPECT_FALSE(parse_job_state("Queued"));
  EXPECT_FALSE(parse_job_state("canceled"));
  EXPECT_FALSE(parse_job_state(""));
  EXPECT_FALSE(parse_job_state(" queued"));
  EXPECT_TRUE(is_terminal(JobState::cancelled));
  EXPECT_FALSE(is_terminal(JobState::running));
}

TEST(Records, JobKindsRoundTrip) {
  EXPECT_STREQ(to_string(JobKind::simulation), "simulation");
  EXPECT_STREQ(to_string(JobKind::identification), "identification");
  EXPECT_EQ(parse_job_kind("simulation"), JobKind::simulation);
  EXPECT_EQ(parse_job_kind("identification"), JobKind::identification);
  EXPECT_STREQ(to_string(JobKind::robot_identification), "robot_identification");
  EXPECT_EQ(parse_job_kind("robot_identification"), JobKind::robot_identification);
  for (const JobKind kind : kJobKinds) EXPECT_EQ(parse_job_kind(to_string(kind)), kind);
  EXPECT_FALSE(parse_job_kind("identify"));
  EXPECT_FALSE(parse_job_kind(""));
}

}  // namespace
}  // namespace manipid::api
