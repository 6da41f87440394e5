// columns.h — the columns every store backend reads whole job, dataset and robot records with, in
// the order its read_job / read_dataset / read_robot expect (the two schemas name them alike).
#pragma once

#include <string>

namespace manipid::server::store {

/// Whole job records; seq last (it orders lists and is their page tokens' position).
inline const std::string kJobColumns =
    "id, kind, state, created_at, started_at, finished_at, request, dataset_id, evaluations, best_cost, "
    "cancel_requested, attempts, result, error, robot_id, validation_dataset_id, worker, owner, seq";
inline constexpr int kJobOwnerColumn = 17;
inline constexpr int kJobSeqColumn = 18;
/// Only a dataset's description: its samples are not read. seq last.
inline const std::string kDatasetColumns =
    "id, name, created_at, source_job, joints, samples, dt, has_torque, has_reference, uniform, has_rates, "
    "has_accelerations, owner, seq";
inline constexpr int kDatasetOwnerColumn = 12;
inline constexpr int kDatasetSeqColumn = 13;
/// Only a robot's description: its URDF document is not read. seq last.
inline const std::string kRobotColumns = "id, name, created_at, base, tip, joints, summary, owner, seq";
inline constexpr int kRobotOwnerColumn = 7;
inline constexpr int kRobotSeqColumn = 8;

}  // namespace manipid::server::store
