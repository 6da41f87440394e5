// payload_json.h — a payload identification as JSON: the object `manipid payload --json` prints.
//
// Shape (numbers that do not exist are null, never NaN):
//   { "method": "payload from the arm's residual torque (linear least squares)",
//     "robot": {"name", "tip_link"},
//     "arm": "the URDF's values" | "an identification (its point)",
//     "detected": true,                      the mass exceeds two standard errors (or was given)
//     "mass": kg, "mass_std_error": kg,
//     "centre_of_mass": [x, y, z] m, tip-link frame, "centre_of_mass_std_errors": [...],
//     "inertia_about_com": {"ixx", "ixy", "ixz", "iyy", "iyz", "izz"} kg m², tip-link axes (URDF entries),
//     "inertia_std_errors": {...},
//     "parameters": [{"name": "m" | "mx" | ... | "Izz", "estimate", "std_error", "data_share"}]  about the tip
//                   link's origin, the form the torque is linear in,
//     "undetermined": [names],  "variance_inflation",
//     "given": {"mass": kg | null, "centre_of_mass": [...] | null},
//     "filters": {"comparison_cutoff_hz", "chosen_by_held_out", "held_out_error" (null when given),
//                 "candidates": [{"comparison_cutoff_hz", "held_out_error"}]}, "judge": {"lowpass", "cutoff_hz", "trim_seconds"},
//     "torque_joints": [joint names], "weights": "unit" | "per-joint", "joint_weights": [per fitted joint], "rows",
//     "fit": {"arm_only_error", "with_payload_error"}   ‖L r‖/‖L τ‖ on the training rows,
//     "consistent": the estimate is a real rigid body, "consistency_findings": [why not],
//     "physical": null (not asked, or no payload) | {"least_squares_consistent", "least_squares_findings",
//                 "relative_cost_increase", "report"}  the physical fit (PayloadOptions::physical),
//     "validation": {"arm_only": {"relative_error", "rms_error", "overall_relative_error"},
//                    "with_payload": {...}}  (if any),
//     "warnings": [...], "wall_seconds" }
#pragma once

#include "manipid/core/robot/model.h"
#include "manipid/core/robot/payload.h"

#include <nlohmann/json.hpp>

#include <optional>
#include <string>

namespace manipid::api {

nlohmann::ordered_json payload_to_json(const robot::Model& model, const robot::PayloadResult& result,
                                       const robot::PayloadOptions& options, const std::string& arm_source,
                                       const std::optional<robot::PayloadValidation>& validation);

}  // namespace manipid::api
