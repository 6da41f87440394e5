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
//     "filter": {"half_length", "band", "dt", "automatic"}, "torque_source", "warnings": [...] }
#pragma once

#include "manipid/core/identification.h"

#include <nlohmann/json.hpp>

#include <vector>

namespace manipid::api {

nlohmann::ordered_json result_to_json(const IdentificationResult& result);
/// History records as {"index", "cost", "parameters": {"m1": ...}} objects.
nlohmann::ordered_json history_to_json(const std::vector<HistoryRecord>& history, const std::vector<std::string>& names);

}  // namespace manipid::api
