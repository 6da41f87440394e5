// new_records.h — the description a new dataset, robot or job is stored with, the same in every
// backend; each backend adds the id and time stamp it draws inside its own transaction.
#pragma once

#include "store/store.h"

#include "manipid/api/records.h"
#include "manipid/core/signal/trajectory.h"

#include <string>

namespace manipid::server::store {

/// `owner`'s dataset of `data`: its size, sample period (uniform: t[1] − t[0]; jittery: the median step)
/// and the blocks it has. std::invalid_argument when the blocks' shapes are wrong
/// (check_dataset_shape, store/encoding.h).
api::DatasetInfo describe_dataset(const std::string& owner, const std::string& name, const Trajectory& data,
                                  const std::string& source_job);
/// A robot as uploaded: name, base, tip, joints and summary.
api::RobotInfo describe_robot(const NewRobot& robot);
/// A queued job of `job`.
api::JobInfo describe_job(const NewJob& job);

}  // namespace manipid::server::store
