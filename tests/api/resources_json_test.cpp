// resources_json_test.cpp — a job on the wire (api/resources_json.h: job_to_text): the stored
// request and result spliced in as valid JSON, the bytes a parse-and-dump gives, non-JSON text as
// a string, and the members each state and kind shows.
#include "manipid/api/resources_json.h"

#include <gtest/gtest.h>

#include <string>

namespace manipid::api {
namespace {

using OrderedJson = nlohmann::ordered_json;

JobInfo finished_identification() {
  JobInfo job;
  job.id = "job_0123456789abcdef";
  job.kind = JobKind::identification;
  job.state = JobState::succeeded;
  job.created_at = "2026-11-26T08:00:00.000Z";
  job.started_at = "2026-11-26T08:00:00.100Z";
  job.finished_at = "2026-11-26T08:00:00.200Z";
  job.dataset_id = "ds_1";
  job.evaluations = 15;
  job.best_cost = 0.0209293;
  job.attempts = 1;
  job.worker = "host:12:0";
  // As the runner stores them: compact dump() text, key order kept, numbers as dump() writes them.
  job.request = OrderedJson{{"dataset_id", "ds_1"}, {"half_length", 100}, {"band", 0.2}, {"name", "a \"quoted\" \u00e9"}}.dump();
  job.result = OrderedJson{{"final_cost", 0.020929312345678912}, {"estimates", {{"m1", 1e-7}, {"m2", -3.5e300}}},
                    {"warnings", OrderedJson::array()}, {"nested", {{"list", {1, 2.5, nullptr, true}}}}}
                   .dump();
  return job;
}

TEST(JobText, IsValidJsonWhoseDumpIsTheSameBytes) {
  const JobInfo job = finished_identification();
  const std::string text = job_to_text(job);
  const OrderedJson parsed = OrderedJson::parse(text);  // throws on a bad splice
  EXPECT_EQ(parsed.dump(), text);
  EXPECT_EQ(parsed["request"], OrderedJson::parse(job.request));
  EXPECT_EQ(parsed["result"], OrderedJson::parse(job.result));
  EXPECT_EQ(parsed["result"]["estimates"]["m2"].get<double>(), -3.5e300);
  EXPECT_EQ(parsed["progress"]["best_cost"].get<double>(), 0.0209293);
  EXPECT_FALSE(parsed.contains("error"));
  EXPECT_TRUE(parsed["worker"].is_null());  // shown only while running
  // The members in the documented order.
  std::string order;
  for (const auto& [key, value] : parsed.items()) order += key + " ";
  EXPECT_EQ(order,
            "id kind state created_at owner started_at finished_at attempts worker dataset_id robot_id "
            "validation_dataset_id cancel_requested progress request result links ");
  EXPECT_EQ(parsed["links"]["history"], "/v1/jobs/job_0123456789abcdef/history");
  EXPECT_EQ(parsed["links"]["dataset"], "/v1/datasets/ds_1");
}

TEST(JobText, AListItemHasEverythingButTheRequest) {
  const JobInfo job = finished_identification();
  OrderedJson whole = OrderedJson::parse(job_to_text(job));
  const OrderedJson item = OrderedJson::parse(job_to_text(job, JobText::without_request));
  whole.erase("request");
  EXPECT_EQ(item, whole);
}

TEST(JobText, StoredTextThatIsNotJsonGoesOutAsAString) {
  JobInfo job = finished_identification();
  job.result = "{\"final_cost\": 1,";  // cut short: never written by manipid
  job.error = "plain words";
  job.request.clear();
  const OrderedJson parsed = OrderedJson::parse(job_to_text(job));
  EXPECT_EQ(parsed["result"], "{\"final_cost\": 1,");
  EXPECT_EQ(parsed["error"], "plain words");
  EXPECT_EQ(parsed["request"], "");
}

TEST(JobText, ARunningJobShowsItsWorkerAndNoResult) {
  JobInfo job = finished_identification();
  job.state = JobState::running;
  job.finished_at.clear();
  job.result.clear();
  job.best_cost.reset();
  const OrderedJson parsed = OrderedJson::parse(job_to_text(job));
  EXPECT_EQ(parsed["worker"], "host:12:0");
  EXPECT_TRUE(parsed["finished_at"].is_null());
  EXPECT_TRUE(parsed["progress"]["best_cost"].is_null());
  EXPECT_FALSE(parsed.contains("result"));
}

TEST(JobText, ARobotIdentificationLinksItsRobotAndUrdfNotAHistory) {
  JobInfo job = finished_identification();
  job.kind = JobKind::robot_identification;
  job.robot_id = "rb_1";
  job.validation_dataset_id = "ds_2";
  const OrderedJson parsed = OrderedJson::parse(job_to_text(job));
  EXPECT_EQ(parsed["kind"], "robot_identification");
  const OrderedJson& links = parsed["links"];
  EXPECT_FALSE(links.contains("history"));
  EXPECT_EQ(links["fit"], "/v1/jobs/job_0123456789abcdef/fit");
  EXPECT_EQ(links["robot"], "/v1/robots/rb_1");
  EXPECT_EQ(links["urdf"], "/v1/jobs/job_0123456789abcdef/urdf");
  EXPECT_EQ(links["validation"], "/v1/jobs/job_0123456789abcdef/validation");
  EXPECT_EQ(links["validation_dataset"], "/v1/datasets/ds_2");
}

}  // namespace
}  // namespace manipid::api
