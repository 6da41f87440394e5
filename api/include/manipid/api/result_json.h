// result_json.h — identification results as JSON: the object `manipid identify --json`
// prints and the service returns as a job's `result`.
//
// Shape (every parameter by name; numbers that do not exist — the estimate of a parameter the
// data cannot determine alone, the standard error of a fixed or unidentifiable one — are
// null, never NaN):
//   { "method", "algorithm",
//     "estimates": {"m1": null, "m2": 25.0003, ...}, "std_errors": {"m1": null, "m2": 5e-6, ...},
//     "point": {"m1": 50.08, ...}  (where the minimiser stopped, every parameter: what the model
//              was evaluated at, e.g. for the torque fit; unidentifiable entries are one
//              arbitrary point of a valley the data cannot tell apart, not estimates),
//     "initial": {...}, "free": ["m1", ...],
//     "correlation": {"parameters": [...], "matrix": [[...]]},
//     "identifiability": {"all_identifiable", "unidentifiable": [...],
//                         "combinations": [{"name", "value", "std_error"}], "findings": [...],
//                         "singular_values": [...]},
//     "initial_cost", "final_cost", "evaluations", "simulations", "refinement_steps",
//     "wall_seconds", "stop_reason", "cancelled",
//     "filter": {"half_length", "band", "dt", "automatic"}, "torque_source",
//     "gains": {"source": "none"|"given"|"estimated"|"assumed", "kp": [...]|null, "kd": [...]|null,
//               "estimated": {"kp", "kd", "relative_residual": [...]} | null},
//     "residual_check": {"residual_rms", "noise_rms"} (the final residual's RMS and what the data's
//               measurement noise would leave; far above it, the residual is the method's bias and
//               the standard errors understate the error),
//     "warnings": [...],
//     "truth": {"m2": 25, ...} | null }
// "truth" holds the true values where they are known — a simulation's own parameters, or values
// the user gave (`--truth`, the request's "truth") — and is null otherwise: an uploaded file says
// nothing of the robot it came from, so no preset's values are shown beside its estimates.
#pragma once

#include "manipid/core/paper/identification.h"

#include <nlohmann/json.hpp>

#include <vector>

namespace manipid::api {

/// `truth`: empty when unknown, else 2n entries in θ order with NaN for a value not given.
nlohmann::ordered_json result_to_json(const IdentificationResult& result, const Eigen::VectorXd& truth = {});
/// The known entries of `truth` by name ({"m2": 25, ...}), or null when none is known.
nlohmann::ordered_json truth_to_json(const std::vector<std::string>& names, const Eigen::VectorXd& truth);
/// History records as {"index", "cost", "parameters": {"m1": ...}} objects.
nlohmann::ordered_json history_to_json(const std::vector<HistoryRecord>& history, const std::vector<std::string>& names);

}  // namespace manipid::api
