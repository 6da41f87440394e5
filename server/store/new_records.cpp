// new_records.cpp — the descriptions of new datasets, robots and jobs (see new_records.h).
#include "store/new_records.h"

#include "store/encoding.h"

namespace manipid::server::store {

api::DatasetInfo describe_dataset(const std::string& owner, const std::string& name, const Trajectory& data,
                                  const std::string& source_job) {
  check_dataset_shape(data);
  api::DatasetInfo dataset;
  dataset.owner = owner;
  dataset.name = name;
  dataset.source_job = source_job;
  dataset.joints = data.joint_count();
  dataset.samples = data.samples();
  dataset.dt = data.sample_period();  // uniform: t[1] − t[0]; jittery: the median step
  dataset.uniform = data.is_uniform();
  dataset.has_torque = data.has_torque();
  dataset.has_reference = data.has_reference();
  dataset.has_rates = data.has_rates();
  dataset.has_accelerations = data.has_accelerations();
  return dataset;
}

api::RobotInfo describe_robot(const NewRobot& robot) {
  api::RobotInfo described;
  described.name = robot.name;
  described.base = robot.base;
  described.tip = robot.tip;
  described.joints = robot.joints;
  described.summary = robot.summary;
  described.owner = robot.owner;
  return described;
}

api::JobInfo describe_job(const NewJob& job) {
  api::JobInfo described;
  described.kind = job.kind;
  described.state = api::JobState::queued;
  described.request = job.request;
  described.dataset_id = job.dataset_id;
  described.robot_id = job.robot_id;
  described.validation_dataset_id = job.validation_dataset_id;
  described.owner = job.owner;
  return described;
}

}  // namespace manipid::server::store
