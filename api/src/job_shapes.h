// job_shapes.h — internal to api/: the shape of each kind's job (job_memory.h), defined in job_memory.cpp
// beside the measured figures they use, and held by the kinds' table (job_kinds.cpp).
#pragma once

#include "manipid/api/job_memory.h"

#include <nlohmann/json.hpp>

namespace manipid::api::shapes {

JobShape simulation(const nlohmann::json& request, const DatasetLookup& datasets, const RobotJointsLookup& robots);
JobShape preset_identification(const nlohmann::json& request, const DatasetLookup& datasets,
                               const RobotJointsLookup& robots);
JobShape robot_identification(const nlohmann::json& request, const DatasetLookup& datasets,
                              const RobotJointsLookup& robots);
JobShape payload_identification(const nlohmann::json& request, const DatasetLookup& datasets,
                                const RobotJointsLookup& robots);
JobShape excitation(const nlohmann::json& request, const DatasetLookup& datasets, const RobotJointsLookup& robots);

}  // namespace manipid::api::shapes
