// job_memory_test.cpp — a job's shape from its request (api/job_memory.h): samples, joints and
// the work for each kind of job, with the field that sets its size; the estimate grows with
// each; a budget it exceeds is refused naming that field.
#include "manipid/api/job_memory.h"

#include "manipid/core/errors.h"

#include <gtest/gtest.h>

#include <string>

namespace manipid::api {
namespace {

using nlohmann::json;

std::optional<DatasetInfo> dataset(const std::string& id) {
  DatasetInfo info;
  info.id = id;
  info.joints = id == "ds_7" ? 7 : 4;
  info.samples = 10001;
  info.dt = 0.001;
  if (id == "ds_none") return std::nullopt;
  return info;
}

std::optional<int> robot(const std::string& id) {
  if (id == "rb_7") return 7;
  if (id == "rb_100") return 100;
  return std::nullopt;
}

JobShape shape(JobKind kind, const json& request) { return job_shape(kind, request, dataset, robot); }

TEST(JobShape, SimulationCountsItsSamplesJointsAndParameters) {
  const JobShape simulated = shape(JobKind::simulation, {{"duration", 3600}});
  EXPECT_EQ(simulated.samples, 3'600'001);
  EXPECT_EQ(simulated.joints, 4);
  EXPECT_EQ(simulated.work, "simulation");
  EXPECT_EQ(simulated.field, "duration");
  EXPECT_EQ(shape(JobKind::simulation, {{"duration", 10}, {"dt", 1e-4}}).samples, 100'001);
}

TEST(JobShape, IdentificationOfADatasetOrASimulation) {
  const JobShape stored = shape(JobKind::identification, {{"dataset_id", "ds_4"}});
  EXPECT_EQ(stored.samples, 10001);
  EXPECT_EQ(stored.field, "dataset_id");
  // The closed loop simulated at every evaluation holds more per sample than input-error.
  const JobShape two_stage = shape(JobKind::identification, {{"dataset_id", "ds_4"}, {"method", "two-stage"}});
  EXPECT_EQ(two_stage.work, "two-stage identification");
  EXPECT_GT(two_stage.bytes_per_sample_joint, stored.bytes_per_sample_joint);
  const JobShape simulated = shape(JobKind::identification, {{"simulation", {{"duration", 20}}}});
  EXPECT_EQ(simulated.samples, 20001);
  EXPECT_EQ(simulated.field, "simulation");
  EXPECT_EQ(shape(JobKind::identification, {{"dataset_id", "ds_none"}}).samples, 0);
}

TEST(JobShape, RobotIdentificationCountsBothDatasetsAndItsLayout) {
  const JobShape both = shape(JobKind::robot_identification, {{"robot_id", "rb_7"},
                                                              {"dataset_id", "ds_7"},
                                                              {"validation_dataset_id", "ds_7"},
                                                              {"friction", {"viscous", "coulomb", "offset"}}});
  EXPECT_EQ(both.samples, 20002);
  EXPECT_EQ(both.joints, 7);
  EXPECT_EQ(both.work, "robot identification");
  EXPECT_EQ(both.field, "dataset_id");
  // Resampled onto a finer grid: ten times the samples, and "dt" is what sets them.
  const JobShape finer = shape(JobKind::robot_identification, {{"robot_id", "rb_7"}, {"dataset_id", "ds_7"}, {"dt", 1e-4}});
  EXPECT_EQ(finer.samples, 100001);
  EXPECT_EQ(finer.field, "dt");
}

TEST(JobShape, PayloadIdentificationCountsItsRunsAndHoldsLessThanTheArms) {
  const json request = {{"payload", true}, {"robot_id", "rb_7"}, {"dataset_ids", {"ds_7", "ds_7"}},
                        {"validation_dataset_id", "ds_7"}, {"arm_job_id", "job_1"}};
  const JobShape payload = shape(JobKind::payload_identification, request);
  EXPECT_EQ(payload.samples, 30003);
  EXPECT_EQ(payload.joints, 7);
  EXPECT_EQ(payload.work, "payload identification");
  EXPECT_EQ(payload.field, "dataset_id");
  // Body n's ten columns, not the arm's every one: less per sample than the arm's identification.
  const JobShape arm = shape(JobKind::robot_identification, {{"robot_id", "rb_7"}, {"dataset_id", "ds_7"}});
  EXPECT_LT(payload.bytes_per_sample_joint, arm.bytes_per_sample_joint);
  json finer = request;
  finer["dt"] = 1e-4;
  EXPECT_EQ(shape(JobKind::payload_identification, finer).field, "dt");
  EXPECT_THROW(shape(JobKind::payload_identification, {{"robot_id", "rb_7"}, {"dataset_id", "ds_7"}}), InputError);
}

TEST(JobShape, ExcitationCountsItsPeriodsAtItsStep) {
  const JobShape excitation = shape(JobKind::excitation, {{"robot_id", "rb_7"}, {"period", 10}, {"duration", 30}});
  EXPECT_EQ(excitation.samples, 30001);
  EXPECT_EQ(excitation.joints, 7);
  EXPECT_EQ(excitation.field, "duration");
  // Its criterion's regressor: N = 200 instants (5 harmonics) × 7 joints × 84 columns (10 per link,
  // viscous and Coulomb per joint) four times (Y, Y_b, and for the SVD a scaled copy and its own), and
  // four 84² matrices.
  EXPECT_DOUBLE_EQ(excitation.extra_bytes, 8.0 * (4.0 * 200 * 7 * 84 + 4.0 * 84 * 84));
}

TEST(JobMemory, AnExcitationOfManyJointsAndHarmonicsCountsItsCriterion) {
  // 100 joints, 20 harmonics: the regressor alone is 800 × 100 × 1200 doubles (768 MB); it peaked at
  // 3.0 GB while the per-sample rule said 31 MiB. Now estimated near what it peaked at, and refused at the
  // door under a 1 GiB budget, naming harmonics.
  const JobShape wide = shape(JobKind::excitation, {{"robot_id", "rb_100"}, {"harmonics", 20}});
  EXPECT_GT(job_memory_bytes(wide), 2.8e9);
  EXPECT_LT(job_memory_bytes(wide), 3.4e9);
  try {
    check_job_memory(wide, std::size_t{1} << 30);
    FAIL() << "no error";
  } catch (const InputError& error) {
    EXPECT_EQ(error.field(), "harmonics");
    EXPECT_NE(std::string(error.what()).find("800 instants x 100 joints x 1200 columns"), std::string::npos) << error.what();
  }
}

TEST(JobMemory, GrowsWithSamplesJointsAndParametersAndIsRefusedBeyondTheBudget) {
  const JobShape base{100000, 4, 160.0, "simulation", "duration"};
  const std::size_t bytes = job_memory_bytes(base);
  EXPECT_LT(bytes, job_memory_bytes({200000, 4, 160.0, "simulation", "duration"}));
  EXPECT_LT(bytes, job_memory_bytes({100000, 7, 160.0, "simulation", "duration"}));
  // The part that grows: samples × joints × bytes each.
  const std::size_t fixed = job_memory_bytes({0, 4, 160.0, "simulation", "duration"});
  EXPECT_EQ(bytes - fixed, 100000u * 4u * 160u);
  EXPECT_NO_THROW(check_job_memory(base, bytes));
  try {
    check_job_memory(base, bytes - 1);
    FAIL() << "no error";
  } catch (const InputError& error) {
    EXPECT_EQ(error.field(), "duration");
    EXPECT_NE(std::string(error.what()).find("--job-memory"), std::string::npos) << error.what();
    EXPECT_NE(std::string(error.what()).find("this simulation would hold about"), std::string::npos) << error.what();
    EXPECT_NE(std::string(error.what()).find("100000 samples of 4 joints"), std::string::npos) << error.what();
  }
}

TEST(JobMemory, BytesAreDescribedInMiBAndGiB) {
  EXPECT_EQ(describe_bytes(64u << 20), "64 MiB");
  EXPECT_EQ(describe_bytes(std::size_t{3} << 29), "1.5 GiB");
  EXPECT_EQ(describe_bytes(10), "1 MiB");
}

}  // namespace
}  // namespace manipid::api
